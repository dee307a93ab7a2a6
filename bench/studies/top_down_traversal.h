// The self-query's walk before issue 27's half traversal, kept for bench/traversal_study.cpp: a
// self-query from the leaf at sorted position `after` descends from the root like any query,
// testing both children of each node on the path to its own leaf (tests that always pass,
// since those nodes hold the query's own box) and skipping left children that end at or
// before `after`. Same pairs, met in the same order, as traversal.h's traverse_groups().
#pragma once

#include "minkq/traversal.h"

namespace minkq::bench {

template <class Shape, class OnHits, class Work>
void top_down_traverse(const BvhView& bvh, const Shape& shape, int32_t after, OnHits& on_leaf, Work& work) {
  if (bvh.num_prims <= 0 || after >= bvh.num_prims - 1) return;
  auto visit_range = [&](int32_t first, int32_t last, const Box& range_box) {
    visit_leaf_range(bvh.leaf_groups, shape, first, last, after, range_box, on_leaf, work);
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

// queries.h's run_query over the walk above.
template <class Shape, class Queries, class Emit, class Work>
void run_query_top_down(const BvhView& bvh, const Queries& queries, int32_t i, Emit& emit, Work& work) {
  const QueryTarget target = queries.target(i);
  const Shape shape = Shape::from(queries.geometry(target));
  LeafFilter<Shape, Queries, Emit, Work> on_leaf{queries, bvh.sorted_prims, target, emit, work};
  top_down_traverse(bvh, shape, target.after, on_leaf, work);
}

}  // namespace minkq::bench
