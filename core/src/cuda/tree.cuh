// The CUDA tree: tree.h's per-element build and refit steps, one thread per element, with
// CUB's radix sort and reductions; the counterpart of cpu/tree.h, whose trees it matches bit
// for bit. Included by cuda/backend.cu only.
#pragma once

#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_reduce.cuh>
#include <cub/device/device_scan.cuh>
#include <thrust/iterator/counting_iterator.h>

#include "cuda/runtime.cuh"
#include "minkq/tree.h"

namespace minkq::cuda {

struct BoxUnion {
  __host__ __device__ Box operator()(const Box& a, const Box& b) const { return box_union(a, b); }
};

// Primitive i's centre as a point box: reduced with BoxUnion, this is the CPU's box_expand.
template <class Boxes>
struct CentreBox {
  Boxes boxes;
  __host__ __device__ Box operator()(int32_t i) const { return Box::of_point(box_centre(boxes(i))); }
};

template <class Boxes>
static __global__ void morton_kernel(Boxes boxes, int32_t n, const Box* centre_bounds, uint64_t* keys, int32_t* ids) {
  const int64_t i = global_index();
  if (i >= n) return;
  keys[i] = morton_code(morton_frame(*centre_bounds), box_centre(boxes(int32_t(i))));
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

template <class Boxes>
static __global__ void refit_kernel(Boxes boxes, int32_t num_nodes, const int32_t* sorted_prims, BoxGroup* leaf_groups,
                                    BvhNode* nodes, int32_t* arrivals) {
  const int64_t slot = global_index();
  if (slot < 2 * int64_t(num_nodes)) refit_from_slot(int32_t(slot), boxes, sorted_prims, leaf_groups, nodes, arrivals);
}

// Ids 0..n-1 sorted by the Morton code of their box centres, ties broken by id: cpu/tree.h's
// sort_by_morton on the device.
template <class Boxes>
void sort_by_morton(Boxes boxes, int32_t n, DeviceBuffer<uint64_t>& sorted_keys, DeviceBuffer<int32_t>& sorted_ids) {
  sorted_keys.ensure(size_t(n));
  sorted_ids.ensure(size_t(n));
  if (n == 0) return;
  // Bounds of the centres: min/max are exact, so the reduction order does not matter.
  DeviceBuffer<Box> centre_bounds(1);
  DeviceBuffer<char> temp;
  const thrust::counting_iterator<int32_t> ids(0);
  run_cub(temp, "cub::DeviceReduce::TransformReduce", [&](void* storage, size_t& bytes) {
    return cub::DeviceReduce::TransformReduce(storage, bytes, ids, centre_bounds.data(), n, BoxUnion{},
                                              CentreBox<Boxes>{boxes}, Box::empty(), kStream);
  });
  DeviceBuffer<uint64_t> keys(n);
  DeviceBuffer<int32_t> order(n);
  launch("morton_kernel launch", morton_kernel<Boxes>, n, kThreads, boxes, n, centre_bounds.data(), keys.data(),
         order.data());
  // LSD radix sort is stable and the values start as 0..n-1: ties are broken by index, as in
  // the CPU's sort of (key, index) pairs. Morton codes use the low 63 bits.
  run_cub(temp, "cub::DeviceRadixSort::SortPairs", [&](void* storage, size_t& bytes) {
    return cub::DeviceRadixSort::SortPairs(storage, bytes, keys.data(), sorted_keys.data(), order.data(),
                                           sorted_ids.data(), n, 0, 63, kStream);
  });
}

struct NodeArea {
  const BvhNode* nodes;
  __host__ __device__ double operator()(int32_t i) const { return node_area(nodes[i]); }
};
struct DoubleSum {
  __host__ __device__ double operator()(double a, double b) const { return a + b; }
};

// CpuTree::build step by step.
class CudaTree {
 public:
  template <class Boxes>
  void build(Boxes boxes, int32_t n, const BuildConfig& config = {}) {
    n_ = n;
    sorted_prims_.ensure(size_t(n));
    leaf_groups_.ensure(size_t(box_group_count(n)));
    zero(sorted_prims_, size_t(n));
    num_nodes_ = 0;
    cost_at_build_ = 0.0;
    if (n == 0) return;
    if (n == 1) {
      const BvhNode root = one_leaf_root();
      num_nodes_ = 1;
      nodes_.ensure(1);
      arrivals_.ensure(1);
      copy(nodes_.data(), &root, sizeof(root), cudaMemcpyHostToDevice);
      refit(boxes);
      cost_at_build_ = area_cost();
      return;
    }
    DeviceBuffer<uint64_t> sorted_keys;
    sort_by_morton(boxes, n, sorted_keys, sorted_prims_);
    DeviceBuffer<KarrasNode> karras(size_t(n - 1));
    DeviceBuffer<int32_t> kept(size_t(n - 1)), new_index(size_t(n - 1));
    launch("karras_kernel launch", karras_kernel, n - 1, kThreads, sorted_keys.data(), n, config.leaf_size, karras.data(),
           kept.data());
    DeviceBuffer<char> temp;
    run_cub(temp, "cub::DeviceScan::ExclusiveSum", [&](void* storage, size_t& bytes) {
      return cub::DeviceScan::ExclusiveSum(storage, bytes, kept.data(), new_index.data(), n - 1, kStream);
    });
    int32_t last_index = 0, last_kept = 0;
    copy(&last_index, new_index.data() + (n - 2), sizeof(int32_t), cudaMemcpyDeviceToHost);
    copy(&last_kept, kept.data() + (n - 2), sizeof(int32_t), cudaMemcpyDeviceToHost);
    num_nodes_ = last_index + last_kept;
    nodes_.ensure(size_t(num_nodes_));
    arrivals_.ensure(size_t(num_nodes_));
    zero(nodes_, size_t(num_nodes_));
    launch("collapse_kernel launch", collapse_kernel, n - 1, kThreads, karras.data(), new_index.data(), n,
           config.leaf_size, nodes_.data());
    refit(boxes);
    cost_at_build_ = area_cost();
  }

  template <class Boxes>
  void refit(Boxes boxes) {
    zero(arrivals_, size_t(num_nodes_));
    launch("refit_kernel launch", refit_kernel<Boxes>, int64_t(num_nodes_) * 2, kThreads, boxes, num_nodes_,
           sorted_prims_.data(), leaf_groups_.data(), nodes_.data(), arrivals_.data());
  }

  // CpuTree::area_cost, summed by a device reduction: equal up to rounding.
  double area_cost() const {
    if (num_nodes_ == 0) return 0.0;
    BvhNode root;
    copy(&root, nodes_.data(), sizeof(root), cudaMemcpyDeviceToHost);
    const double root_area = root_half_area(root);
    if (!(root_area > 0.0)) return 0.0;
    area_sum_.ensure(1);
    const thrust::counting_iterator<int32_t> ids(0);
    run_cub(area_temp_, "cub::DeviceReduce::TransformReduce", [&](void* storage, size_t& bytes) {
      return cub::DeviceReduce::TransformReduce(storage, bytes, ids, area_sum_.data(), num_nodes_, DoubleSum{},
                                                NodeArea{nodes_.data()}, 0.0, kStream);
    });
    double total = 0.0;
    copy(&total, area_sum_.data(), sizeof(total), cudaMemcpyDeviceToHost);
    return total / root_area;
  }
  double cost_at_build() const { return cost_at_build_; }

  BvhView view() const { return {nodes_.data(), leaf_groups_.data(), sorted_prims_.data(), n_}; }

 private:
  int32_t n_ = 0;
  double cost_at_build_ = 0.0;
  int32_t num_nodes_ = 0;
  DeviceBuffer<BvhNode> nodes_;
  DeviceBuffer<int32_t> arrivals_;
  DeviceBuffer<int32_t> sorted_prims_;  // primitive at each sorted leaf position
  DeviceBuffer<BoxGroup> leaf_groups_;  // box of the primitive at sorted position p: lane p % 4 of group p / 4
  // area_cost()'s scratch, kept: growth is asked for every step, and a cudaFree would wait for
  // the whole GPU.
  mutable DeviceBuffer<double> area_sum_;
  mutable DeviceBuffer<char> area_temp_;
};


}  // namespace minkq::cuda
