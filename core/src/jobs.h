// Jobs: how a scene of many geometries answers a query kind in one pass. Each job is one
// geometry's query elements against one geometry's tree: itself (a self job, run by the
// one-mesh scene's query source) or another of the same world whose group and mask allow the
// pair (a cross job, run by a cross source, cross_queries.h). A JobPass runs all of a call's jobs
// as one list of queries, so the backends run them in one parallel loop or one kernel launch as
// they run any pass (executor.h), and each job adds its geometries' first global ids to its pairs.
#pragma once

#include <algorithm>
#include <type_traits>
#include <vector>

#include "executor.h"
#include "minkq/cross_queries.h"

namespace minkq {

// An emitter (leaf_filter.h) that adds the jobs' global id offsets to each pair, and for a
// symmetric kind whose query geometry numbers after the tree's, swaps it into (lower, higher).
template <class Emit>
struct OffsetEmit {
  static constexpr bool kCountsOnly = counts_only<Emit>;
  Emit& emit;
  int32_t first_offset, second_offset;
  bool swap;
  MINKQ_HD void operator()(int32_t first, int32_t second) {
    first += first_offset;
    second += second_offset;
    if (swap) emit(second, first); else emit(first, second);
  }
  MINKQ_HD void add(unsigned n) { emit.add(n); }
};

// No reversed cross jobs (EE, VV: the smaller side queries already).
struct NoReversed {};

// One job: queries first_query .. first_query + num_queries - 1 of its pass, against bvh, by the
// self source, the cross source or the reversed cross source (VT, EV: cross_queries.h's
// CrossPrimVertexQueries, run with the box as its node test and the pass's shape at its leaves).
// Its sources hold no radius and only the geometry's own filters (a self job's incidence rule):
// the pass supplies the query's (with_request), so that a table of jobs serves every query of its
// kind while the geometries keep their arrays (MeshStoreOn's job tables).
template <class SelfQueries, class CrossQueries, class ReversedQueries = NoReversed>
struct GeometryJob {
  using Reversed = ReversedQueries;
  int32_t first_query, num_queries;
  bool self;
  bool reversed;
  bool swap;  // OffsetEmit's
  int32_t first_offset, second_offset;
  BvhView bvh;
  SelfQueries self_queries;
  CrossQueries cross_queries;
  ReversedQueries reversed_queries;
};

// A job's source with the query's radius and filters.
template <class Source>
MINKQ_HD Source with_request(Source source, float r, uint32_t filters) {
  source.r = r;
  source.filters |= filters;
  return source;
}

// The source a reversed job runs with the pass's shape.
template <class Shape, class Prim>
MINKQ_HD ReversedVertexPrimQueries<Prim, Shape> reversed_source(const CrossPrimVertexQueries<Prim>& q) {
  return {q};
}

// The jobs of each kind.
using VertexTriangleJob = GeometryJob<VertexTriangleQueries, CrossVertexTriangleQueries, CrossPrimVertexQueries<Triangle>>;
using VertexEdgeJob = GeometryJob<VertexEdgeQueries, CrossVertexEdgeQueries, CrossPrimVertexQueries<Edge>>;
using EdgeEdgeJob = GeometryJob<EdgeEdgeQueries, CrossEdgeEdgeQueries>;
using VertexVertexJob = GeometryJob<VertexVertexQueries, CrossVertexVertexQueries>;

// A pass over jobs (executor memory, in order of first_query, none empty): query i runs in the
// job whose range holds it, found by binary search.
template <class Shape_, class Job>
struct JobPass {
  using Shape = Shape_;
  QueryKind kind;
  const Job* jobs;
  int32_t num_jobs;
  int32_t num_queries;  // all the jobs' together
  int32_t first_bound;  // the pairs' first ids lie below it
  PairOutput out;
  float r;           // the query's radius and filters (kLeafExact), given to each job's source
  uint32_t filters;
  template <class Emit, class Work>
  MINKQ_HD void run(int32_t i, Emit& emit, Work& work) const {
    in_job(job_of(i), i, emit, [&](auto shape, const BvhView& bvh, const auto& queries, int32_t q, auto& job_emit) {
      run_query<decltype(shape)>(bvh, queries, q, job_emit, work);
    });
  }
#if !defined(__CUDACC__)
  // Queries i .. i + count - 1 walked together (packet.h): a packet per job they fall in.
  template <class Emit>
  void run_packet(int32_t i, int count, Emit& emit) const {
    for (const int32_t end = i + count; i < end;) {
      const int32_t k = job_of(i);
      const int here = int(std::min(end, jobs[k].first_query + jobs[k].num_queries) - i);
      in_job(k, i, emit, [&](auto shape, const BvhView& bvh, const auto& queries, int32_t q, auto& job_emit) {
        minkq::run_packet<decltype(shape)>(bvh, queries, q, here, job_emit);
      });
      i += here;
    }
  }
#endif
  MINKQ_HD int32_t first_ids() const { return first_bound; }

 private:
  // The job whose range holds query i (binary search).
  MINKQ_HD int32_t job_of(int32_t i) const {
    int32_t lo = 0, hi = num_jobs - 1;
    while (lo < hi) {
      const int32_t mid = (lo + hi + 1) / 2;
      if (jobs[mid].first_query <= i) lo = mid; else hi = mid - 1;
    }
    return lo;
  }
  // run(shape, bvh, queries, q, job_emit) for query i of job k: the job's tree, its source with
  // the request's radius and filters, i's number in the job and an emitter numbering the job's
  // pairs globally; `shape` is a value of the node test's type (a reversed job's: the box test).
  template <class Emit, class Run>
  MINKQ_HD void in_job(int32_t k, int32_t i, Emit& emit, Run&& run) const {
    const Job& job = jobs[k];
    OffsetEmit<Emit> offset_emit{emit, job.first_offset, job.second_offset, job.swap};
    const int32_t q = i - job.first_query;
    if constexpr (!std::is_same<typename Job::Reversed, NoReversed>::value) {
      if (job.reversed)
        return run(BoxShape{}, job.bvh, reversed_source<Shape>(with_request(job.reversed_queries, r, filters)), q,
                   offset_emit);
    }
    if (job.self) run(Shape{}, job.bvh, with_request(job.self_queries, r, filters), q, offset_emit);
    else run(Shape{}, job.bvh, with_request(job.cross_queries, r, filters), q, offset_emit);
  }
};

// What a geometry brings to the planning of jobs: its role and element counts.
struct GeometryShape {
  GeometryRole role;
  int32_t vertices, triangles, edges;
};

// One job of a kind, before it has a tree: geometry `query`'s elements against geometry `tree`'s;
// reversed (VT, EV across geometries): walked from the tree geometry's primitives into the query
// geometry's vertex tree, which it then needs.
struct JobPlan {
  int32_t query, tree;
  bool reversed = false;
};

// Whether geometries a != b are tested against each other: they share a world (or either is in
// every world) and each one's group has a bit in the other's mask.
inline bool may_pair(const GeometryRole& a, const GeometryRole& b) {
  const bool same_world = a.world == b.world || a.world < 0 || b.world < 0;
  return same_world && (a.group & b.mask) != 0 && (b.group & a.mask) != 0;
}

// The jobs of a kind, in order of (query, tree): a self job for each geometry with `self`, and
// for each pair of geometries that may_pair allows, both taking part in the kind: both directions
// for VT and EV (each side's vertices against the other's triangles or edges), one for EE and VV,
// queried from the geometry with fewer query elements (ties: the first). Jobs with no query or no
// tree element are left out. The pairs come from the worlds one at a time (each against itself and
// against the geometries of every world), so geometries of different worlds are never compared.
inline std::vector<JobPlan> plan_jobs(const std::vector<GeometryShape>& geometries, QueryKind kind) {
  const bool vertex_queries = kind != QueryKind::kEdgeEdge;
  const bool symmetric = kind == QueryKind::kEdgeEdge || kind == QueryKind::kVertexVertex;
  auto queries = [&](int32_t g) { return vertex_queries ? geometries[g].vertices : geometries[g].edges; };
  auto tree_elements = [&](int32_t g) {
    switch (kind) {
      case QueryKind::kVertexTriangle: return geometries[g].triangles;
      case QueryKind::kVertexVertex: return geometries[g].vertices;
      default: return geometries[g].edges;
    }
  };
  auto takes_part = [&](int32_t g) { return (geometries[g].role.kinds & kind_bit(kind)) != 0; };
  std::vector<JobPlan> plans;
  // A VT or EV job walks from the side with fewer elements: the vertices of `q` into the tree of
  // `t`, or reversed, the primitives of `t` into the vertex tree of `q`.
  auto add = [&](int32_t q, int32_t t) {
    if (queries(q) > 0 && tree_elements(t) > 0)
      plans.push_back({q, t, q != t && !symmetric && tree_elements(t) < queries(q)});
  };
  auto add_cross = [&](int32_t a, int32_t b) {
    if (!takes_part(a) || !takes_part(b) || !may_pair(geometries[a].role, geometries[b].role)) return;
    if (!symmetric) {
      add(a, b);
      add(b, a);
    } else if (queries(b) < queries(a)) {
      add(b, a);
    } else {
      add(a, b);
    }
  };
  const int32_t n = int32_t(geometries.size());
  for (int32_t g = 0; g < n; ++g)
    if (takes_part(g) && geometries[g].role.self) add(g, g);
  // Worlds: geometries grouped by world id, those of every world (-1) apart.
  std::vector<int32_t> order(size_t(n), 0), every;
  for (int32_t g = 0; g < n; ++g) order[size_t(g)] = g;
  std::stable_sort(order.begin(), order.end(),
                   [&](int32_t a, int32_t b) { return geometries[a].role.world < geometries[b].role.world; });
  for (int32_t g : order)
    if (geometries[g].role.world < 0) every.push_back(g);
  for (size_t i = every.size(); i < order.size();) {
    size_t end = i;
    while (end < order.size() && geometries[order[end]].role.world == geometries[order[i]].role.world) ++end;
    for (size_t a = i; a < end; ++a)
      for (size_t b = a + 1; b < end; ++b) add_cross(std::min(order[a], order[b]), std::max(order[a], order[b]));
    i = end;
  }
  for (size_t a = 0; a < every.size(); ++a)
    for (int32_t g = 0; g < n; ++g)
      if (g != every[a] && (geometries[g].role.world >= 0 || g > every[a])) add_cross(std::min(every[a], g), std::max(every[a], g));
  std::sort(plans.begin(), plans.end(),
            [](const JobPlan& a, const JobPlan& b) { return a.query != b.query ? a.query < b.query : a.tree < b.tree; });
  return plans;
}

}  // namespace minkq
