// The CPU tree: tree.h's per-element build and refit steps run in parallel with TBB, the
// counterpart of cuda/tree.cuh (the same steps, so the trees are bit-identical). Used by the
// CPU executor (cpu/backend.cpp) and, through the minkq_internal target, by the tree tests and
// the benchmarks' studies.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <utility>
#include <vector>

#include "cpu/runtime.h"
#include "minkq/tree.h"

namespace minkq {

// The bounds of the centres of boxes(0..n-1) (min and max are exact: any order gives them).
template <class Boxes>
Box centre_bounds(Boxes boxes, int32_t n) {
  return tbb::parallel_reduce(
      tbb::blocked_range<int32_t>(0, n, 4096), Box::empty(),
      [&](const tbb::blocked_range<int32_t>& range, Box acc) {
        for (int32_t i = range.begin(); i != range.end(); ++i) acc = box_expand(acc, box_centre(boxes(i)));
        return acc;
      },
      [](Box a, Box b) { return box_union(a, b); });
}

// Ids 0..n-1 sorted by key_of(id), ties broken by id (as CUB's stable radix sort of the CUDA
// backend), with the sorted keys.
template <class KeyOf>
void sort_by_key(int32_t n, const KeyOf& key_of, std::vector<uint64_t>& keys, std::vector<int32_t>& ids) {
  std::vector<std::pair<uint64_t, int32_t>> keyed(static_cast<size_t>(n));
  parallel_for_each(n, [&](int64_t i) { keyed[i] = {key_of(int32_t(i)), int32_t(i)}; });
  tbb::parallel_sort(keyed.begin(), keyed.end());
  keys.assign(size_t(n), 0);
  ids.assign(size_t(n), 0);
  parallel_for_each(n, [&](int64_t i) {
    keys[i] = keyed[i].first;
    ids[i] = keyed[i].second;
  });
}

// Ids 0..n-1 sorted by the Morton code of their box centres (ties by id), with the keys.
template <class Boxes>
void sort_by_morton(Boxes boxes, int32_t n, std::vector<uint64_t>& keys, std::vector<int32_t>& ids) {
  if (n == 0) {
    keys.clear();
    ids.clear();
    return;
  }
  const MortonFrame frame = morton_frame(centre_bounds(boxes, n));
  sort_by_key(n, [&](int32_t i) { return morton_code(frame, box_centre(boxes(i))); }, keys, ids);
}

// tree.h's bottom-up refit from every child slot of `nodes` in parallel (the arrival counters,
// one per node, zeroed first): the leaf groups and every node's child boxes from boxes().
template <class Boxes>
void refit_slots(Boxes boxes, std::vector<BvhNode>& nodes, const int32_t* sorted_prims, BoxGroup* leaf_groups,
                 std::vector<int32_t>& arrivals) {
  std::fill(arrivals.begin(), arrivals.end(), 0);
  parallel_for_each(int64_t(nodes.size()) * 2, [&](int64_t slot) {
    refit_from_slot(int32_t(slot), boxes, sorted_prims, leaf_groups, nodes.data(), arrivals.data());
  });
}

class CpuTree {
 public:
  const std::vector<BvhNode>& nodes() const { return nodes_; }
  // Primitive at each sorted leaf position.
  const std::vector<int32_t>& sorted_prims() const { return sorted_prims_; }

  // Builds the tree over boxes(0..n-1): sorted by the Morton codes of their centres, then
  // the hierarchy over the sorted codes.
  template <class Boxes>
  void build(Boxes boxes, int32_t n, const BuildConfig& config = {}) {
    std::vector<uint64_t> keys;
    std::vector<int32_t> order;
    if (n > 1) sort_by_morton(boxes, n, keys, order);
    build_sorted(boxes, keys, std::move(order), n, config);
  }

  // The same over primitives already in leaf order: sorted_prims[p] is the primitive at leaf
  // position p and keys[p] its 63-bit key, ascending (ties in position order); for n <= 1
  // both may be empty. build() is this with Morton codes.
  template <class Boxes>
  void build_sorted(Boxes boxes, const std::vector<uint64_t>& keys, std::vector<int32_t> sorted_prims, int32_t n,
                    const BuildConfig& config = {}) {
    const int32_t leaf_size = config.leaf_size;
    n_ = n;
    cost_at_build_ = 0.0;
    nodes_.clear();
    sorted_prims_ = std::move(sorted_prims);
    sorted_prims_.resize(size_t(n), 0);
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

  template <class Boxes>
  void refit(Boxes boxes) {
    refit_slots(boxes, nodes_, sorted_prims_.data(), leaf_groups_.data(), arrivals_);
  }

  // The tree's area cost (tree.h's area_cost).
  double area_cost() const { return minkq::area_cost(nodes_.data(), int64_t(nodes_.size())); }
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
