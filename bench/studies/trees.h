// The tree builds the tree study (minkq_ablation --only trees) sets beside the library's
// Morton build over cubic cells (core/src/cpu/tree.h): Morton codes over cells stretched per
// axis (the usual LBVH frame, which the library used before), and a top-down binned SAH build
// (not kept). Both give trees in the library's layout, so its traversal and refit serve them.
#pragma once

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "cpu/tree.h"
#include "minkq/tree.h"
#include "store.h"

namespace minkq::bench {

// The per-axis Morton frame: every axis stretched to the full 21 bits of its own extent.
inline MortonFrame morton_frame_per_axis(const Box& centre_bounds) {
  const Vec3 extent = centre_bounds.hi - centre_bounds.lo;
  return {centre_bounds.lo, {morton_scale(extent.x), morton_scale(extent.y), morton_scale(extent.z)}};
}

// CpuTree::build with the per-axis frame in place of cubic cells.
template <class Boxes>
void build_per_axis(CpuTree& tree, Boxes boxes, int32_t n) {
  HostVector<uint64_t> keys;
  HostVector<int32_t> order;
  if (n > 1) {
    HostVector<Box> element;
    const MortonFrame frame = morton_frame_per_axis(element_boxes(boxes, n, element));
    sort_by_key(n, [&](int32_t i) { return morton_code(frame, box_centre(element[size_t(i)])); }, keys, order);
  }
  tree.build_sorted(boxes, keys, std::move(order), n);
}

// A tree laid out by the SAH build below, in the library's layout: node records with their
// links and splits, the primitive at each leaf position, the leaf boxes in groups of four, and
// the refit's arrival counters (refit with cpu/tree.h's refit_slots).
struct SahTree {
  std::vector<BvhNode> nodes;
  std::vector<int32_t> sorted_prims;
  std::vector<BoxGroup> leaf_groups;
  std::vector<int32_t> arrivals;
  double cost_at_build = 0.0;  // area_cost of the built tree (before any refit)

  template <class Boxes>
  void refit(Boxes boxes) {
    refit_slots(boxes, nodes, sorted_prims.data(), leaf_groups.data(), arrivals);
  }
  double growth() const { return minkq::growth(area_cost(nodes.data(), int64_t(nodes.size())), cost_at_build); }
  BvhView view() const { return {nodes.data(), leaf_groups.data(), sorted_prims.data(), int32_t(sorted_prims.size())}; }
};

// A top-down binned SAH build (the tree-quality alternative of issue 8; not the library's
// build): each range of primitives is split where the summed half areas of the two sides,
// weighted by their counts, are least (centres binned in 32 slabs per axis; the middle when
// the centres coincide), until a side holds at most kLeafSize primitives. Nodes in preorder,
// leaf ranges contiguous: the library's layout, traversal and refit serve it unchanged.
template <class Boxes>
SahTree build_sah(Boxes boxes, int32_t n) {
  constexpr int kBins = 32;
  std::vector<Box> box(static_cast<size_t>(n));
  std::vector<Vec3> centre(box.size());
  std::vector<int32_t> order(box.size());
  for (int32_t i = 0; i < n; ++i) {
    box[size_t(i)] = boxes(i);
    centre[size_t(i)] = box_centre(box[size_t(i)]);
    order[size_t(i)] = i;
  }
  auto axis_of = [](const Vec3& v, int axis) { return axis == 0 ? v.x : axis == 1 ? v.y : v.z; };
  // Partitions order[first..last] and returns the last position of the left side.
  auto split = [&](int32_t first, int32_t last) {
    Box bounds = Box::empty();
    for (int32_t p = first; p <= last; ++p) bounds = box_expand(bounds, centre[size_t(order[size_t(p)])]);
    double best = INFINITY;
    int best_axis = -1, best_bin = 0;
    for (int axis = 0; axis < 3; ++axis) {
      const float lo = axis_of(bounds.lo, axis), extent = axis_of(bounds.hi, axis) - lo;
      if (!(extent > 0.0f)) continue;
      Box bin_box[kBins];
      int32_t bin_count[kBins] = {};
      std::fill(bin_box, bin_box + kBins, Box::empty());
      for (int32_t p = first; p <= last; ++p) {
        const int32_t id = order[size_t(p)];
        const int b = std::min(kBins - 1, int((axis_of(centre[size_t(id)], axis) - lo) * (kBins / extent)));
        bin_box[b] = box_union(bin_box[b], box[size_t(id)]);
        ++bin_count[b];
      }
      double right_cost[kBins] = {};  // of bins b.. kBins - 1
      Box right = Box::empty();
      int32_t count = 0;
      for (int b = kBins - 1; b > 0; --b) {
        right = box_union(right, bin_box[b]);
        count += bin_count[b];
        right_cost[b] = count ? count * half_area(right) : -1.0;  // -1: empty side
      }
      Box left = Box::empty();
      count = 0;
      for (int b = 0; b + 1 < kBins; ++b) {
        left = box_union(left, bin_box[b]);
        count += bin_count[b];
        if (count == 0 || right_cost[b + 1] < 0.0) continue;
        const double cost = count * half_area(left) + right_cost[b + 1];
        if (cost < best) best = cost, best_axis = axis, best_bin = b;
      }
    }
    if (best_axis < 0) return first + (last - first) / 2;
    const float lo = axis_of(bounds.lo, best_axis), extent = axis_of(bounds.hi, best_axis) - lo;
    int32_t* middle = std::partition(order.data() + first, order.data() + last + 1, [&](int32_t id) {
      return std::min(kBins - 1, int((axis_of(centre[size_t(id)], best_axis) - lo) * (kBins / extent))) <= best_bin;
    });
    return int32_t(middle - order.data()) - 1;
  };
  std::vector<BvhNode> nodes;
  if (n == 1) nodes.push_back(one_leaf_root());
  struct Range {
    int32_t first, last, parent_slot;
  };
  std::vector<Range> stack;
  if (n > 1) stack.push_back({0, n - 1, -1});
  while (!stack.empty()) {
    const Range range = stack.back();
    stack.pop_back();
    const int32_t self = int32_t(nodes.size());
    if (range.parent_slot >= 0) {
      BvhNode& parent = nodes[size_t(range.parent_slot >> 1)];
      (range.parent_slot & 1 ? parent.right : parent.left) = self;
    }
    const int32_t s = split(range.first, range.last);
    BvhNode node{};
    node.parent = range.parent_slot;
    node.split = s;
    node.left = ~range.first;  // leaf ranges unless a child node links itself in
    node.right = ~range.last;
    nodes.push_back(node);
    // Right first: the left subtree follows its parent in memory.
    if (range.last - s > kLeafSize) stack.push_back({s + 1, range.last, self << 1 | 1});
    if (s - range.first + 1 > kLeafSize) stack.push_back({range.first, s, self << 1});
  }
  SahTree tree{std::move(nodes), std::move(order), {}, {}, 0.0};
  tree.leaf_groups.assign(size_t(box_group_count(n)), BoxGroup{});
  tree.arrivals.assign(tree.nodes.size(), 0);
  tree.refit(boxes);
  tree.cost_at_build = area_cost(tree.nodes.data(), int64_t(tree.nodes.size()));
  return tree;
}

}  // namespace minkq::bench
