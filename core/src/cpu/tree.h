// The CPU tree: the per-element build and refit steps run in parallel with TBB, the
// counterpart of cuda/tree.cuh (the same steps, so the trees are bit-identical). Used by the
// CPU executor (cpu/backend.cpp) and, through the minkq_internal target, by the tree tests and
// the benchmarks' studies.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <utility>

#include "cpu/radix_sort.h"
#include "cpu/runtime.h"
#include "minkq/build.h"
#include "minkq/cost.h"
#include "minkq/morton.h"
#include "minkq/refit.h"

namespace minkq {

// Every element's box once: out[i] = boxes(i), returning the bounds of their centres (min and
// max are exact: any order gives them). The build reads the boxes from `out` from then on.
template <class Boxes>
Box element_boxes(Boxes boxes, int32_t n, HostVector<Box>& out) {
  static_assert(!by_leaf_position<Boxes>, "a build reads its elements by id");
  out.resize(size_t(n));
  return tbb::parallel_reduce(
      tbb::blocked_range<int32_t>(0, n, 4096), Box::empty(),
      [&](const tbb::blocked_range<int32_t>& range, Box acc) {
        for (int32_t i = range.begin(); i != range.end(); ++i) {
          const Box b = boxes(i);
          out[size_t(i)] = b;
          acc = box_expand(acc, box_centre(b));
        }
        return acc;
      },
      [](Box a, Box b) { return box_union(a, b); });
}

// Ids 0..n-1 sorted by key_of(id), ties broken by id (a stable radix sort, as CUB's of the
// CUDA backend), with the sorted keys.
template <class KeyOf>
void sort_by_key(int32_t n, const KeyOf& key_of, HostVector<uint64_t>& keys, HostVector<int32_t>& ids) {
  keys.resize(size_t(n));
  ids.resize(size_t(n));
  parallel_for_each(n, [&](int64_t i) {
    keys[size_t(i)] = key_of(int32_t(i));
    ids[size_t(i)] = int32_t(i);
  });
  radix_sort_pairs(keys, ids, 64);
}

// Ids 0..n-1 sorted by the Morton code of the centres of boxes[0..n-1] (ties by id), with the
// keys; centres: the bounds of those centres (element_boxes gives both).
inline void sort_by_morton(const HostVector<Box>& boxes, const Box& centres, HostVector<uint64_t>& keys,
                           HostVector<int32_t>& ids, RadixScratch& scratch) {
  const int32_t n = int32_t(boxes.size());
  const MortonFrame frame = morton_frame(centres);
  keys.resize(size_t(n));
  ids.resize(size_t(n));
  parallel_for_each(n, [&](int64_t i) {
    keys[size_t(i)] = morton_code(frame, box_centre(boxes[size_t(i)]));
    ids[size_t(i)] = int32_t(i);
  });
  radix_sort_pairs(keys, ids, 63, scratch);  // Morton codes use the low 63 bits
}
inline void sort_by_morton(const HostVector<Box>& boxes, const Box& centres, HostVector<uint64_t>& keys,
                           HostVector<int32_t>& ids) {
  RadixScratch scratch;
  sort_by_morton(boxes, centres, keys, ids, scratch);
}

// What a Morton sort of n elements needs besides its output, about 44 B per element: each
// element's box (evaluated once), the keys, the radix sort's second buffers.
struct SortScratch {
  HostVector<Box> element;
  HostVector<uint64_t> keys;
  RadixScratch radix;
  void reserve(int32_t n) {
    const size_t count = size_t(std::max(n, 0));
    element.reserve(count), keys.reserve(count), radix.keys.reserve(count), radix.values.reserve(count);
  }
  size_t bytes() const {
    return element.capacity() * sizeof(Box) + keys.capacity() * sizeof(uint64_t) + radix.bytes();
  }
};

// Ids 0..n-1 in the Morton order of boxes(0..n-1)'s centres (ties by id), each box evaluated
// once into s.element and the sorted keys left in s.keys.
template <class Boxes>
void sort_by_morton(Boxes boxes, int32_t n, HostVector<int32_t>& ids, SortScratch& s) {
  const Box centres = element_boxes(boxes, n, s.element);
  sort_by_morton(s.element, centres, s.keys, ids, s.radix);
}

// The scratch of a build over n elements, about 48 B per element: the sort's and the ids in key
// order (the sort's second key buffer, free once the keys are sorted, then holds the top-down
// build's per-node record: TopDownBuild). A tree keeps it once reserved (CpuTree::reserve_build),
// so that rebuilds of the same size allocate nothing; otherwise each build makes and frees its own.
struct BuildScratch {
  SortScratch sort;
  HostVector<int32_t> order;
  void reserve(int32_t n) {
    sort.reserve(n);
    order.reserve(size_t(std::max(n, 0)));
  }
  size_t bytes() const { return sort.bytes() + order.capacity() * sizeof(int32_t); }
};

// The tree over n >= 2 sorted keys, top-down from the root through the kept nodes only (those
// over more than leaf_size leaves; about one Karras node in twenty at the default size): each
// range comes from its parent, so a node costs one split search (split_position) instead of
// karras_node()'s three, and the nodes below the kept ones are never computed. The records
// equal those of the CUDA build (every Karras node, a scan of the kept ones, collapse_node, the
// refit), numbered the same: in Karras order, where the root and every right child (node
// `first` of its range) precede their subtrees and every left child (node `last`) follows its
// own. Two passes, subtrees over many leaves split into parallel tasks:
//   count: per kept Karras node i, its split and the kept nodes in its subtree, packed into
//          info[i] (a node's two children sit side by side there, split and split + 1);
//   emit:  each kept node's record, with its number, links, child boxes and the leaf groups,
//          the boxes returned upwards (unions are exact: the same boxes as a refit's).
template <class Boxes>
struct TopDownBuild {
  static constexpr int32_t kTaskLeaves = 4096;  // a subtree over more leaves forks its children
  const uint64_t* keys;
  int32_t n, leaf_size;
  Boxes boxes;
  const int32_t* sorted_prims;
  uint64_t* info;  // n - 1 entries: (kept nodes in the subtree << 32) | split, at kept nodes only
  BvhNode* nodes;
  BoxGroup* leaf_groups;

  static int32_t split_of(uint64_t info) { return int32_t(uint32_t(info)); }
  static int32_t nodes_of(uint64_t info) { return int32_t(info >> 32); }

  template <class Left, class Right>
  static void both(int32_t first, int32_t last, const Left& left, const Right& right) {
    if (last - first + 1 > kTaskLeaves) tbb::parallel_invoke(left, right);
    else left(), right();
  }

  // Kept node i over [first, last]: how many kept nodes its subtree holds, itself included.
  int32_t count(int32_t i, int32_t first, int32_t last) const {
    const int32_t split = split_position(keys, n, first, last);
    int32_t left = 0, right = 0;
    both(first, last, [&] { if (keeps_range(first, split, leaf_size)) left = count(split, first, split); },
         [&] { if (keeps_range(split + 1, last, leaf_size)) right = count(split + 1, split + 1, last); });
    const int32_t below = 1 + left + right;
    info[i] = uint64_t(uint32_t(below)) << 32 | uint32_t(split);
    return below;
  }

  // Writes kept node i over [first, last] and its subtree; base: the kept nodes before the
  // subtree's Karras indices, parent: its link. Returns the subtree's box.
  Box emit(int32_t i, int32_t first, int32_t last, int32_t base, int32_t parent) const {
    const int32_t split = split_of(info[i]);
    const bool left_kept = keeps_range(first, split, leaf_size), right_kept = keeps_range(split + 1, last, leaf_size);
    const int32_t below_left = left_kept ? nodes_of(info[split]) : 0;
    const int32_t below_right = right_kept ? nodes_of(info[split + 1]) : 0;
    const bool precedes = i == first;
    const int32_t self = precedes ? base : base + below_left + below_right;
    const int32_t left_base = precedes ? base + 1 : base, right_base = left_base + below_left;
    BvhNode node;
    node.left = left_kept ? left_base + below_left - 1 : ~first;  // a left child follows its subtree
    node.right = right_kept ? right_base : ~last;                  // a right child precedes its own
    node.parent = parent;
    node.split = split;
    both(
        first, last,
        [&] {
          node.left_box = left_kept ? emit(split, first, split, left_base, self << 1)
                                    : leaf_range_box(first, split, boxes, sorted_prims, leaf_groups);
        },
        [&] {
          node.right_box = right_kept ? emit(split + 1, split + 1, last, right_base, self << 1 | 1)
                                      : leaf_range_box(split + 1, last, boxes, sorted_prims, leaf_groups);
        });
    nodes[self] = node;
    return box_union(node.left_box, node.right_box);
  }
};

// The node records of the tree over n >= 2 sorted keys with their boxes, and the leaf groups
// (box_group_count(n) of them): TopDownBuild's two passes, its per-node records in `info`.
template <class Boxes>
void build_nodes(const uint64_t* keys, int32_t n, int32_t leaf_size, Boxes boxes, const int32_t* sorted_prims,
                 HostVector<BvhNode>& nodes, BoxGroup* leaf_groups, HostVector<uint64_t>& info) {
  info.resize(size_t(n - 1));
  TopDownBuild<Boxes> build{keys, n, leaf_size, boxes, sorted_prims, info.data(), nullptr, leaf_groups};
  nodes.resize(size_t(build.count(0, 0, n - 1)));
  build.nodes = nodes.data();
  build.emit(0, 0, n - 1, 0, -1);
}
template <class Boxes>
void build_nodes(const uint64_t* keys, int32_t n, int32_t leaf_size, Boxes boxes, const int32_t* sorted_prims,
                 HostVector<BvhNode>& nodes, BoxGroup* leaf_groups) {
  HostVector<uint64_t> info;
  build_nodes(keys, n, leaf_size, boxes, sorted_prims, nodes, leaf_groups, info);
}

// tree.h's bottom-up refit from every child slot of `nodes` in parallel (the arrival counters,
// one per node, zeroed first): the leaf groups and every node's child boxes from boxes().
// Nodes, Arrivals: vectors of BvhNode and int32_t (the studies' trees keep std::vectors).
template <class Boxes, class Nodes, class Arrivals>
void refit_slots(Boxes boxes, Nodes& nodes, const int32_t* sorted_prims, BoxGroup* leaf_groups, Arrivals& arrivals) {
  std::fill(arrivals.begin(), arrivals.end(), 0);
  parallel_for_each(int64_t(nodes.size()) * 2, [&](int64_t slot) {
    refit_from_slot(int32_t(slot), boxes, sorted_prims, leaf_groups, nodes.data(), arrivals.data());
  });
}

class CpuTree {
 public:
  const HostVector<BvhNode>& nodes() const { return nodes_; }
  // Primitive at each sorted leaf position.
  const HostVector<int32_t>& sorted_prims() const { return sorted_prims_; }

  // Builds the tree over boxes(0..n-1): each box evaluated once, the primitives sorted by
  // the Morton codes of the box centres, then the kept nodes with their boxes (build_nodes).
  template <class Boxes>
  void build(Boxes boxes, int32_t n, const BuildConfig& config = {}) {
    static_assert(BoxesContract<Boxes>::value, "a build reads its boxes from a Boxes functor (bvh.h)");
    BuildScratch local;
    BuildScratch& s = reserved_ ? scratch_ : local;
    if (n > 1) sort_by_morton(boxes, n, s.order, s.sort); else element_boxes(boxes, n, s.sort.element);
    build_over(s.sort.keys, s.order, s, config);
  }

  // The same over primitives already in leaf order: sorted_prims[p] is the primitive at leaf
  // position p and keys[p] its 63-bit key, ascending (ties in position order); for n <= 1
  // both may be empty. build() is this with Morton codes.
  template <class Boxes>
  void build_sorted(Boxes boxes, const HostVector<uint64_t>& keys, HostVector<int32_t> sorted_prims, int32_t n,
                    const BuildConfig& config = {}) {
    BuildScratch local;
    BuildScratch& s = reserved_ ? scratch_ : local;
    element_boxes(boxes, n, s.sort.element);
    build_over(keys, sorted_prims, s, config);
  }

  // Keeps the scratch of builds over n primitives from now on (BuildScratch), so that rebuilds
  // of that size allocate nothing; bytes() counts it.
  void reserve_build(int32_t n) {
    scratch_.reserve(n);
    sorted_prims_.reserve(size_t(std::max(n, 0)));  // swapped with the scratch's order by each build
    reserved_ = true;
  }

  template <class Boxes>
  void refit(Boxes boxes) {
    refit_slots(boxes, nodes_, sorted_prims_.data(), leaf_groups_.data(), arrivals_);
  }

  // The tree's area cost (cost.h's area_cost).
  double area_cost() const { return minkq::area_cost(nodes_.data(), int64_t(nodes_.size())); }
  // area_cost() right after the last build.
  double cost_at_build() const { return cost_at_build_; }

  BvhView view() const { return {nodes_.data(), leaf_groups_.data(), sorted_prims_.data(), n_}; }
  // The box of the primitive at sorted position p, and all of them in groups of four.
  Box leaf_box(int32_t p) const { return group_box(leaf_groups_[size_t(p >> 2)], p & 3); }
  const BoxGroup* leaf_groups() const { return leaf_groups_.data(); }
  int32_t size() const { return n_; }
  // Bytes held: node records with their refit counters, per primitive its id and box in leaf
  // order (boxes in groups of four: up to three unused lanes), and the build scratch once
  // reserved.
  size_t bytes() const {
    return nodes_.size() * (sizeof(BvhNode) + sizeof(int32_t)) + size_t(n_) * sizeof(int32_t) +
           leaf_groups_.size() * sizeof(BoxGroup) + (reserved_ ? scratch_.bytes() : 0);
  }

 private:
  // build_sorted() over the primitives' boxes in s.sort.element (element i: primitive i's), with
  // sorted_prims taken as the leaf order (its vector swapped with the tree's last one).
  void build_over(const HostVector<uint64_t>& keys, HostVector<int32_t>& sorted_prims, BuildScratch& s,
                  const BuildConfig& config) {
    const int32_t n = int32_t(s.sort.element.size());
    n_ = n;
    cost_at_build_ = 0.0;
    sorted_prims_.swap(sorted_prims);
    if (n <= 1) sorted_prims_.assign(size_t(n), 0);
    // Every lane below n is written below; the lanes past the last primitive stay zero.
    leaf_groups_.resize(size_t(box_group_count(n)));
    if (n > 0) leaf_groups_.back() = BoxGroup{};
    const GivenBoxes boxes{s.sort.element.data()};
    if (n <= 1) nodes_.assign(size_t(n), one_leaf_root());
    else build_nodes(keys.data(), n, config.leaf_size, boxes, sorted_prims_.data(), nodes_, leaf_groups_.data(),
                     s.sort.radix.keys);
    arrivals_.assign(nodes_.size(), 0);
    if (n == 1) refit(boxes);
    cost_at_build_ = area_cost();
  }

  int32_t n_ = 0;
  double cost_at_build_ = 0.0;
  HostVector<BvhNode> nodes_;
  HostVector<int32_t> arrivals_;
  HostVector<int32_t> sorted_prims_;
  HostVector<BoxGroup> leaf_groups_;  // box of the primitive at sorted position p: lane p % 4 of group p / 4
  bool reserved_ = false;
  BuildScratch scratch_;  // kept once reserved
};

}  // namespace minkq
