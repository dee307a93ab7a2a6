// The leaf filter: what a query does with a leaf group's hits (drop the incident ones, run the
// source's other tests, emit the source's pairs), and run_query, which ties a query source
// (query_sources.h) to a shape and to the one traversal (traversal.h). Backends call it per
// query and supply only emit(first, second).
#pragma once

#include <utility>

#include "minkq/query_sources.h"
#include "minkq/traversal.h"

namespace minkq {

// Whether an emitter only counts pairs (a static kCountsOnly member and add(n)): the leaf
// filter then adds a group's candidates at once instead of emitting them one by one.
template <class Emit>
using CountsOnly = std::integral_constant<bool, Emit::kCountsOnly>;
template <class Emit>
constexpr bool counts_only = flag_set<CountsOnly, Emit>;

// An emitter: emit(first, second) for each pair, and for a count-only one add(n) as well (a
// count-only emitter still takes the pairs one by one where the source tests them). Checked
// where one is used (run_query).
namespace emit_contract {
template <class E>
using Call = decltype(std::declval<E&>()(int32_t(), int32_t()));
template <class E>
using Add = decltype(std::declval<E&>().add(0u));
}  // namespace emit_contract
template <class E>
constexpr bool is_emitter = is_detected<emit_contract::Call, E> && (!counts_only<E> || is_detected<emit_contract::Add, E>);
template <class E>
struct EmitContract {
  static_assert(is_detected<emit_contract::Call, E>, "emitter: needs operator()(int32_t first, int32_t second)");
  static_assert(!counts_only<E> || is_detected<emit_contract::Add, E>, "count-only emitter: needs add(unsigned n)");
  static constexpr bool value = is_emitter<E>;
};

// The count-only emitter both backends use: the number of pairs a query (or a run of queries)
// finds, each leaf group's accepted lanes added as one popcount where the source has no tests
// past the incidence filter. A backend adds `counted` to its total once per thread.
struct PairCounter {
  static constexpr bool kCountsOnly = true;
  uint64_t counted = 0;
  MINKQ_HD void operator()(int32_t, int32_t) { ++counted; }
  MINKQ_HD void add(unsigned n) { counted += n; }
};

// The leaf filter of a query target (element q; a self-query's at leaf position `after`), a leaf
// group's hits at a time (positions base + k for the bits k of hits, each a primitive whose box
// the shape overlaps): each is counted, the incidence filter drops lanes (dropped_lanes, four at
// once), the source's other tests (accept_rest, told the leaf position) keep or drop the rest
// one by one where it has any, and each kept one is emitted as the source's pair. The sources
// read a query's element and the primitives by leaf position (testing/by_id_queries.h states
// the same verdict for one pair, by id).
template <class Shape, class Queries, class Emit, class Work>
struct LeafFilter {
  const Queries& queries;
  const int32_t* sorted_prims;
  QueryTarget target;
  Emit& emit;
  Work& work;
  MINKQ_HD void operator()(int64_t base, unsigned hits, const BoxGroup& /*group*/) const {
    work.test_primitives(unsigned(popcount(hits)));
    hits &= ~queries.dropped_lanes(target, base, hits);
    const bool rest = queries.template tests_rest<Shape>();
    if constexpr (counts_only<Emit>) {
      if (!rest) {
        work.emit_candidates(unsigned(popcount(hits)));
        emit.add(unsigned(popcount(hits)));
        return;
      }
    }
    for (; hits != 0; hits &= hits - 1u) {
      const int k = lowest_bit(hits);
      const int32_t prim = sorted_prims[base + k];
      if (rest && !queries.template accept_rest<Shape>(target, prim, base + k)) continue;
      work.emit_candidate();
      const Pair pair = queries.pair(target.q, prim);
      emit(pair.first, pair.second);
    }
  }
};

// Query i of the batch: emit(first, second) for each pair it finds; work counts (or not).
template <class Shape, class Queries, class Emit, class Work>
MINKQ_HD void run_query(const BvhView& bvh, const Queries& queries, int32_t i, Emit& emit, Work& work) {
  static_assert(QuerySourceContract<Queries, Shape>::value, "not a query source (query_sources.h)");
  static_assert(EmitContract<Emit>::value, "not an emitter");
  const QueryTarget target = queries.target(i);
  const Shape shape = Shape::from(queries.geometry(target));
  LeafFilter<Shape, Queries, Emit, Work> on_hits{queries, bvh.sorted_prims, target, emit, work};
  traverse_groups(bvh, shape, target.after, on_hits, work);
}

}  // namespace minkq
