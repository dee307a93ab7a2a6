// A study of issue 8's "wide BVH" lever (bench only, not the library's tree): the binary tree
// of CpuTree collapsed into W-ary nodes (W = 4 or 8), each holding its children's boxes in
// groups of four (BoxGroup) so a vector compare per axis tests four at once. Leaf ranges, the
// sorted leaf order and the leaf boxes stay the binary tree's, so the leaf scan, the EE
// "after" pruning and the pairs are unchanged; only the internal levels differ.
//
// Topology is fixed when collapsing (at the frame the binary tree was built, from its child
// box areas); fill() then copies the boxes of any refit of that binary tree: each wide child
// is one binary child slot, whose box is the exact union of its leaves, which is what a
// bottom-up refit of the wide nodes would compute.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "cpu/tree.h"
#include "minkq/queries.h"  // run_query_wide: QueryTarget, LeafFilter
#include "minkq/traversal.h"
#include "studies/box_tests.h"

namespace minkq::bench {

template <int W>
struct WideNode {
  BoxGroup boxes[W / 4];  // child k's box: lane k % 4 of group k / 4; empty slots +inf / -inf (fail every test)
  int32_t child[W];       // >= 0: wide node; < 0 (not kNoChild): ~first of a leaf range; kNoChild: empty
  int32_t last[W];        // last sorted leaf position under the child (-1 in empty slots)
  Box box(int k) const { return group_box(boxes[k / 4], k % 4); }
};
static_assert(sizeof(WideNode<4>) == 128 && sizeof(WideNode<8>) == 256, "two or four 64-byte lines");

template <int W>
class WideTree {
 public:
  // Collapses the binary tree: starting from a node's two child slots, the internal slot with
  // the largest box area is replaced by its two children until W slots are filled or none
  // is internal; nodes in depth-first order, children left to right (leaf order kept).
  void collapse(const CpuTree& binary) {
    nodes_.clear();
    source_.clear();
    n_ = binary.size();
    if (n_ < 2) return;  // the studies use scenes with at least two primitives
    const auto& b = binary.nodes();
    struct Slot {
      int32_t slot;  // binary (node << 1) | side
      int32_t child;
      int32_t last;
    };
    // A binary right leaf range is ~last; every wide leaf range is ~first.
    auto slots_of = [&](int32_t node, int32_t last) {
      const BvhNode& n = b[size_t(node)];
      const int32_t right = n.right >= 0 || n.right == kNoChild ? n.right : ~(n.split + 1);
      return std::vector<Slot>{{node << 1, n.left, n.split}, {node << 1 | 1, right, last}};
    };
    auto area = [&](const Slot& s) {
      const BvhNode& p = b[size_t(s.slot >> 1)];
      return half_area(s.slot & 1 ? p.right_box : p.left_box);
    };
    // (binary node, its last position, wide node's parent slot to link)
    struct Pending {
      int32_t binary, last, parent_slot;
    };
    std::vector<Pending> stack{{0, n_ - 1, -1}};
    while (!stack.empty()) {
      const Pending p = stack.back();
      stack.pop_back();
      std::vector<Slot> slots = slots_of(p.binary, p.last);
      while (int(slots.size()) < W) {
        int best = -1;
        for (int k = 0; k < int(slots.size()); ++k)
          if (slots[size_t(k)].child >= 0 && (best < 0 || area(slots[size_t(k)]) > area(slots[size_t(best)]))) best = k;
        if (best < 0) break;
        const Slot s = slots[size_t(best)];
        const std::vector<Slot> two = slots_of(s.child, s.last);
        slots.erase(slots.begin() + best);
        slots.insert(slots.begin() + best, two.begin(), two.end());
      }
      const int32_t self = int32_t(nodes_.size());
      if (p.parent_slot >= 0) nodes_[size_t(p.parent_slot / W)].child[p.parent_slot % W] = self;
      WideNode<W> node{};
      for (int k = 0; k < W; ++k) {
        node.child[k] = kNoChild;
        node.last[k] = -1;
        source_.push_back(-1);
      }
      for (int k = 0; k < int(slots.size()); ++k) {
        node.child[k] = slots[size_t(k)].child;  // internal ones relinked when their node is made
        node.last[k] = slots[size_t(k)].last;
        source_[size_t(self) * W + size_t(k)] = slots[size_t(k)].slot;
      }
      nodes_.push_back(node);
      for (int k = int(slots.size()) - 1; k >= 0; --k)  // left child first out: depth-first order
        if (slots[size_t(k)].child >= 0) stack.push_back({slots[size_t(k)].child, slots[size_t(k)].last, self * W + k});
    }
  }

  // Child boxes from the binary tree's current boxes (after its refit). quantized: each child
  // box grown outward to the grid of 255 steps of a power of two per axis spanning the node's
  // box (what 8-bit child planes relative to the node, as in compressed wide BVHs, can hold),
  // stored decoded: the tests and counts are those of such a layout, the time is not (no
  // decoding here, and the records keep their float size).
  void fill(const CpuTree& binary, bool quantized = false) {
    const auto& b = binary.nodes();
    quantized_ = quantized;
    for (size_t i = 0; i < nodes_.size(); ++i) {
      Box boxes[W];
      Box node_box = Box::empty();
      for (int k = 0; k < W; ++k) {
        const int32_t slot = source_[i * W + size_t(k)];
        boxes[k] = {{INFINITY, INFINITY, INFINITY}, {-INFINITY, -INFINITY, -INFINITY}};
        if (slot < 0) continue;
        boxes[k] = slot & 1 ? b[size_t(slot >> 1)].right_box : b[size_t(slot >> 1)].left_box;
        node_box = box_union(node_box, boxes[k]);
      }
      for (int k = 0; k < W; ++k) {
        float lo[3] = {boxes[k].lo.x, boxes[k].lo.y, boxes[k].lo.z}, hi[3] = {boxes[k].hi.x, boxes[k].hi.y, boxes[k].hi.z};
        if (quantized && source_[i * W + size_t(k)] >= 0) {
          const float origin[3] = {node_box.lo.x, node_box.lo.y, node_box.lo.z};
          const float top[3] = {node_box.hi.x, node_box.hi.y, node_box.hi.z};
          for (int a = 0; a < 3; ++a) {
            const double step = std::ldexp(1.0, std::ilogb(std::max(double(top[a]) - origin[a], 1e-300) / 255.0) + 1);
            const double qlo = std::floor((double(lo[a]) - origin[a]) / step);
            const double qhi = std::min(255.0, std::ceil((double(hi[a]) - origin[a]) / step));
            // Decoded planes, rounded outward to float and never inside the exact box.
            lo[a] = std::min(lo[a], next_down(float(origin[a] + qlo * step)));
            hi[a] = std::max(hi[a], qhi >= 255.0 ? top[a] : next_up(float(origin[a] + qhi * step)));
          }
        }
        set_group_box(nodes_[i].boxes[k / 4], k % 4, {{lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}});
      }
    }
    leaf_groups_ = binary.leaf_groups();
    sorted_prims_ = binary.sorted_prims().data();
  }
  // Whether child boxes are grown (quantized): a one-primitive leaf then needs its exact box.
  bool quantized() const { return quantized_; }

  const std::vector<WideNode<W>>& nodes() const { return nodes_; }
  const BoxGroup* leaf_groups() const { return leaf_groups_; }
  const int32_t* sorted_prims() const { return sorted_prims_; }
  int32_t size() const { return n_; }

 private:
  int32_t n_ = 0;
  bool quantized_ = false;
  std::vector<WideNode<W>> nodes_;
  std::vector<int32_t> source_;  // binary child slot of each wide child, -1 for empty slots
  const BoxGroup* leaf_groups_ = nullptr;
  const int32_t* sorted_prims_ = nullptr;
};

// Bit k set where child k passes the shape's box test, four children at a time
// (may_overlap_group: 4-float lanes for the library's shapes).
template <int W, class Shape>
inline unsigned box_test_lanes(const WideNode<W>& node, const Shape& shape) {
  unsigned bits = 0;
  for (int g = 0; g < W / 4; ++g) bits |= may_overlap_group(shape, node.boxes[g], 0xfu) << (4 * g);
  return bits;
}

// traverse_groups() of traversal.h over wide nodes; kLanes: the child boxes tested 4 at a time, else the
// shape's may_overlap child by child. Leaf ranges are visited as the library does (traversal.h).
// Work counts: nodes_visited = wide records read, node_tests = non-empty child boxes past
// `after` (tested) plus leaf boxes scanned.
template <int W, bool kLanes, class Shape, class OnLeaf, class Work>
void traverse_wide(const WideTree<W>& tree, const Shape& shape, int32_t after, OnLeaf& on_leaf, Work& work) {
  if (tree.size() < 2 || after >= tree.size() - 1) return;
  const WideNode<W>* nodes = tree.nodes().data();
  auto visit_range = [&](int32_t first, int32_t last, const Box& range_box) {
    if (tree.quantized())  // a child box holds its primitive's only grown: test the exact one
      return scan_leaves(tree.leaf_groups(), shape, first, last, after, on_leaf, work);
    visit_leaf_range(tree.leaf_groups(), shape, first, last, after, range_box, on_leaf, work);
  };
  int32_t stack[kTraversalStack * W];  // each level pushes at most W - 1 siblings
  int sp = 0;
  int32_t node = 0;
  while (true) {
    const WideNode<W>& n = nodes[node];
    work.visit_node();
    unsigned hits = 0;
    if constexpr (kLanes) {
      hits = box_test_lanes(n, shape);
      for (int k = 0; k < W; ++k) {
        if (n.child[k] == kNoChild || n.last[k] <= after) hits &= ~(1u << k);
        else work.test_node();
      }
    } else {
      for (int k = 0; k < W; ++k) {
        if (n.child[k] == kNoChild || n.last[k] <= after) continue;
        work.test_node();
        if (shape.may_overlap(n.box(k))) hits |= 1u << k;
      }
    }
    int32_t next = -1;
    for (int k = W - 1; k >= 0; --k) {  // right to left: the leftmost internal child is visited next
      if (!(hits >> k & 1u)) continue;
      const int32_t c = n.child[k];
      if (c < 0) {
        visit_range(~c, n.last[k], n.box(k));
      } else {
        if (next >= 0) stack[sp++] = next;
        next = c;
      }
    }
    if (next >= 0) { node = next; continue; }
    if (sp == 0) return;
    node = stack[--sp];
  }
}

// run_query of queries.h over a wide tree.
template <int W, bool kLanes, class Shape, class Queries, class Emit, class Work>
void run_query_wide(const WideTree<W>& tree, const Queries& queries, int32_t i, Emit& emit, Work& work) {
  const QueryTarget target = queries.target(i);
  const Shape shape = Shape::from(queries.geometry(target));
  LeafFilter<Shape, Queries, Emit, Work> on_leaf{queries, tree.sorted_prims(), target, emit, work};
  traverse_wide<W, kLanes>(tree, shape, target.after, on_leaf, work);
}

}  // namespace minkq::bench
