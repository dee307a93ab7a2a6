// The CPU tree: bvh.h's per-element build and refit steps run in parallel with TBB. Shared by
// the CPU backend and the BVH invariant tests.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <utility>
#include <vector>

#include "minkq/bvh.h"

namespace minkq {

template <class Fn>
void parallel_for_each(int64_t n, Fn&& fn) {
  tbb::parallel_for(tbb::blocked_range<int64_t>(0, n, 1024), [&](const tbb::blocked_range<int64_t>& range) {
    for (int64_t i = range.begin(); i != range.end(); ++i) fn(i);
  });
}

// Ids 0..n-1 sorted by the Morton code of their box centres, ties broken by id (as CUB's
// stable radix sort of the CUDA backend), with the sorted keys.
template <class Boxes>
void sort_by_morton(Boxes boxes, int32_t n, std::vector<uint64_t>& keys, std::vector<int32_t>& ids,
                    MortonCells cells = MortonCells::kCubes) {
  keys.assign(size_t(n), 0);
  ids.assign(size_t(n), 0);
  if (n == 0) return;
  const Box centre_bounds = tbb::parallel_reduce(
      tbb::blocked_range<int32_t>(0, n, 4096), Box::empty(),
      [&](const tbb::blocked_range<int32_t>& range, Box acc) {
        for (int32_t i = range.begin(); i != range.end(); ++i) acc = box_expand(acc, box_centre(boxes(i)));
        return acc;
      },
      [](Box a, Box b) { return box_union(a, b); });
  const MortonFrame frame = morton_frame(centre_bounds, cells);
  std::vector<std::pair<uint64_t, int32_t>> keyed(static_cast<size_t>(n));
  parallel_for_each(n, [&](int64_t i) { keyed[i] = {morton_code(frame, box_centre(boxes(int32_t(i)))), int32_t(i)}; });
  tbb::parallel_sort(keyed.begin(), keyed.end());
  parallel_for_each(n, [&](int64_t i) {
    keys[i] = keyed[i].first;
    ids[i] = keyed[i].second;
  });
}

class CpuTree {
 public:
  const std::vector<BvhNode>& nodes() const { return nodes_; }
  // Primitive at each sorted leaf position.
  const std::vector<int32_t>& sorted_prims() const { return sorted_prims_; }

  // leaf_size: primitives per leaf range at most (1 to kLeafSize; other sizes, and other
  // Morton cells, for studies).
  template <class Boxes>
  void build(Boxes boxes, int32_t n, int32_t leaf_size = kLeafSize, MortonCells cells = MortonCells::kCubes) {
    n_ = n;
    cost_at_build_ = 0.0;
    nodes_.clear();
    sorted_prims_.assign(size_t(n), 0);
    leaf_groups_.assign(size_t(box_group_count(n)), BoxGroup{});
    arrivals_.clear();
    if (n == 0) return;
    if (n == 1) {
      nodes_.assign(1, one_leaf_root());
      arrivals_.assign(1, 0);
      refit(boxes);
      cost_at_build_ = area_cost();
      return;
    }
    std::vector<uint64_t> keys;
    sort_by_morton(boxes, n, keys, sorted_prims_, cells);
    std::vector<KarrasNode> karras(size_t(n - 1));
    parallel_for_each(n - 1, [&](int64_t i) { karras[i] = karras_node(int32_t(i), keys.data(), n); });
    std::vector<int32_t> new_index(size_t(n - 1));
    int32_t kept = 0;
    for (int32_t i = 0; i < n - 1; ++i) {
      new_index[i] = kept;
      kept += keeps_node(i, karras[i], leaf_size) ? 1 : 0;
    }
    nodes_.assign(size_t(kept), BvhNode{});
    arrivals_.assign(size_t(kept), 0);
    parallel_for_each(n - 1, [&](int64_t i) {
      if (keeps_node(int32_t(i), karras[i], leaf_size))
        collapse_node(int32_t(i), karras.data(), new_index.data(), leaf_size, nodes_.data());
    });
    refit(boxes);
    cost_at_build_ = area_cost();
  }

  // A tree laid out elsewhere (bench/ablation.cpp's SAH build, a study): node records with
  // their links and splits, and the primitive at each leaf position; refit fills the boxes.
  template <class Boxes>
  void adopt(std::vector<BvhNode> nodes, std::vector<int32_t> sorted_prims, Boxes boxes) {
    n_ = int32_t(sorted_prims.size());
    nodes_ = std::move(nodes);
    sorted_prims_ = std::move(sorted_prims);
    leaf_groups_.assign(size_t(box_group_count(n_)), BoxGroup{});
    arrivals_.assign(nodes_.size(), 0);
    refit(boxes);
    cost_at_build_ = area_cost();
  }

  template <class Boxes>
  void refit(Boxes boxes) {
    std::fill(arrivals_.begin(), arrivals_.end(), 0);
    parallel_for_each(int64_t(nodes_.size()) * 2, [&](int64_t slot) {
      refit_from_slot(int32_t(slot), boxes, sorted_prims_.data(), leaf_groups_.data(), nodes_.data(), arrivals_.data());
    });
  }

  // The sum of node_area over the nodes, over the root box's half area (0 without area):
  // summed in node order, so the same on every run.
  double area_cost() const {
    if (nodes_.empty()) return 0.0;
    const double root = root_half_area(nodes_[0]);
    if (!(root > 0.0)) return 0.0;
    double sum = 0.0;
    for (const BvhNode& node : nodes_) sum += node_area(node);
    return sum / root;
  }
  // area_cost() right after the last build.
  double cost_at_build() const { return cost_at_build_; }

  BvhView view() const { return {nodes_.data(), leaf_groups_.data(), sorted_prims_.data(), n_}; }
  // The box of the primitive at sorted position p, and all of them in groups of four.
  Box leaf_box(int32_t p) const { return group_box(leaf_groups_[size_t(p >> 2)], p & 3); }
  const BoxGroup* leaf_groups() const { return leaf_groups_.data(); }
  int32_t size() const { return n_; }
  // Bytes held: node records with their refit counters, and per primitive its id and box in
  // leaf order (boxes in groups of four: up to three unused lanes).
  size_t bytes() const {
    return nodes_.size() * (sizeof(BvhNode) + sizeof(int32_t)) + size_t(n_) * sizeof(int32_t) +
           leaf_groups_.size() * sizeof(BoxGroup);
  }

 private:
  int32_t n_ = 0;
  double cost_at_build_ = 0.0;
  std::vector<BvhNode> nodes_;
  std::vector<int32_t> arrivals_;
  std::vector<int32_t> sorted_prims_;
  std::vector<BoxGroup> leaf_groups_;  // box of the primitive at sorted position p: lane p % 4 of group p / 4
};

}  // namespace minkq
