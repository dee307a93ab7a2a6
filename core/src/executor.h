// The executor: what differs between the CPU and the CUDA backend, supplied to the scene stores
// (store.h) as their template argument X. cpu/backend.cpp and cuda/backend.cu define one each.
//
//   X::Device                      what the executor is constructed from (CUDA: the ordinal).
//   X::Array<T>                    an owning array in the executor's memory, with data().
//   X::Tree                        the backend's tree: build(boxes, n), refit(boxes),
//                                  area_cost(), cost_at_build(), view().
//   scope()                        an object held for the duration of each call (CUDA: the
//                                  device made current, and the caller's given back after).
//   hold() / release()             the same across construction; hold_for_teardown() (which
//                                  cannot fail) before the members are destroyed.
//   finish()                       completes the call's work and reports its errors.
//   gather(values, Array<T>&)      packs strided Vec3 or Box records (host or, on CUDA, device
//                                  memory) into an array.
//   gather_float64(values, Array<Vec3>&, Array<float>& rho, accumulate)
//                                  the same from float64 vertices, rounded to nearest, with
//                                  rho[0] the farthest the rounding moved one (float64.h), or
//                                  the larger of that and rho[0] as it was (accumulate).
//   upload(Array<T>&, vector<T>)   takes host topology over.
//   download(T* host, Array<T>, n) copies n records to the host.
//   sort_by_morton(boxes, n, Array<int32_t>& ids)
//                                  ids 0..n-1 in the Morton order of the boxes' centres.
//   fill_groups(prims, sorted_prims, n, Array<LeafGroup<Prim>>& out)
//                                  the n elements (by id) in a tree's leaf order (leaf_groups.h's
//                                  LeafGroup, fill_leaf_group), sized for them.
//   scatter_groups(groups, sorted_prims, n, Array<Prim>& out)
//                                  the inverse: the elements by id, sized for them.
//   run_passes<Work>(works, passes...)
//                                  runs the QueryPasses of one call (one parallel loop, or one
//                                  kernel launch) and returns each pass's exact pair count,
//                                  its pairs written, and sorted when asked, where they fit;
//                                  for outputs with a count pointer (asynchronous queries) the
//                                  count goes there, pairs up to the capacity, nothing is read
//                                  back and the returned counts are not used.
//
// and for the asynchronous calls (backend.h's MeshStore section):
//   scope_on(stream)               the scope of an asynchronous call: on CUDA the caller's
//                                  stream, with allocation and host copies refused.
//   wait(stream)                   waits for the stream's work (CUDA).
//   reserve_staging(Array<Vec3>&, n), reserve_pending(), reserve_canonical(pairs),
//   reserve_build(Tree&, boxes, n), reserve_sort(boxes, n)
//                                  the scratch the asynchronous calls use, kept from then on.
//   reserve_nodes(Tree&, n)        the tree's node storage for every build over n elements,
//                                  never moved after (CUDA: captured graphs keep its address).
//   reserve_scratch(Array<T>&, n)  room for n elements kept in the array, so that filling it
//                                  with up to n allocates nothing (a rebuild's elements by id).
//   commit_finite(values, staging, dst, rho, call, first)
//                                  dst = values (executor memory) unless a coordinate is not
//                                  finite; then dst is kept and the pending error recorded,
//                                  naming vertex first + i (values: a slice of the caller's).
//                                  Float64 values also set *rho (rho: nullptr for float).
//   commit_finite_swept(x0, x1, staging0, staging1, dst0, dst1, rho, call, first)
//                                  the same for a swept step's two positions, checked
//                                  together: on a bad coordinate in either, dst0 is kept and
//                                  dst1 = dst0 (the scene at rest).
//   take_pending()                 the pending error (after wait()), cleared.
//
// ExecutorContract checks each of these is there, with the stores' argument types, where a store
// is instantiated (MeshStoreOn, BoxStoreOn).
#pragma once

#include <array>
#include <cstddef>
#include <utility>
#include <vector>

#include "backend.h"
#include "minkq/detect.h"
#include "minkq/leaf_filter.h"
#include "minkq/packet.h"

namespace minkq {

// The queries of one request for a pass: the request's kind, the tree, the query source and
// where the pairs go, with the node test as a type. A pass is what run_passes runs: queries
// 0..num_queries-1, query i by run(i, emit, work), whose pairs' first ids lie below first_ids()
// (the bits a canonical sort covers). jobs.h's JobPass is the other kind of pass.
template <class Shape_, class Queries>
struct QueryPass {
  using Shape = Shape_;
  QueryKind kind;
  BvhView bvh;
  Queries queries;
  int32_t num_queries;
  PairOutput out;
  template <class Emit, class Work>
  MINKQ_HD void run(int32_t i, Emit& emit, Work& work) const {
    run_query<Shape>(bvh, queries, i, emit, work);
  }
#if !defined(__CUDACC__)
  // Queries i .. i + count - 1 (count 1 to kPacket) walked together, without work counts.
  template <class Emit>
  void run_packet(int32_t i, int count, Emit& emit) const {
    minkq::run_packet<Shape>(bvh, queries, i, count, emit);
  }
#endif
  MINKQ_HD int32_t first_ids() const { return num_queries; }
};

namespace executor_contract {
template <class X, class T>
using Array = typename X::template Array<T>;
template <class X>
using Device = typename X::Device;
template <class X>
using ArrayData = decltype(std::declval<Array<X, Vec3>&>().data());
template <class X>
using Tree = typename X::Tree;
template <class X>
using TreeBuild = decltype(std::declval<Tree<X>&>().build(std::declval<GivenBoxes>(), int32_t()));
template <class X>
using TreeRefit = decltype(std::declval<Tree<X>&>().refit(std::declval<GivenBoxes>()));
template <class X>
using TreeAreaCost = decltype(std::declval<const Tree<X>&>().area_cost());
template <class X>
using TreeCostAtBuild = decltype(std::declval<const Tree<X>&>().cost_at_build());
template <class X>
using TreeView = decltype(std::declval<const Tree<X>&>().view());
template <class X>
using Scope = decltype(std::declval<X&>().scope());
template <class X>
using Hold = decltype(std::declval<X&>().hold(), std::declval<X&>().release(), std::declval<X&>().hold_for_teardown());
template <class X>
using Finish = decltype(std::declval<X&>().finish());
template <class X>
using Gather = decltype(std::declval<X&>().gather(std::declval<const Strided&>(), std::declval<Array<X, Vec3>&>()));
template <class X>
using GatherFloat64 = decltype(std::declval<X&>().gather_float64(
    std::declval<const Strided&>(), std::declval<Array<X, Vec3>&>(), std::declval<Array<X, float>&>(), bool()));
template <class X>
using Upload = decltype(std::declval<X&>().upload(std::declval<Array<X, Edge>&>(), std::declval<std::vector<Edge>>()));
template <class X>
using Download = decltype(std::declval<X&>().download(std::declval<Edge*>(), std::declval<const Array<X, Edge>&>(), size_t()));
template <class X>
using SortByMorton = decltype(std::declval<X&>().sort_by_morton(std::declval<PointBoxes>(), int32_t(),
                                                                 std::declval<Array<X, int32_t>&>()));
template <class X>
using FillGroups = decltype(std::declval<X&>().fill_groups(std::declval<const Edge*>(), std::declval<const int32_t*>(),
                                                           int32_t(), std::declval<Array<X, EdgeGroup>&>()));
template <class X>
using ScatterGroups = decltype(std::declval<X&>().scatter_groups(std::declval<const Array<X, EdgeGroup>&>(),
                                                                 std::declval<const int32_t*>(), int32_t(),
                                                                 std::declval<Array<X, Edge>&>()));
template <class X>
using RunPasses = decltype(std::declval<X&>().template run_passes<NoWork>(
    std::declval<const std::array<WorkCounts*, 1>&>(), std::declval<const QueryPass<BoxShape, UserQueries>&>()));
template <class X>
using ScopeOn = decltype(std::declval<X&>().scope_on(Stream()), std::declval<X&>().wait(Stream()));
template <class X>
using Reserve = decltype(std::declval<X&>().reserve_staging(std::declval<Array<X, Vec3>&>(), int32_t()),
                         std::declval<X&>().reserve_pending(), std::declval<X&>().reserve_canonical(size_t()),
                         std::declval<X&>().reserve_build(std::declval<Tree<X>&>(), std::declval<GivenBoxes>(), int32_t()),
                         std::declval<X&>().reserve_nodes(std::declval<Tree<X>&>(), int32_t()),
                         std::declval<X&>().reserve_sort(std::declval<PointBoxes>(), int32_t()),
                         std::declval<X&>().reserve_scratch(std::declval<Array<X, Edge>&>(), int32_t()));
template <class X>
using CommitFinite = decltype(std::declval<X&>().commit_finite(
    std::declval<const Strided&>(), std::declval<Array<X, Vec3>&>(), std::declval<Array<X, Vec3>&>(),
    std::declval<float*>(), PendingError::kRefit, int64_t()));
template <class X>
using CommitFiniteSwept = decltype(std::declval<X&>().commit_finite_swept(
    std::declval<const Strided&>(), std::declval<const Strided&>(), std::declval<Array<X, Vec3>&>(),
    std::declval<Array<X, Vec3>&>(), std::declval<Array<X, Vec3>&>(), std::declval<Array<X, Vec3>&>(),
    std::declval<float*>(), PendingError::kRefit, int64_t()));
template <class X>
using TakePending = decltype(std::declval<X&>().take_pending());
}  // namespace executor_contract

// Instantiated where a store is: a message for each member X lacks.
template <class X>
struct ExecutorContract {
  template <template <class> class Op>
  static constexpr bool has = is_detected<Op, X>;
  static_assert(has<executor_contract::Device>, "executor: needs a type Device, what it is constructed from");
  static_assert(has<executor_contract::ArrayData>, "executor: needs template <class T> Array<T>, an owning array with data()");
  static_assert(has<executor_contract::Tree>, "executor: needs a type Tree, the backend's tree");
  static_assert(has<executor_contract::TreeBuild>, "executor: Tree needs build(Boxes, int32_t n)");
  static_assert(has<executor_contract::TreeRefit>, "executor: Tree needs refit(Boxes)");
  static_assert(detected_as<double, executor_contract::TreeAreaCost, X> &&
                    detected_as<double, executor_contract::TreeCostAtBuild, X>,
                "executor: Tree needs double area_cost() const and double cost_at_build() const");
  static_assert(detected_as<BvhView, executor_contract::TreeView, X>, "executor: Tree needs BvhView view() const");
  static_assert(has<executor_contract::Scope>, "executor: needs scope(), held for the duration of each call");
  static_assert(has<executor_contract::Hold>, "executor: needs hold(), release() and hold_for_teardown()");
  static_assert(has<executor_contract::Finish>, "executor: needs finish()");
  static_assert(has<executor_contract::Gather> && has<executor_contract::GatherFloat64>,
                "executor: needs gather(values, Array<T>&) and gather_float64(values, Array<Vec3>&, Array<float>&, bool)");
  static_assert(has<executor_contract::Upload> && has<executor_contract::Download>,
                "executor: needs upload(Array<T>&, std::vector<T>&&) and download(T*, const Array<T>&, size_t)");
  static_assert(has<executor_contract::SortByMorton>, "executor: needs sort_by_morton(boxes, n, Array<int32_t>&)");
  static_assert(has<executor_contract::FillGroups> && has<executor_contract::ScatterGroups>,
                "executor: needs fill_groups(prims, sorted_prims, n, Array<LeafGroup<Prim>>&) and "
                "scatter_groups(groups, sorted_prims, n, Array<Prim>&)");
  static_assert(detected_as<std::array<uint64_t, 1>, executor_contract::RunPasses, X>,
                "executor: needs template <class Work, class... Pass> std::array<uint64_t, sizeof...(Pass)> "
                "run_passes(works, passes...)");
  static_assert(has<executor_contract::ScopeOn>, "executor: needs scope_on(Stream) and wait(Stream)");
  static_assert(has<executor_contract::Reserve>,
                "executor: needs reserve_staging, reserve_pending, reserve_canonical, reserve_build, "
                "reserve_nodes, reserve_sort and reserve_scratch");
  static_assert(has<executor_contract::CommitFinite> && has<executor_contract::CommitFiniteSwept>,
                "executor: needs commit_finite(values, staging, dst, rho, call) and "
                "commit_finite_swept(x0, x1, staging0, staging1, dst0, dst1, rho, call)");
  static_assert(detected_as<PendingError, executor_contract::TakePending, X>, "executor: needs PendingError take_pending()");
  static constexpr bool value = true;
};

}  // namespace minkq
