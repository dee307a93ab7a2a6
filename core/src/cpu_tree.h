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
void sort_by_morton(Boxes boxes, int32_t n, std::vector<uint64_t>& keys, std::vector<int32_t>& ids) {
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
  const MortonFrame frame = morton_frame(centre_bounds);
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
  const std::vector<int32_t>& leaf_parent() const { return leaf_parent_; }
  // Primitive at each sorted leaf position.
  const std::vector<int32_t>& sorted_prims() const { return sorted_prims_; }

  template <class Boxes>
  void build(Boxes boxes, int32_t n) {
    n_ = n;
    nodes_.assign(size_t(n > 1 ? n - 1 : n), BvhNode{});
    leaf_parent_.assign(size_t(n), 0);
    arrivals_.assign(nodes_.size(), 0);
    sorted_prims_.assign(size_t(n), 0);
    if (n == 0) return;
    if (n == 1) {
      nodes_[0].left = ~0;
      nodes_[0].right = kNoChild;
      nodes_[0].parent = -1;
      nodes_[0].split = 0;
      refit(boxes);
      return;
    }
    std::vector<uint64_t> keys;
    sort_by_morton(boxes, n, keys, sorted_prims_);
    parallel_for_each(n - 1, [&](int64_t i) {
      build_internal_node(int32_t(i), keys.data(), sorted_prims_.data(), n, nodes_.data(), leaf_parent_.data());
    });
    refit(boxes);
  }

  template <class Boxes>
  void refit(Boxes boxes) {
    std::fill(arrivals_.begin(), arrivals_.end(), 0);
    parallel_for_each(n_, [&](int64_t p) {
      refit_from_leaf(int32_t(p), boxes(int32_t(p)), leaf_parent_.data(), nodes_.data(), arrivals_.data());
    });
  }

  BvhView view() const { return {nodes_.data(), n_}; }
  int32_t size() const { return n_; }

 private:
  int32_t n_ = 0;
  std::vector<BvhNode> nodes_;
  std::vector<int32_t> leaf_parent_;
  std::vector<int32_t> arrivals_;
  std::vector<int32_t> sorted_prims_;
};

}  // namespace minkq
