// The traversal, written once for every query shape and both backends: a query walks the
// tree (bvh.h) top-down with a small stack, tests child boxes with the shape's box test and
// scans leaf ranges four boxes at a time with the shape's leaf test (shapes.h states the
// contract a shape fulfils), handing each group's hits to the leaf filter at once; a
// self-query walks only the half after its own leaf. Work is counted when asked for and
// compiled out when not.
#pragma once

#include "minkq/bvh.h"
#include "minkq/shapes.h"

namespace minkq {

// ---- Traversal ---------------------------------------------------------------------------------

// Work of a traversal, counted when asked for (WorkCounts) and compiled out when not (NoWork).
// The counts depend only on the tree and the queries, so they are equal on every backend.
struct WorkCounts {
  uint64_t nodes_visited = 0;    // internal node records read
  uint64_t node_tests = 0;       // child boxes tested against the query shape
  uint64_t primitive_tests = 0;  // primitives whose box passed, handed to the leaf filter
  uint64_t candidates = 0;       // pairs emitted
  MINKQ_HD void visit_node() { ++nodes_visited; }
  MINKQ_HD void test_node() { ++node_tests; }
  MINKQ_HD void test_nodes(unsigned n) { node_tests += n; }
  MINKQ_HD void test_primitives(unsigned n) { primitive_tests += n; }
  MINKQ_HD void emit_candidate() { ++candidates; }
  MINKQ_HD void emit_candidates(unsigned n) { candidates += n; }
  MINKQ_HD void add(const WorkCounts& o) {
    nodes_visited += o.nodes_visited;
    node_tests += o.node_tests;
    primitive_tests += o.primitive_tests;
    candidates += o.candidates;
  }
};
struct NoWork {
  MINKQ_HD void visit_node() {}
  MINKQ_HD void test_node() {}
  MINKQ_HD void test_nodes(unsigned) {}
  MINKQ_HD void test_primitives(unsigned) {}
  MINKQ_HD void emit_candidate() {}
  MINKQ_HD void emit_candidates(unsigned) {}
};

// The members a work type has (WorkCounts' and NoWork's), checked where one is used (walk,
// traverse_groups).
namespace work_contract {
template <class W>
using VisitNode = decltype(std::declval<W&>().visit_node());
template <class W>
using TestNode = decltype(std::declval<W&>().test_node());
template <class W>
using TestNodes = decltype(std::declval<W&>().test_nodes(0u));
template <class W>
using TestPrimitives = decltype(std::declval<W&>().test_primitives(0u));
template <class W>
using EmitCandidate = decltype(std::declval<W&>().emit_candidate());
template <class W>
using EmitCandidates = decltype(std::declval<W&>().emit_candidates(0u));
}  // namespace work_contract

template <class W>
constexpr bool is_work = is_detected<work_contract::VisitNode, W> && is_detected<work_contract::TestNode, W> &&
                         is_detected<work_contract::TestNodes, W> && is_detected<work_contract::TestPrimitives, W> &&
                         is_detected<work_contract::EmitCandidate, W> && is_detected<work_contract::EmitCandidates, W>;

// Instantiated where a work type is used: one message for each member W lacks.
template <class W>
struct WorkContract {
  static_assert(is_detected<work_contract::VisitNode, W>, "Work: needs visit_node()");
  static_assert(is_detected<work_contract::TestNode, W>, "Work: needs test_node()");
  static_assert(is_detected<work_contract::TestNodes, W>, "Work: needs test_nodes(unsigned)");
  static_assert(is_detected<work_contract::TestPrimitives, W>, "Work: needs test_primitives(unsigned)");
  static_assert(is_detected<work_contract::EmitCandidate, W>, "Work: needs emit_candidate()");
  static_assert(is_detected<work_contract::EmitCandidates, W>, "Work: needs emit_candidates(unsigned)");
  static constexpr bool value = is_work<W>;
};

// Leaf positions max(first, after + 1)..last, a group of four at a time: on_hits(base, hits,
// group) for each group whose boxes pass overlaps in some lane (four at once: overlaps_group,
// through group_test), hits holding bit k for position base + k. Only the first and the last
// group of the range ask for fewer than four lanes.
template <class Shape, class OnHits, class Work>
MINKQ_HD void scan_leaves(const BoxGroup* leaf_groups, const Shape& shape, int32_t first, int32_t last, int32_t after,
                          OnHits& on_hits, Work& work) {
  const int64_t start = first > after ? first : int64_t(after) + 1;
  if (start > last) return;
  const auto& test = group_test(shape);
  const int64_t last_base = int64_t(last) & ~int64_t(3);
  int64_t base = start & ~int64_t(3);
  unsigned lanes = (0xfu << (start - base)) & 0xfu;
  for (;; base += 4, lanes = 0xfu) {
    if (base == last_base) lanes &= 0xfu >> (3 - (last - base));
    const BoxGroup& group = leaf_groups[base >> 2];
    const unsigned hits = test.overlaps_group(group, lanes);
    work.test_nodes(unsigned(popcount(lanes)));
    if (hits != 0) on_hits(base, hits, group);
    if (base == last_base) return;
  }
}

// A leaf range whose box passed may_overlap. One leaf: its box is the range's and passed the
// box test; only the finer one is left.
template <class Shape, class OnHits, class Work>
MINKQ_HD void visit_leaf_range(const BoxGroup* leaf_groups, const Shape& shape, int32_t first, int32_t last,
                               int32_t after, const Box& range_box, OnHits& on_hits, Work& work) {
  if (first == last) {
    if (shape.finer(range_box)) on_hits(int64_t(first) & ~int64_t(3), 1u << (first & 3), leaf_groups[first >> 2]);
    return;
  }
  scan_leaves(leaf_groups, shape, first, last, after, on_hits, work);
}

// The one walk of the tree, for every query shape and both backends: on_range(first, last,
// box, own) is called, in the order met, for every leaf range [first, last] that the shape may
// overlap (may_overlap passes its box and the box of every node above it, but for a
// self-query's path, below). Only leaf ranges holding positions after `after` are reached: a
// self-query from the leaf at position i passes i; other queries pass -1. A node is entered
// only when its last position is past `after` (the root: n - 1 > after), so only a left child
// (last = split) is ever skipped for that. own: the range holds position `after` itself, so
// only its positions after `after` count.
//
// A self-query walks the half of the tree after its own leaf (a half traversal, as ArborX's
// HalfTraversal does by climbing from the leaf): every node on the path from the root to the
// leaf range holding position `after` holds the query's own box, which the shape overlaps, so
// the path is followed down the splits with no box test, while the children beside it are
// tested as in any walk. The ranges, and the order they are met in, are those of the plain
// top-down walk with the path's always-true tests left out (and were a path test false, no box
// below it could hold a pair: the pairs would still be the same).
template <class Shape, class OnRange, class Work>
MINKQ_HD void walk(const BvhView& bvh, const Shape& shape, int32_t after, OnRange& on_range, Work& work) {
  // The walk alone tests only node boxes; traverse_groups checks the whole contract.
  static_assert(shape_contract::kMayOverlap<Shape>, "Shape: needs bool may_overlap(const Box&) const");
  static_assert(WorkContract<Work>::value, "the work type does not fulfil the Work contract");
  if (bvh.num_prims <= 0 || after >= bvh.num_prims - 1) return;
  int32_t stack[kTraversalStack];
  int sp = 0;
  int32_t node = 0;
  bool on_path = after >= 0;  // node's range holds `after` (the root's does)
  while (true) {
    const BvhNode& n = bvh.nodes[node];
    work.visit_node();
    int32_t next = -1;
    // The child holding `after` and leaves past it (a left child ending at `after` is skipped).
    const bool left_on_path = on_path && after < n.split, right_on_path = on_path && after > n.split;
    if (n.split > after) {
      if (!left_on_path) work.test_node();
      if (left_on_path || shape.may_overlap(n.left_box)) {
        if (n.left < 0) on_range(~n.left, n.split, n.left_box, left_on_path); else next = n.left;
      }
    }
    if (n.right != kNoChild) {
      if (!right_on_path) work.test_node();
      if (right_on_path || shape.may_overlap(n.right_box)) {
        if (n.right < 0) {
          on_range(n.split + 1, ~n.right, n.right_box, right_on_path);
        } else if (next < 0) {
          next = n.right;
        } else {
          stack[sp++] = n.right;
        }
      }
    }
    // Still on the path when going on into the child that holds `after` (always `next` then).
    on_path = (left_on_path && n.left >= 0) || (right_on_path && n.right >= 0);
    if (next >= 0) { node = next; continue; }
    if (sp == 0) return;
    node = stack[--sp];
  }
}

// The traversal: on_hits(base, hits, group) is called for the leaf groups holding primitives at
// sorted positions after `after` whose box the shape overlaps (the contract at the top of
// shapes.h makes that exact: may_overlap accepts every ancestor box of such a box), bit k of
// hits for position base + k; a self-query thus meets each pair once. The leaf filter
// (leaf_filter.h) takes a group's hits at once.
template <class Shape, class OnHits, class Work>
MINKQ_HD void traverse_groups(const BvhView& bvh, const Shape& shape, int32_t after, OnHits& on_hits, Work& work) {
  static_assert(ShapeContract<Shape>::value, "the query shape does not fulfil the Shape contract (shapes.h)");
  static_assert(WorkContract<Work>::value, "the work type does not fulfil the Work contract");
  auto on_range = [&](int32_t first, int32_t last, const Box& range_box, bool) {
    visit_leaf_range(bvh.leaf_groups, shape, first, last, after, range_box, on_hits, work);
  };
  walk(bvh, shape, after, on_range, work);
}

// The same, primitive by primitive: on_leaf(prim, box) for each, in the order met.
template <class Shape, class OnLeaf, class Work>
MINKQ_HD void traverse(const BvhView& bvh, const Shape& shape, int32_t after, OnLeaf& on_leaf, Work& work) {
  auto on_hits = [&](int64_t base, unsigned hits, const BoxGroup& group) {
    for (; hits != 0; hits &= hits - 1u) {
      const int k = lowest_bit(hits);
      on_leaf(bvh.sorted_prims[base + k], group_box(group, k));
    }
  };
  traverse_groups(bvh, shape, after, on_hits, work);
}

}  // namespace minkq
