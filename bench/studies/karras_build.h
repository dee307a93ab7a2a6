// The build the library ran before issue 27 (retired, kept for minkq_build_study's same-run
// comparison): the primitive box functor evaluated in each of three passes (centre bounds,
// Morton codes, refit), (key, id) pairs sorted by TBB's comparison sort, and the kept Karras
// nodes numbered by a serial scan. Its trees equal CpuTree::build's record for record (the
// study checks that before timing either).
#pragma once

#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

#include <utility>
#include <vector>

#include "cpu/runtime.h"
#include "cpu/tree.h"
#include "minkq/tree.h"

namespace minkq::bench {

struct RetiredTree {
  std::vector<BvhNode> nodes;
  std::vector<int32_t> sorted_prims;
  std::vector<BoxGroup> leaf_groups;
  std::vector<int32_t> arrivals;
  double cost_at_build = 0.0;
};

template <class Boxes>
void build_retired(RetiredTree& t, Boxes boxes, int32_t n, int32_t leaf_size = kLeafSize) {
  t.nodes.clear();
  t.sorted_prims.assign(size_t(n), 0);
  t.leaf_groups.assign(size_t(box_group_count(n)), BoxGroup{});
  t.arrivals.clear();
  if (n == 0) return;
  if (n == 1) {
    t.nodes.assign(1, one_leaf_root());
    t.arrivals.assign(1, 0);
    refit_slots(boxes, t.nodes, t.sorted_prims.data(), t.leaf_groups.data(), t.arrivals);
    t.cost_at_build = area_cost(t.nodes.data(), int64_t(t.nodes.size()));
    return;
  }
  const Box centres = tbb::parallel_reduce(
      tbb::blocked_range<int32_t>(0, n, 4096), Box::empty(),
      [&](const tbb::blocked_range<int32_t>& range, Box acc) {
        for (int32_t i = range.begin(); i != range.end(); ++i) acc = box_expand(acc, box_centre(boxes(i)));
        return acc;
      },
      [](Box a, Box b) { return box_union(a, b); });
  const MortonFrame frame = morton_frame(centres);
  std::vector<std::pair<uint64_t, int32_t>> keyed(static_cast<size_t>(n));
  parallel_for_each(n, [&](int64_t i) { keyed[size_t(i)] = {morton_code(frame, box_centre(boxes(int32_t(i)))), int32_t(i)}; });
  tbb::parallel_sort(keyed.begin(), keyed.end());
  std::vector<uint64_t> keys(static_cast<size_t>(n));
  parallel_for_each(n, [&](int64_t i) {
    keys[size_t(i)] = keyed[size_t(i)].first;
    t.sorted_prims[size_t(i)] = keyed[size_t(i)].second;
  });
  std::vector<KarrasNode> karras(size_t(n - 1));
  parallel_for_each(n - 1, [&](int64_t i) { karras[size_t(i)] = karras_node(int32_t(i), keys.data(), n); });
  std::vector<int32_t> new_index(size_t(n - 1));
  int32_t kept = 0;
  for (int32_t i = 0; i < n - 1; ++i) {
    new_index[size_t(i)] = kept;
    kept += keeps_node(i, karras[size_t(i)], leaf_size) ? 1 : 0;
  }
  t.nodes.assign(size_t(kept), BvhNode{});
  t.arrivals.assign(size_t(kept), 0);
  parallel_for_each(n - 1, [&](int64_t i) {
    if (keeps_node(int32_t(i), karras[size_t(i)], leaf_size))
      collapse_node(int32_t(i), karras.data(), new_index.data(), leaf_size, t.nodes.data());
  });
  refit_slots(boxes, t.nodes, t.sorted_prims.data(), t.leaf_groups.data(), t.arrivals);
  t.cost_at_build = area_cost(t.nodes.data(), int64_t(t.nodes.size()));
}

}  // namespace minkq::bench
