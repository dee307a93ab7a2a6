// The one-pass bottom-up build (Apetrei 2014, as ArborX builds), studied for issue 27 and not
// kept: on this machine's CPUs its climb, with an atomic exchange per node and a dependent
// chain of loads per leaf, took as long as the Karras hierarchy plus the refit it replaces
// (bench/results/build.md, "one-pass" column). It gives the library's trees record for record
// (minkq_build_study checks), so it stays here as the starting point of a GPU study, where
// atomics are cheap and the Karras searches diverge.
#pragma once

#include <vector>

#include "cpu/runtime.h"
#include "cpu/tree.h"
#include "minkq/tree.h"
#include "karras_tree.h"

namespace minkq::bench {

// The binary tree over n >= 2 sorted keys that karras_node() describes, built bottom-up with
// its boxes in one pass (Apetrei 2014): a thread per leaf climbs. A node's parent extends it
// towards the neighbour with which it shares the longer key prefix (the two prefixes are never
// equal); of a parent's two children, the first to arrive leaves its far end at the parent's
// split and stops, the second takes it, merges both boxes and climbs on. A node that is a left
// child is Karras node `last` of its range, a right child node `first`, the root node 0, so the
// pass writes the records karras_node() would give, plus each node's box, and the collapse
// below numbers and links them unchanged. `ends` (n - 1 entries, one per split) starts all -1.

inline int32_t atomic_exchange(int32_t* slot, int32_t value) {
  return __atomic_exchange_n(slot, value, __ATOMIC_ACQ_REL);
}

// The climb from sorted leaf position p: element[order[q]] is the box at position q. Writes
// leaf p's box into its group lane, and for every node this thread completes its Karras record
// and its box (node_boxes, by Karras index).
inline void climb_from_leaf(int32_t p, const uint64_t* keys, int32_t n, const Box* element, const int32_t* order,
                            BoxGroup* leaf_groups, int32_t* ends, KarrasNode* karras, Box* node_boxes) {
  Box box = element[order[p]];
  set_group_box(leaf_groups[p >> 2], p & 3, box);
  int32_t first = p, last = p, split = -1;  // the node reached so far, and its split (-1: a leaf)
  while (true) {
    const bool root = first == 0 && last == n - 1;
    const bool left = !root && (first == 0 || (last != n - 1 && common_prefix(keys, n, last, last + 1) >
                                                                  common_prefix(keys, n, first - 1, first)));
    if (split >= 0) {  // an internal node, complete: its record and box
      const int32_t self = root ? 0 : left ? last : first;
      karras[self] = {first, last, split};
      node_boxes[self] = box;
    }
    if (root) return;
    const int32_t parent_split = left ? last : first - 1;
    const int32_t other = atomic_exchange(&ends[parent_split], left ? first : last);
    if (other < 0) return;  // the sibling is still on its way: it climbs on
    // The sibling: [parent_split + 1, other] on the right, or [other, parent_split] on the left;
    // one leaf's box is the element's, a larger node's was written by the thread that made it.
    const int32_t sibling = left ? parent_split + 1 : parent_split;
    const bool sibling_leaf = left ? other == parent_split + 1 : other == parent_split;
    const Box other_box = sibling_leaf ? element[order[sibling]] : node_boxes[sibling];
    box = left ? box_union(box, other_box) : box_union(other_box, box);  // left before right, as the refit
    if (left) last = other; else first = other;
    split = parent_split;
  }
}

// Kept node i's child boxes from the one-pass build: a binary child's box, whether the child
// stays a node or becomes a leaf range (unions are exact: the refit would give the same).
inline void set_child_boxes(int32_t i, const KarrasNode* karras, const int32_t* new_index, const Box* node_boxes,
                            const Box* element, const int32_t* order, BvhNode* nodes) {
  const KarrasNode k = karras[i];
  BvhNode& node = nodes[new_index[i]];
  node.left_box = k.first == k.split ? element[order[k.first]] : node_boxes[k.split];
  node.right_box = k.split + 1 == k.last ? element[order[k.last]] : node_boxes[k.split + 1];
}

// The node records over n >= 2 sorted keys, their boxes and the leaf groups (what
// CpuTree::build gives): the climb from every leaf in parallel, the kept nodes numbered by the
// CUDA build's scan (testing/karras_tree.h), then each written once with its child boxes.
inline void build_nodes_one_pass(const uint64_t* keys, int32_t n, const Box* element, const int32_t* order,
                                 int32_t leaf_size, std::vector<BvhNode>& nodes, BoxGroup* leaf_groups) {
  std::vector<KarrasNode> karras(static_cast<size_t>(n - 1));
  std::vector<Box> node_boxes(static_cast<size_t>(n - 1));
  std::vector<int32_t> ends(static_cast<size_t>(n - 1), -1);
  parallel_for_each(n, [&](int64_t p) {
    climb_from_leaf(int32_t(p), keys, n, element, order, leaf_groups, ends.data(), karras.data(), node_boxes.data());
  });
  std::vector<int32_t> new_index;
  nodes.assign(size_t(test::index_kept_nodes(karras, leaf_size, new_index)), BvhNode{});
  parallel_for_each(n - 1, [&](int64_t i) {
    if (!keeps_node(int32_t(i), karras[size_t(i)], leaf_size)) return;
    collapse_node(int32_t(i), karras.data(), new_index.data(), leaf_size, nodes.data());
    set_child_boxes(int32_t(i), karras.data(), new_index.data(), node_boxes.data(), element, order, nodes.data());
  });
}

}  // namespace minkq::bench
