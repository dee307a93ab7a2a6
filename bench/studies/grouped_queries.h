// Queries run in groups, studied for issue 27 and not kept (bench/traversal_study.cpp,
// results/traversal.md): the self-queries of one leaf range (EE, VV), or a run of consecutive
// queries in Morton order (VT), share one walk of the tree with the box around all their
// boxes, then each takes the listed leaf ranges its own box test passes. It reads a fraction
// of the node records and meets the same pairs in the same order, but on the CPU the time
// moves far less than the node reads: the leaf scans and the pairs' filter take most of it.
// It would also make the work counters differ from the CUDA backend's per-query walk.
#pragma once

#include <algorithm>

#include "minkq/queries.h"

namespace minkq::bench {

// The box test behind a shape's may_overlap (the box mode is its own).
inline const BoxShape& box_test_of(const BoxShape& s) { return s; }
template <class Shape>
const BoxShape& box_test_of(const Shape& s) {
  return s.box_test();
}

// The leaf range [first, last] holding sorted position `pos` (0 <= pos < n), down the splits.
void leaf_range_of(const BvhView& bvh, int32_t pos, int32_t& first, int32_t& last) {
  first = 0, last = bvh.num_prims - 1;
  if (bvh.num_prims <= 1) return;
  for (int32_t node = 0;;) {
    const BvhNode& n = bvh.nodes[node];
    if (pos <= n.split) {
      last = n.split;
      if (n.left < 0) return;
      node = n.left;
    } else {
      first = n.split + 1;
      if (n.right < 0) return;
      node = n.right;
    }
  }
}

// ---- Queries by group ---------------------------------------------------------------------------
// Queries begin..end of a batch: either self-queries at sorted positions of one leaf range
// (EdgeEdgeQueries, VertexVertexQueries: query i at position i), which share the path to that
// range, or queries that pass after = -1 (VertexPrimQueries). Each reaches
// only leaf ranges whose box its shape may overlap. So one walk with the box around all their
// shapes' boxes (a box test every member's passes wherever its own does: the gap test is
// monotone) lists the leaf ranges any of them can reach, in the order met; each member then
// takes the listed ranges its own box test passes, in that order, and scans them as its own
// walk would. The pairs, and the order each query meets them in, are run_query's; the nodes are
// read once for the group instead of once per query. A list that outgrows kGroupRanges is
// dropped and the members walk one by one.
constexpr int kGroupRanges = 64;

struct RangeEntry {
  Box box;
  int32_t first, last;
  bool own;  // the members' own range: no box test, scanned after each member's position
};

template <class Shape, class Queries, class Emit, class Work>
void run_group(const BvhView& bvh, const Queries& queries, int32_t begin, int32_t end, Emit& emit, Work& work) {
  BoxShape group{{FLT_MAX, FLT_MAX, FLT_MAX}, {-FLT_MAX, -FLT_MAX, -FLT_MAX}, 0.0f};
  for (int32_t i = begin; i <= end; ++i) {
    const BoxShape b = box_test_of(Shape::from(queries.geometry(queries.target(i))));
    group.lo = vmin(group.lo, b.lo), group.hi = vmax(group.hi, b.hi), group.r = max_num(group.r, b.r);
  }
  RangeEntry ranges[kGroupRanges];
  int count = 0;
  bool overflow = false;
  auto collect = [&](int32_t first, int32_t last, const Box& box, bool own) {
    if (count == kGroupRanges) {
      overflow = true;
      return;
    }
    ranges[count++] = {box, first, last, own};
  };
  walk(bvh, group, queries.target(begin).after, collect, work);
  for (int32_t i = begin; i <= end; ++i) {
    if (overflow) {
      run_query<Shape>(bvh, queries, i, emit, work);
      continue;
    }
    const QueryTarget target = queries.target(i);
    const Shape shape = Shape::from(queries.geometry(target));
    LeafFilter<Shape, Queries, Emit, Work> on_leaf{queries, bvh.sorted_prims, target, emit, work};
    for (int k = 0; k < count; ++k) {
      const RangeEntry& e = ranges[k];
      if (!e.own) {
        work.test_node();
        if (!shape.may_overlap(e.box)) continue;
      }
      visit_leaf_range(bvh.leaf_groups, shape, e.first, e.last, target.after, e.box, on_leaf, work);
    }
  }
}

// Queries [begin, end) in groups: self-queries leaf range by leaf range, others kGroupQueries
// at a time.
constexpr int32_t kGroupQueries = 16;
template <class Shape, class Queries, class Emit, class Work>
void run_grouped(const BvhView& bvh, const Queries& queries, int32_t begin, int32_t end, Emit& emit, Work& work) {
  for (int32_t i = begin; i < end;) {
    int32_t stop = std::min(end, i + kGroupQueries) - 1;
    if (queries.target(i).after >= 0) {
      int32_t first, last;
      leaf_range_of(bvh, i, first, last);
      stop = std::min(last, end - 1);
    }
    run_group<Shape>(bvh, queries, i, stop, emit, work);
    i = stop + 1;
  }
}

}  // namespace minkq::bench
