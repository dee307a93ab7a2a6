// The traversal, written once for every query shape and both backends: a query walks the
// tree (tree.h) top-down with a small stack, tests child boxes with the shape's box test and
// scans leaf ranges four boxes at a time with the shape's leaf test (shapes.h states the
// contract a shape fulfils). Work is counted when asked for and compiled out when not.
#pragma once

#include "minkq/tree.h"

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
  MINKQ_HD void test_primitive() { ++primitive_tests; }
  MINKQ_HD void emit_candidate() { ++candidates; }
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
  MINKQ_HD void test_primitive() {}
  MINKQ_HD void emit_candidate() {}
};

// Leaf positions max(first, after + 1)..last, a group of four at a time: on_leaf(prim, box) for
// each whose box passes overlaps (four at once: overlaps_group).
template <class Shape, class OnLeaf, class Work>
MINKQ_HD void scan_leaves(const BoxGroup* leaf_groups, const int32_t* sorted_prims, const Shape& shape, int32_t first,
                          int32_t last, int32_t after, OnLeaf& on_leaf, Work& work) {
  for (int64_t p = first > after ? first : after + 1; p <= last; p = (p | 3) + 1) {
    const int64_t base = p & ~int64_t(3);
    const int from = int(p - base), to = last - base < 3 ? int(last - base) : 3;
    const BoxGroup& group = leaf_groups[base >> 2];
    unsigned hits = shape.overlaps_group(group, (2u << to) - (1u << from));  // lanes from..to
    for (int k = from; k <= to; ++k) work.test_node();
    for (; hits != 0; hits &= hits - 1u) {
      const int k = lowest_bit(hits);
      on_leaf(sorted_prims[base + k], group_box(group, k));
    }
  }
}

// A leaf range whose box passed may_overlap. One leaf: its box is the range's and passed the
// box test; only the finer one is left.
template <class Shape, class OnLeaf, class Work>
MINKQ_HD void visit_leaf_range(const BoxGroup* leaf_groups, const int32_t* sorted_prims, const Shape& shape,
                               int32_t first, int32_t last, int32_t after, const Box& range_box, OnLeaf& on_leaf,
                               Work& work) {
  if (first == last) {
    if (shape.finer(range_box)) on_leaf(sorted_prims[first], range_box);
    return;
  }
  scan_leaves(leaf_groups, sorted_prims, shape, first, last, after, on_leaf, work);
}

// The one traversal: on_leaf(prim, box) is called for every primitive whose box the shape
// overlaps (the contract at the top of shapes.h makes that exact: may_overlap accepts every
// ancestor box of such a box). Only leaves at sorted positions after `after` are reached: a
// self-query from the leaf at position i passes i and meets each pair once; other queries
// pass -1. A node is entered only when its last position is past `after` (the root:
// n - 1 > after), so only the left child (last = split) can fail.
template <class Shape, class OnLeaf, class Work>
MINKQ_HD void traverse(const BvhView& bvh, const Shape& shape, int32_t after, OnLeaf& on_leaf, Work& work) {
  if (bvh.num_prims <= 0 || after >= bvh.num_prims - 1) return;
  auto visit_range = [&](int32_t first, int32_t last, const Box& range_box) {
    visit_leaf_range(bvh.leaf_groups, bvh.sorted_prims, shape, first, last, after, range_box, on_leaf, work);
  };
  int32_t stack[kTraversalStack];
  int sp = 0;
  int32_t node = 0;
  while (true) {
    const BvhNode& n = bvh.nodes[node];
    work.visit_node();
    int32_t next = -1;
    if (n.split > after) {
      work.test_node();
      if (shape.may_overlap(n.left_box)) {
        if (n.left < 0) visit_range(~n.left, n.split, n.left_box); else next = n.left;
      }
    }
    if (n.right != kNoChild) {
      work.test_node();
      if (shape.may_overlap(n.right_box)) {
        if (n.right < 0) {
          visit_range(n.split + 1, ~n.right, n.right_box);
        } else if (next < 0) {
          next = n.right;
        } else {
          stack[sp++] = n.right;
        }
      }
    }
    if (next >= 0) { node = next; continue; }
    if (sp == 0) return;
    node = stack[--sp];
  }
}

}  // namespace minkq
