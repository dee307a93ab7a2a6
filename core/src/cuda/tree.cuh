// The CUDA tree: the per-element build and refit steps, one thread per element, with
// CUB's radix sort, scan and reductions; the counterpart of cpu/tree.h, whose trees it matches bit
// for bit. Included by cuda/backend.cu only.
#pragma once

#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_reduce.cuh>
#include <cub/device/device_scan.cuh>
#include <thrust/iterator/counting_iterator.h>

#include "cuda/runtime.cuh"
#include "minkq/build.h"
#include "minkq/cost.h"
#include "minkq/morton.h"
#include "minkq/refit.h"

namespace minkq::cuda {

struct BoxUnion {
  __host__ __device__ Box operator()(const Box& a, const Box& b) const { return box_union(a, b); }
};

// Element i's centre as a point box: reduced with BoxUnion, this is the CPU's box_expand.
struct CentreBox {
  const Box* boxes;  // the element boxes, evaluated once
  __host__ __device__ Box operator()(int32_t i) const { return Box::of_point(box_centre(boxes[i])); }
};

// Every element's box once (cpu/tree.h's element_boxes): the build reads them from `out`.
template <class Boxes>
static __global__ void element_boxes_kernel(Boxes boxes, int32_t n, Box* out) {
  static_assert(!by_leaf_position<Boxes>, "a build reads its elements by id");
  const int64_t i = global_index();
  if (i < n) out[i] = boxes(int32_t(i));
}

static __global__ void morton_kernel(const Box* boxes, int32_t n, const Box* centre_bounds, uint64_t* keys, int32_t* ids) {
  const int64_t i = global_index();
  if (i >= n) return;
  keys[i] = morton_code(morton_frame(*centre_bounds), box_centre(boxes[i]));
  ids[i] = int32_t(i);
}

static __global__ void karras_kernel(const uint64_t* keys, int32_t n, int32_t leaf_size, KarrasNode* karras,
                                     int32_t* kept) {
  const int64_t i = global_index();
  if (i >= n - 1) return;
  karras[i] = karras_node(int32_t(i), keys, n);
  kept[i] = keeps_node(int32_t(i), karras[i], leaf_size) ? 1 : 0;
}

static __global__ void collapse_kernel(const KarrasNode* karras, const int32_t* new_index, int32_t n,
                                       int32_t leaf_size, BvhNode* nodes) {
  const int64_t i = global_index();
  if (i < n - 1 && keeps_node(int32_t(i), karras[i], leaf_size))
    collapse_node(int32_t(i), karras, new_index, leaf_size, nodes);
}

// The refit's two passes over the nodes that exist (*num_nodes of them, counted on the device),
// each a grid-stride loop: the launch does not depend on the node count, which a later build
// may change under a captured refit. Zeroes the arrival flags; then every child slot, in any
// order (refit_from_slot never waits for another thread).
static __global__ void zero_arrivals_kernel(const int32_t* num_nodes, int32_t* arrivals) {
  for (int64_t i = global_index(); i < *num_nodes; i += int64_t(gridDim.x) * blockDim.x) arrivals[i] = 0;
}
template <class Boxes>
static __global__ void refit_kernel(Boxes boxes, const int32_t* num_nodes, const int32_t* sorted_prims,
                                    BoxGroup* leaf_groups, BvhNode* nodes, int32_t* arrivals) {
  const int64_t slots = 2 * int64_t(*num_nodes);
  for (int64_t slot = global_index(); slot < slots; slot += int64_t(gridDim.x) * blockDim.x)
    refit_from_slot(int32_t(slot), boxes, sorted_prims, leaf_groups, nodes, arrivals);
}

// The node count of a build: the kept Karras nodes (n >= 2), or the one-leaf root (n == 1).
static __global__ void count_nodes_kernel(const int32_t* new_index, const int32_t* kept, int32_t n, int32_t* num_nodes) {
  *num_nodes = new_index[n - 2] + kept[n - 2];
}
static __global__ void one_leaf_kernel(BvhNode* nodes, int32_t* num_nodes) {
  nodes[0] = one_leaf_root();
  *num_nodes = 1;
}

// What a Morton sort needs besides its output; kept by a tree (or executor) that has reserved
// it, else made for one build and freed after.
struct SortScratch {
  DeviceBuffer<Box> boxes;  // every element's box, evaluated once
  DeviceBuffer<Box> centre_bounds;
  DeviceBuffer<uint64_t> keys, sorted_keys;  // sorted_keys: the build's input
  DeviceBuffer<int32_t> order;
  DeviceBuffer<char> temp;
};

// The CUB calls of a build, each run twice by run_cub (to size, then to run) and sized alone
// by reserve(): the same arguments either way.
inline cudaError_t reduce_centre_bounds(void* storage, size_t& bytes, const Box* boxes, int32_t n, Box* out) {
  const thrust::counting_iterator<int32_t> ids(0);
  return cub::DeviceReduce::TransformReduce(storage, bytes, ids, out, n, BoxUnion{},
                                            CentreBox{boxes}, Box::empty(), stream());
}
// LSD radix sort is stable and the values start as 0..n-1: ties are broken by index, as in the
// CPU's stable radix sort (cpu/radix_sort.h). Morton codes use the low 63 bits.
inline cudaError_t sort_morton_pairs(void* storage, size_t& bytes, SortScratch& s, int32_t* sorted_ids, int32_t n) {
  return cub::DeviceRadixSort::SortPairs(storage, bytes, s.keys.data(), s.sorted_keys.data(), s.order.data(),
                                         sorted_ids, n, 0, 63, stream());
}
inline cudaError_t scan_kept(void* storage, size_t& bytes, const int32_t* kept, int32_t* new_index, int32_t n) {
  return cub::DeviceScan::ExclusiveSum(storage, bytes, kept, new_index, n, stream());
}

// Sizes `s` for Morton sorts of n elements (their boxes evaluated once into s.boxes first, so
// the element type does not matter), kept from then on.
inline void reserve_sort(SortScratch& s, int32_t n) {
  s.boxes.ensure(size_t(n));
  s.centre_bounds.ensure(1);
  s.keys.ensure(size_t(n));
  s.sorted_keys.ensure(size_t(n));
  s.order.ensure(size_t(n));
  size_t reduce_bytes = 0, sort_bytes = 0;
  check(reduce_centre_bounds(nullptr, reduce_bytes, nullptr, n, nullptr), "cub::DeviceReduce::TransformReduce");
  check(sort_morton_pairs(nullptr, sort_bytes, s, nullptr, n), "cub::DeviceRadixSort::SortPairs");
  s.temp.ensure(std::max<size_t>({reduce_bytes, sort_bytes, 1}));
}

// Ids 0..n-1 sorted by the Morton code of their box centres, ties broken by id: cpu/tree.h's
// sort_by_morton on the device, the sorted codes in s.sorted_keys and each element's box, once
// evaluated, in s.boxes.
template <class Boxes>
void sort_by_morton(Boxes boxes, int32_t n, SortScratch& s, DeviceBuffer<int32_t>& sorted_ids) {
  sorted_ids.ensure(size_t(n));
  if (n == 0) return;
  s.boxes.ensure(size_t(n));
  s.centre_bounds.ensure(1);
  s.keys.ensure(size_t(n));
  s.sorted_keys.ensure(size_t(n));
  s.order.ensure(size_t(n));
  // Bounds of the centres: min/max are exact, so the reduction order does not matter.
  launch("element_boxes_kernel launch", element_boxes_kernel<Boxes>, n, kThreads, boxes, n, s.boxes.data());
  run_cub(s.temp, "cub::DeviceReduce::TransformReduce", [&](void* storage, size_t& bytes) {
    return reduce_centre_bounds(storage, bytes, s.boxes.data(), n, s.centre_bounds.data());
  });
  launch("morton_kernel launch", morton_kernel, n, kThreads, s.boxes.data(), n, s.centre_bounds.data(), s.keys.data(),
         s.order.data());
  run_cub(s.temp, "cub::DeviceRadixSort::SortPairs",
          [&](void* storage, size_t& bytes) { return sort_morton_pairs(storage, bytes, s, sorted_ids.data(), n); });
}

// Node i's term of the area cost, for the nodes that exist (0 past *num_nodes).
struct NodeArea {
  const BvhNode* nodes;
  const int32_t* num_nodes;
  __device__ double operator()(int32_t i) const { return i < *num_nodes ? node_area(nodes[i]) : 0.0; }
};
struct DoubleSum {
  __host__ __device__ double operator()(double a, double b) const { return a + b; }
};
inline cudaError_t sum_node_areas(void* storage, size_t& bytes, const BvhNode* nodes, const int32_t* num_nodes,
                                  int32_t capacity, double* out) {
  const thrust::counting_iterator<int32_t> ids(0);
  return cub::DeviceReduce::TransformReduce(storage, bytes, ids, out, capacity, DoubleSum{}, NodeArea{nodes, num_nodes},
                                            0.0, stream());
}
// *cost = *sum over the root's half area (0 without nodes or area): tree.h's area_cost.
static __global__ void area_cost_kernel(const BvhNode* nodes, const int32_t* num_nodes, const double* sum, double* cost) {
  double value = 0.0;
  if (*num_nodes > 0) {
    const double root = root_half_area(nodes[0]);
    if (root > 0.0) value = *sum / root;
  }
  *cost = value;
}

// CpuTree::build step by step. Node records and arrival flags: until reserve_nodes(), a build
// reads its node count back once the kept flags are scanned (the collapse has not run yet) and
// grows them to grown_node_room (build.h) when they would not fit; a blocking call may move
// them. reserve_nodes() sizes them for the most any build over n primitives keeps
// (max_node_count) and no build moves them after, so a build enqueued by a stream-ordered call
// never reads back or allocates, and a refit or query recorded into a CUDA graph stays valid
// across rebuilds that keep more nodes. The refit and area kernels cover the nodes that exist
// (counted on the device) over the room allocated. A build's scratch is kept once
// reserve_build() has sized it (the build then enqueues its work without allocating), else
// made and freed.
class CudaTree {
 public:
  template <class Boxes>
  void build(Boxes boxes, int32_t n, const BuildConfig& config = {}) {
    static_assert(BoxesContract<Boxes>::value, "a build reads its boxes from a Boxes functor (bvh.h)");
    n_ = n;
    sorted_prims_.ensure(size_t(n));
    leaf_groups_.ensure(size_t(box_group_count(n)));
    counts_.ensure(1);
    costs_.ensure(3);
    size_once();
    zero(sorted_prims_, size_t(n));
    zero(counts_, 1);
    if (n == 0) {
      zero(costs_, 3);
      return;
    }
    if (n == 1) {
      grow_nodes(1);
      launch("one_leaf_kernel launch", one_leaf_kernel, 1, 1, nodes_.data(), counts_.data());
      refit(boxes);
      store_cost(costs_.data() + kCostAtBuild);
      return;
    }
    BuildScratch local;
    BuildScratch& s = reserved_ ? scratch_ : local;
    sort_by_morton(boxes, n, s.sort, sorted_prims_);
    s.karras.ensure(size_t(n - 1));
    s.kept.ensure(size_t(n - 1));
    s.new_index.ensure(size_t(n - 1));
    launch("karras_kernel launch", karras_kernel, n - 1, kThreads, s.sort.sorted_keys.data(), n, config.leaf_size,
           s.karras.data(), s.kept.data());
    run_cub(s.sort.temp, "cub::DeviceScan::ExclusiveSum", [&](void* storage, size_t& bytes) {
      return scan_kept(storage, bytes, s.kept.data(), s.new_index.data(), n - 1);
    });
    launch("count_nodes_kernel launch", count_nodes_kernel, 1, 1, s.new_index.data(), s.kept.data(), n, counts_.data());
    fit_nodes(n);
    launch("collapse_kernel launch", collapse_kernel, n - 1, kThreads, s.karras.data(), s.new_index.data(), n,
           config.leaf_size, nodes_.data());
    refit(GivenBoxes{s.sort.boxes.data()});  // the boxes evaluated once by the sort
    store_cost(costs_.data() + kCostAtBuild);
  }

  // Keeps the scratch of builds over n primitives from now on, so that builds enqueue their
  // work without allocating.
  void reserve_build(int32_t n) {
    const int32_t inner = std::max(n - 1, 1);
    reserve_nodes(n);
    reserve_sort(scratch_.sort, n);
    scratch_.karras.ensure(size_t(inner));
    scratch_.kept.ensure(size_t(inner));
    scratch_.new_index.ensure(size_t(inner));
    size_t scan_bytes = 0;
    check(scan_kept(nullptr, scan_bytes, nullptr, nullptr, inner), "cub::DeviceScan::ExclusiveSum");
    scratch_.sort.temp.ensure(std::max(scan_bytes, scratch_.sort.temp.size()));
    reserved_ = true;
  }

  // Node records and arrival flags for every build over n primitives (max_node_count), kept
  // from now on: no later build reads its count back or moves them.
  void reserve_nodes(int32_t n) {
    size_once();
    grow_nodes(max_node_count(n));
    nodes_reserved_ = true;
  }

  // Enqueued; covers the nodes counted on the device (nodes past the count are never read).
  template <class Boxes>
  void refit(Boxes boxes) {
    if (node_capacity_ == 0) return;
    launch("zero_arrivals_kernel launch", zero_arrivals_kernel, std::min<int64_t>(node_capacity_, max_threads_),
           kThreads, counts_.data(), arrivals_.data());
    launch("refit_kernel launch", refit_kernel<Boxes>, std::min<int64_t>(2 * int64_t(node_capacity_), max_threads_),
           kThreads, boxes, counts_.data(), sorted_prims_.data(), leaf_groups_.data(), nodes_.data(), arrivals_.data());
  }

  // CpuTree::area_cost, summed by a device reduction: equal up to rounding (a blocking call).
  double area_cost() const {
    if (node_capacity_ == 0) return 0.0;
    store_cost(costs_.data() + kCostNow);
    return read_cost(kCostNow);
  }
  double cost_at_build() const { return node_capacity_ == 0 ? 0.0 : read_cost(kCostAtBuild); }

  BvhView view() const { return {nodes_.data(), leaf_groups_.data(), sorted_prims_.data(), n_}; }

 private:
  struct BuildScratch {
    SortScratch sort;  // its temp also serves the scan
    DeviceBuffer<KarrasNode> karras;
    DeviceBuffer<int32_t> kept, new_index;
  };
  enum : int { kCostAtBuild = 0, kCostNow = 1, kAreaSum = 2 };  // costs_ entries

  // The area cost of the tree as it is now into *cost (device memory), enqueued.
  void store_cost(double* cost) const {
    run_cub(area_temp_, "cub::DeviceReduce::TransformReduce", [&](void* storage, size_t& bytes) {
      return sum_node_areas(storage, bytes, nodes_.data(), counts_.data(), node_capacity_, costs_.data() + kAreaSum);
    });
    launch("area_cost_kernel launch", area_cost_kernel, 1, 1, nodes_.data(), counts_.data(), costs_.data() + kAreaSum,
           cost);
  }
  double read_cost(int entry) const {
    double value = 0.0;
    copy(&value, costs_.data() + entry, sizeof(value), cudaMemcpyDeviceToHost);
    return value;
  }

  // Room for the nodes a build over n >= 2 primitives keeps, before its collapse writes them:
  // unless reserved, the count the scan left in counts_[0], read back (a blocking build).
  void fit_nodes(int32_t n) {
    if (nodes_reserved_) return grow_nodes(max_node_count(n));  // no-op but for a larger n
    int32_t kept = 0;
    copy(&kept, counts_.data(), sizeof(kept), cudaMemcpyDeviceToHost);
    grow_nodes(grown_node_room(node_capacity_, kept, n));
  }
  // Node records, arrival flags and the area reduction's scratch for `room` nodes (never fewer
  // than already held).
  void grow_nodes(int32_t room) {
    if (room <= node_capacity_) return;
    nodes_.ensure(size_t(room));
    arrivals_.ensure(size_t(room));
    size_t area_bytes = 0;
    check(sum_node_areas(nullptr, area_bytes, nullptr, nullptr, room, nullptr), "cub::DeviceReduce::TransformReduce");
    area_temp_.ensure(std::max<size_t>(area_bytes, 1));
    node_capacity_ = room;
  }
  // The refit's grid at most: the threads the device holds at once.
  void size_once() {
    if (sized_) return;
    max_threads_ = resident_threads();
    sized_ = true;
  }

  int32_t n_ = 0;
  int32_t node_capacity_ = 0;  // node records and arrival flags held, those that exist counted in counts_[0]
  int64_t max_threads_ = 1;    // the refit's grid at most: the threads the device holds at once
  bool sized_ = false, reserved_ = false, nodes_reserved_ = false;
  DeviceBuffer<BvhNode> nodes_;
  DeviceBuffer<int32_t> arrivals_;
  DeviceBuffer<int32_t> counts_;  // [0]: the number of nodes
  // [kCostAtBuild]: the area cost right after the last build; [kCostNow], [kAreaSum]: area_cost()'s.
  mutable DeviceBuffer<double> costs_;
  DeviceBuffer<int32_t> sorted_prims_;  // primitive at each sorted leaf position
  DeviceBuffer<BoxGroup> leaf_groups_;  // box of the primitive at sorted position p: lane p % 4 of group p / 4
  BuildScratch scratch_;                // kept once reserved
  // The area reduction's scratch, kept: growth is asked for every step, and a cudaFree would
  // wait for the whole GPU.
  mutable DeviceBuffer<char> area_temp_;
};


}  // namespace minkq::cuda
