// The CUDA build's hierarchy on the host, for the tests and the studies that compare the two
// backends' trees without a GPU (the CPU build reaches the same records another way).
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_scan.h>

#include <vector>

#include "cpu/runtime.h"
#include "cpu/tree.h"
#include "minkq/build.h"

namespace minkq::test {

// new_index[i] = the kept Karras nodes before node i (an exclusive scan in parallel, as the
// CUDA build's); returns how many are kept.
inline int32_t index_kept_nodes(const std::vector<KarrasNode>& karras, int32_t leaf_size,
                                std::vector<int32_t>& new_index) {
  const int32_t count = int32_t(karras.size());
  new_index.resize(size_t(count));
  return tbb::parallel_scan(
      tbb::blocked_range<int32_t>(0, count, 16384), 0,
      [&](const tbb::blocked_range<int32_t>& range, int32_t kept, bool is_final) {
        for (int32_t i = range.begin(); i != range.end(); ++i) {
          if (is_final) new_index[size_t(i)] = kept;
          kept += keeps_node(i, karras[size_t(i)], leaf_size) ? 1 : 0;
        }
        return kept;
      },
      [](int32_t a, int32_t b) { return a + b; });
}

// The node records, their boxes and the leaf groups of the tree over n >= 2 sorted keys, by the
// CUDA build's steps on the host (cuda/tree.cuh runs the same tree.h functions a thread per
// element): every Karras node, the kept ones numbered by index_kept_nodes, each written once
// (collapse_node), then the refit from element[order[p]], the box at sorted position p. The CPU
// build (cpu/tree.h's build_nodes, top-down through the kept nodes only) must give the same
// records byte for byte: test_bvh checks it (docs/design-notes.md: what the CPU build bought).
inline void build_nodes_karras(const uint64_t* keys, int32_t n, const Box* element, const int32_t* order,
                               int32_t leaf_size, HostVector<BvhNode>& nodes, BoxGroup* leaf_groups) {
  std::vector<KarrasNode> karras(size_t(n - 1));
  parallel_for_each(n - 1, [&](int64_t i) { karras[size_t(i)] = karras_node(int32_t(i), keys, n); });
  std::vector<int32_t> new_index;
  nodes.assign(size_t(index_kept_nodes(karras, leaf_size, new_index)), BvhNode{});
  parallel_for_each(n - 1, [&](int64_t i) {
    if (keeps_node(int32_t(i), karras[size_t(i)], leaf_size))
      collapse_node(int32_t(i), karras.data(), new_index.data(), leaf_size, nodes.data());
  });
  HostVector<int32_t> arrivals(nodes.size(), 0);
  refit_slots(GivenBoxes{element}, nodes, order, leaf_groups, arrivals);
}

}  // namespace minkq::test
