// CUDA backend: the same per-element steps of bvh.h and queries.h as the CPU backend, one
// thread per element, so trees are bit-identical and candidate sets equal. All work runs on
// the per-thread default stream, so scenes used from different host threads do not serialise
// on the legacy stream; every host read of device results synchronises that stream first.
#include <cuda_runtime.h>

#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_reduce.cuh>
#include <cub/device/device_scan.cuh>
#include <cooperative_groups.h>
#include <cooperative_groups/scan.h>
#include <thrust/iterator/counting_iterator.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <limits>
#include <tuple>
#include <type_traits>
#include <utility>

#include "backend.h"

namespace minkq {
namespace {

namespace cg = cooperative_groups;

const cudaStream_t kStream = cudaStreamPerThread;
constexpr int kThreads = 256;       // element-wise kernels
constexpr int kQueryThreads = 128;  // traversal: divergent, local-memory stack per thread

// ---- Errors and memory ------------------------------------------------------------------------

void check(cudaError_t error, const char* call) {
  if (error == cudaSuccess) return;
  cudaGetLastError();  // clear a non-sticky error so it is not reported again by a later call
  fail(error == cudaErrorMemoryAllocation ? Status::kOutOfMemory : Status::kDevice,
       std::string(call) + " failed: " + cudaGetErrorString(error));
}

// Makes a device the calling thread's current one and gives the caller's device back on
// leave() or destruction, so an application driving another GPU from the same thread is not
// moved to ours.
class DeviceSwitch {
 public:
  DeviceSwitch() = default;
  DeviceSwitch(const DeviceSwitch&) = delete;
  DeviceSwitch& operator=(const DeviceSwitch&) = delete;
  ~DeviceSwitch() { leave(); }
  // Returns the runtime's error (a destructor cannot report it; other callers check it); on
  // one, nothing is switched.
  cudaError_t enter(int ordinal) noexcept {
    leave();
    int previous = 0;
    if (const cudaError_t error = cudaGetDevice(&previous); error != cudaSuccess) return error;
    if (previous != ordinal)
      if (const cudaError_t error = cudaSetDevice(ordinal); error != cudaSuccess) return error;
    previous_ = previous, ordinal_ = ordinal;
    return cudaSuccess;
  }
  void leave() noexcept {
    if (previous_ != ordinal_) cudaSetDevice(previous_);  // cannot be reported
    previous_ = ordinal_ = -1;
  }

 private:
  int previous_ = -1, ordinal_ = -1;
};

// The device of one library call, declared before the call's device buffers so that it
// outlives them.
class DeviceScope {
 public:
  explicit DeviceScope(int ordinal) { check(switch_.enter(ordinal), "cudaGetDevice / cudaSetDevice"); }

 private:
  DeviceSwitch switch_;
};

// Owns one cudaMalloc allocation of `size` elements (none when empty).
template <class T>
class DeviceBuffer {
 public:
  DeviceBuffer() = default;
  explicit DeviceBuffer(size_t count) { ensure(count); }
  DeviceBuffer(const DeviceBuffer&) = delete;
  DeviceBuffer& operator=(const DeviceBuffer&) = delete;
  DeviceBuffer(DeviceBuffer&& other) noexcept
      : data_(std::exchange(other.data_, nullptr)), size_(std::exchange(other.size_, 0)) {}
  DeviceBuffer& operator=(DeviceBuffer&& other) noexcept {
    std::swap(data_, other.data_);
    std::swap(size_, other.size_);
    return *this;
  }
  ~DeviceBuffer() { release(); }

  // Room for at least `count` elements; the contents are not kept when it has to grow.
  void ensure(size_t count) {
    if (count <= size_) return;
    if (count > std::numeric_limits<size_t>::max() / sizeof(T))
      fail(Status::kOutOfMemory, "device allocation size overflows");
    release();  // free first: growing must not need the old and the new block at once
    T* data = nullptr;  // kept only on success: a failed cudaMalloc leaves nothing to free
    check(cudaMalloc(reinterpret_cast<void**>(&data), count * sizeof(T)), "cudaMalloc");
    data_ = data;
    size_ = count;
  }
  T* data() const { return data_; }
  size_t size() const { return size_; }

 private:
  void release() {
    if (data_) cudaFree(data_);  // a destructor cannot report; a failed free only leaks
    data_ = nullptr;
    size_ = 0;
  }
  T* data_ = nullptr;
  size_t size_ = 0;
};

// cudaMemcpy on our stream, complete on return (the host may reuse or read its side at once).
void copy(void* dst, const void* src, size_t bytes, cudaMemcpyKind kind) {
  if (bytes == 0) return;
  check(cudaMemcpyAsync(dst, src, bytes, kind, kStream), "cudaMemcpyAsync");
  check(cudaStreamSynchronize(kStream), "cudaStreamSynchronize");
}

template <class T>
void zero(DeviceBuffer<T>& buffer, size_t count) {
  if (count) check(cudaMemsetAsync(buffer.data(), 0, count * sizeof(T), kStream), "cudaMemsetAsync");
}

template <class T>
void upload(DeviceBuffer<T>& dst, const T* src, size_t count) {
  dst.ensure(count);
  copy(dst.data(), src, count * sizeof(T), cudaMemcpyHostToDevice);
}

// One thread per element i < n.
template <class Kernel, class... Args>
void launch(const char* name, Kernel kernel, int64_t n, int threads, Args... args) {
  if (n <= 0) return;
  kernel<<<unsigned((n + threads - 1) / threads), threads, 0, kStream>>>(args...);
  check(cudaGetLastError(), name);
}

__device__ int64_t global_index() { return int64_t(blockIdx.x) * blockDim.x + threadIdx.x; }

// ---- Strided input ------------------------------------------------------------------------

// Float k of a record. Caller-supplied strides need only be 4-aligned; anything less aligned
// is read byte by byte.
__device__ float load_float(const char* record, int k, bool aligned) {
  if (aligned) return reinterpret_cast<const float*>(record)[k];
  unsigned char bytes[4];
  for (int b = 0; b < 4; ++b) bytes[b] = static_cast<unsigned char>(record[4 * k + b]);
  float f;
  memcpy(&f, bytes, 4);
  return f;
}

bool is_aligned4(const Strided& values) {
  return (reinterpret_cast<uintptr_t>(values.data) % 4 == 0) && values.stride % 4 == 0;
}

__global__ void gather_kernel(const char* base, size_t stride, int64_t n, int floats, bool aligned,
                              float* out) {
  const int64_t i = global_index();
  if (i >= n) return;
  const char* record = base + size_t(i) * stride;
  for (int k = 0; k < floats; ++k) out[i * floats + k] = load_float(record, k, aligned);
}

__global__ void first_non_finite_kernel(const char* base, size_t stride, int64_t n, int floats, bool aligned,
                                        unsigned long long* first) {
  const int64_t i = global_index();
  if (i >= n) return;
  const char* record = base + size_t(i) * stride;
  for (int k = 0; k < floats; ++k)
    if (!isfinite(load_float(record, k, aligned))) {
      atomicMin(first, static_cast<unsigned long long>(i));
      return;
    }
}

// Packs strided Vec3 or Box records (host or device memory) into a device array.
template <class T>
void gather_to_device(const Strided& values, DeviceBuffer<T>& dst) {
  static_assert(std::is_same<T, Vec3>::value || std::is_same<T, Box>::value, "float records only");
  const size_t count = size_t(values.count);
  dst.ensure(count);
  if (count == 0) return;
  if (values.memory == Memory::kHost) {
    if (values.stride == sizeof(T)) return upload(dst, static_cast<const T*>(values.data), count);
    std::vector<T> packed;
    if constexpr (std::is_same<T, Vec3>::value) packed = gather_vec3(values); else packed = gather_boxes(values);
    return upload(dst, packed.data(), count);
  }
  if (values.stride == sizeof(T)) return copy(dst.data(), values.data, count * sizeof(T), cudaMemcpyDeviceToDevice);
  launch("gather_kernel launch", gather_kernel, values.count, kThreads, static_cast<const char*>(values.data),
         values.stride, values.count, int(sizeof(T) / sizeof(float)), is_aligned4(values),
         reinterpret_cast<float*>(dst.data()));
}

// A CUB device algorithm, call(storage, bytes): called once without storage to size its
// temporary storage (grown in `temp`, kept by the caller for reuse), then to run.
template <class CubCall>
void run_cub(DeviceBuffer<char>& temp, const char* what, const CubCall& call) {
  size_t bytes = 0;
  check(call(nullptr, bytes), what);
  temp.ensure(bytes > 0 ? bytes : 1);  // a null storage pointer would only size again
  check(call(temp.data(), bytes), what);
}

// ---- Tree ---------------------------------------------------------------------------------

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
__global__ void morton_kernel(Boxes boxes, int32_t n, const Box* centre_bounds, uint64_t* keys, int32_t* ids) {
  const int64_t i = global_index();
  if (i >= n) return;
  keys[i] = morton_code(morton_frame(*centre_bounds), box_centre(boxes(int32_t(i))));
  ids[i] = int32_t(i);
}

__global__ void karras_kernel(const uint64_t* keys, int32_t n, KarrasNode* karras, int32_t* kept) {
  const int64_t i = global_index();
  if (i >= n - 1) return;
  karras[i] = karras_node(int32_t(i), keys, n);
  kept[i] = keeps_node(int32_t(i), karras[i], kLeafSize) ? 1 : 0;
}

__global__ void collapse_kernel(const KarrasNode* karras, const int32_t* new_index, int32_t n, BvhNode* nodes) {
  const int64_t i = global_index();
  if (i < n - 1 && keeps_node(int32_t(i), karras[i], kLeafSize))
    collapse_node(int32_t(i), karras, new_index, kLeafSize, nodes);
}

template <class Boxes>
__global__ void refit_kernel(Boxes boxes, int32_t num_nodes, const int32_t* sorted_prims, BoxGroup* leaf_groups,
                             BvhNode* nodes, int32_t* arrivals) {
  const int64_t slot = global_index();
  if (slot < 2 * int64_t(num_nodes)) refit_from_slot(int32_t(slot), boxes, sorted_prims, leaf_groups, nodes, arrivals);
}

// Ids 0..n-1 sorted by the Morton code of their box centres, ties broken by id: cpu_tree.h's
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
  void build(Boxes boxes, int32_t n) {
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
    launch("karras_kernel launch", karras_kernel, n - 1, kThreads, sorted_keys.data(), n, karras.data(), kept.data());
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
           nodes_.data());
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
  const int32_t* sorted_prims() const { return sorted_prims_.data(); }

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

// ---- Queries --------------------------------------------------------------------------------

// Where the pairs go: pair i at pairs[2i], pairs[2i + 1] if i < capacity; *count counts all.
struct PairSlots {
  int32_t* pairs;
  unsigned long long capacity;
  unsigned long long* count;
};

// Reserves n slots of *count for each lane that calls it: the lanes of a warp calling together
// share one atomicAdd (its last lane adds the group's total; each lane gets its prefix).
__device__ unsigned long long reserve_slots(unsigned long long* count, unsigned long long n) {
  const cg::coalesced_group group = cg::coalesced_threads();
  const unsigned long long before = cg::exclusive_scan(group, n);
  unsigned long long base = 0;
  if (group.thread_rank() == group.size() - 1) base = atomicAdd(count, before + n);
  return group.shfl(base, group.size() - 1) + before;
}

// emit() of one query's thread: buffers up to kFlush pairs and reserves their slots in one
// warp-aggregated atomic (reserve_slots), far fewer atomics than one per pair.
class PairBuffer {
 public:
  static constexpr int kFlush = 16;
  __device__ explicit PairBuffer(const PairSlots& slots) : slots_(slots) {}
  __device__ void operator()(int32_t first, int32_t second) {
    pairs_[n_++] = make_int2(first, second);
    if (n_ == kFlush) flush();
  }
  __device__ void flush() {
    if (n_ == 0) return;
    const unsigned long long first = reserve_slots(slots_.count, static_cast<unsigned long long>(n_));
    for (int k = 0; k < n_; ++k) {
      const unsigned long long slot = first + k;
      if (slot >= slots_.capacity) break;
      slots_.pairs[2 * slot] = pairs_[k].x;
      slots_.pairs[2 * slot + 1] = pairs_[k].y;
    }
    n_ = 0;
  }

 private:
  PairSlots slots_;
  int n_ = 0;
  int2 pairs_[kFlush];
};

__device__ unsigned long long warp_sum(unsigned long long x) {
  for (int offset = 16; offset > 0; offset /= 2) x += __shfl_down_sync(0xffffffffu, x, offset);
  return x;
}

// Adds each thread's counts into work[0..3] (one atomic per warp and counter).
__device__ void add_work(const WorkCounts& w, unsigned long long* work) {
  const unsigned long long counts[4] = {w.nodes_visited, w.node_tests, w.primitive_tests, w.candidates};
  for (int k = 0; k < 4; ++k) {
    const unsigned long long sum = warp_sum(counts[k]);
    if ((threadIdx.x & 31) == 0 && sum) atomicAdd(&work[k], sum);
  }
}

// A pass's queries on the device: thread first_thread + i runs query i of the QueryPass (whose
// `out` the device does not read: the slots say where the pairs go). Passes start at block
// boundaries, so every block (and warp) runs one pass.
template <class Pass>
struct DevicePass {
  Pass pass;
  int64_t first_thread;
  PairSlots slots;
  unsigned long long* work;  // WorkCounts' four counters
};

__host__ __device__ int64_t round_up_to_block(int64_t n) { return (n + kQueryThreads - 1) / kQueryThreads * kQueryThreads; }

// Thread i's share of a pass, if i lies in the pass's blocks. With WorkCounts, every thread of
// those blocks stays to the end so that whole warps take part in the reduction of the counts.
template <class Work, class Pass>
__device__ void run_pass_thread(const DevicePass<Pass>& d, int64_t i) {
  const int64_t q = i - d.first_thread;
  if (q < 0 || q >= round_up_to_block(d.pass.num_queries)) return;  // uniform over the block
  Work work;
  if (q < d.pass.num_queries) {
    PairBuffer emit(d.slots);
    run_query<typename Pass::Shape>(d.pass.bvh, d.pass.queries, int32_t(q), emit, work);
    emit.flush();
  }
  if constexpr (std::is_same<Work, WorkCounts>::value) add_work(work, d.work);
}

// One thread per query of each pass: one launch answers them all.
template <class Work, class... Pass>
__global__ void __launch_bounds__(kQueryThreads) query_kernel(Pass... passes) {
  const int64_t i = global_index();
  (run_pass_thread<Work>(passes, i), ...);
}

__global__ void pack_pairs_kernel(const int32_t* pairs, int64_t n, uint64_t* keys) {
  const int64_t i = global_index();
  if (i < n) keys[i] = uint64_t(uint32_t(pairs[2 * i])) << 32 | uint32_t(pairs[2 * i + 1]);
}

__global__ void unpack_pairs_kernel(const uint64_t* keys, int64_t n, int32_t* pairs) {
  const int64_t i = global_index();
  if (i >= n) return;
  pairs[2 * i] = int32_t(keys[i] >> 32);
  pairs[2 * i + 1] = int32_t(keys[i] & 0xffffffffu);
}

// Device scratch a store keeps between queries, grown as needed.
struct QueryWorkspace {
  DeviceBuffer<unsigned long long> count;
  DeviceBuffer<unsigned long long> work;  // WorkCounts' four counters
  DeviceBuffer<int32_t> pairs;  // host output: pairs are collected here first
  DeviceBuffer<uint64_t> keys, sorted_keys;
  DeviceBuffer<char> temp;
  std::array<uint64_t, 5> last_count{};  // per QueryKind: the most pairs a query of that kind found
};

int bit_width(uint64_t x) { return x == 0 ? 0 : 64 - __builtin_clzll(x); }

// Sorts n pairs in device memory lexicographically: as uint64 keys (query << 32 | prim).
void sort_pairs(int32_t* pairs, int64_t n, int32_t num_queries, QueryWorkspace& ws) {
  if (n < 2) return;
  ws.keys.ensure(size_t(n));
  ws.sorted_keys.ensure(size_t(n));
  launch("pack_pairs_kernel launch", pack_pairs_kernel, n, kThreads, pairs, n, ws.keys.data());
  const int end_bit = 32 + bit_width(uint64_t(num_queries));  // query ids are < num_queries
  run_cub(ws.temp, "cub::DeviceRadixSort::SortKeys", [&](void* storage, size_t& bytes) {
    return cub::DeviceRadixSort::SortKeys(storage, bytes, ws.keys.data(), ws.sorted_keys.data(), n, 0, end_bit, kStream);
  });
  launch("unpack_pairs_kernel launch", unpack_pairs_kernel, n, kThreads, ws.sorted_keys.data(), n, pairs);
}

// Host output goes through device scratch, sized first by a guess: the kind's last count, or
// 8 pairs per query up to 2^24 pairs (128 MiB: a caller's large host buffer must not claim
// gigabytes before anything is found); a pass whose guess was short (but not the caller's
// buffer) reruns with the exact count.
uint64_t scratch_guess(const QueryWorkspace& ws, QueryKind kind, int32_t num_queries) {
  const uint64_t per_query = std::min<uint64_t>(8 * uint64_t(num_queries) + 65536, uint64_t(1) << 24);
  return std::max<uint64_t>(ws.last_count[int(kind)], per_query);
}

template <class Work, class... Pass>
void launch_passes(const Pass&... passes) {
  const int64_t threads = (round_up_to_block(passes.pass.num_queries) + ...);
  launch("query_kernel launch", query_kernel<Work, Pass...>, threads, kQueryThreads, passes...);
}

// Runs the passes in one kernel launch and one count readback; returns each pass's total,
// its pairs written (and sorted if asked) where they fit the caller's buffer.
template <class Work, class... Pass>
std::array<uint64_t, sizeof...(Pass)> run_passes(QueryWorkspace& ws, const std::array<WorkCounts*, sizeof...(Pass)>& works,
                                                 const Pass&... passes) {
  constexpr size_t kPasses = sizeof...(Pass);
  const std::array<QueryKind, kPasses> kinds{passes.kind...};
  const std::array<PairOutput, kPasses> outs{passes.out...};
  const std::array<int32_t, kPasses> num_queries{passes.num_queries...};
  std::array<uint64_t, kPasses> capacity{};
  for (size_t k = 0; k < kPasses; ++k) {
    capacity[k] = outs[k].capacity;
    if (outs[k].memory == Memory::kHost) capacity[k] = std::min<uint64_t>(outs[k].capacity, scratch_guess(ws, kinds[k], num_queries[k]));
  }
  ws.count.ensure(kPasses);
  ws.work.ensure(4 * kPasses);
  std::array<int32_t*, kPasses> pairs{};
  std::array<uint64_t, kPasses> totals{};
  for (int attempt = 0; attempt < 2; ++attempt) {
    size_t scratch = 0;  // host outputs' slots in ws.pairs, one after another
    for (size_t k = 0; k < kPasses; ++k)
      if (outs[k].memory == Memory::kHost) scratch += 2 * capacity[k];
    ws.pairs.ensure(scratch);
    scratch = 0;
    for (size_t k = 0; k < kPasses; ++k) {
      pairs[k] = outs[k].pairs;
      if (outs[k].memory == Memory::kHost) {
        pairs[k] = ws.pairs.data() + scratch;
        scratch += 2 * capacity[k];
      }
    }
    zero(ws.count, kPasses);
    zero(ws.work, 4 * kPasses);
    int64_t first_thread = 0;
    size_t k = 0;
    auto device_pass = [&](const auto& pass) {
      const DevicePass<std::decay_t<decltype(pass)>> d{pass, first_thread,
                                                       PairSlots{pairs[k], capacity[k], ws.count.data() + k},
                                                       ws.work.data() + 4 * k};
      first_thread += round_up_to_block(pass.num_queries);
      ++k;
      return d;
    };
    const auto device_passes = std::tuple{device_pass(passes)...};  // braces: built left to right
    std::apply([](const auto&... d) { launch_passes<Work>(d...); }, device_passes);
    unsigned long long counts[kPasses];
    copy(counts, ws.count.data(), sizeof(counts), cudaMemcpyDeviceToHost);
    bool rerun = false;
    for (size_t j = 0; j < kPasses; ++j) {
      totals[j] = counts[j];
      if (totals[j] <= outs[j].capacity && totals[j] > capacity[j]) {
        capacity[j] = totals[j];
        rerun = true;
      }
    }
    if (!rerun) break;
  }
  if constexpr (std::is_same<Work, WorkCounts>::value) {  // the last run's counts: a rerun repeats the same work
    unsigned long long counts[4 * kPasses];
    copy(counts, ws.work.data(), sizeof(counts), cudaMemcpyDeviceToHost);
    for (size_t k = 0; k < kPasses; ++k)
      if (works[k]) works[k]->add(WorkCounts{counts[4 * k], counts[4 * k + 1], counts[4 * k + 2], counts[4 * k + 3]});
  }
  for (size_t k = 0; k < kPasses; ++k) {
    ws.last_count[int(kinds[k])] = std::max(ws.last_count[int(kinds[k])], totals[k]);
    if (totals[k] > outs[k].capacity) continue;  // the caller learns the exact count; nothing copied
    if (totals[k] > capacity[k]) fail(Status::kInternal, "pair count changed between two runs of the same query");
    if (outs[k].canonical) sort_pairs(pairs[k], int64_t(totals[k]), num_queries[k], ws);
    if (outs[k].memory == Memory::kHost)
      copy(outs[k].pairs, pairs[k], totals[k] * 2 * sizeof(int32_t), cudaMemcpyDeviceToHost);
  }
  check(cudaStreamSynchronize(kStream), "cudaStreamSynchronize");  // report kernel faults here
  return totals;
}

template <class... Pass>
std::array<uint64_t, sizeof...(Pass)> run_counted(QueryWorkspace& ws, const std::array<WorkCounts*, sizeof...(Pass)>& works,
                                                  const Pass&... passes) {
  return with_work(works, [&](auto work) { return run_passes<decltype(work)>(ws, works, passes...); });
}

// ---- Stores and backend ---------------------------------------------------------------------

// Every public call selects the store's device for its duration (DeviceScope). Constructors
// and destructors hold it from hold_device() on: the members, and this base's, are then
// allocated and freed on it, even when a constructor fails; device_ (destroyed after every
// member) gives the caller's device back, or release_device() at the end of a constructor.
template <class Interface>
class CudaStore : public Interface {
 protected:
  explicit CudaStore(int ordinal) : ordinal_(ordinal) {}
  void finish() { check(cudaStreamSynchronize(kStream), "cudaStreamSynchronize"); }  // errors belong to this call
  // Returns the runtime's error: constructors check it, destructors cannot report it.
  cudaError_t hold_device() noexcept { return device_.enter(ordinal_); }
  void release_device() noexcept { device_.leave(); }
  int ordinal_;

 private:
  DeviceSwitch device_;  // declared before ws_ and the final classes' members: destroyed after them

 protected:
  QueryWorkspace ws_;
};

class CudaMeshStore final : public CudaStore<MeshStore> {
 public:
  CudaMeshStore(int ordinal, const Strided& vertices, const std::vector<Triangle>& triangles,
                const std::vector<Edge>& edges, bool triangle_tree, bool edge_tree)
      : CudaStore(ordinal), has_triangle_tree_(triangle_tree), has_edge_tree_(edge_tree) {
    check(hold_device(), "cudaGetDevice / cudaSetDevice");
    gather_to_device(vertices, vertices_);
    num_vertices_ = int32_t(vertices.count);
    num_triangles_ = int32_t(triangles.size());
    num_edges_ = int32_t(edges.size());
    if (has_triangle_tree_) upload(triangles_, triangles.data(), triangles.size());
    upload(edges_, edges.data(), edges.size());
    build_trees();
    finish();
    release_device();
  }
  ~CudaMeshStore() override { hold_device(); }

  void copy_edges(Edge* host_out) override {
    const DeviceScope device(ordinal_);
    copy(host_out, edges_.data(), size_t(num_edges_) * sizeof(Edge), cudaMemcpyDeviceToHost);
  }

  void refit(const Strided& vertices) override {
    const DeviceScope device(ordinal_);
    gather_to_device(vertices, vertices_);
    if (has_triangle_tree_) triangle_tree_.refit(triangle_boxes());
    if (has_edge_tree_) edge_tree_.refit(edge_boxes());
    finish();
  }

  void rebuild(const Strided& vertices) override {
    const DeviceScope device(ordinal_);
    gather_to_device(vertices, vertices_);
    build_trees();
    finish();
  }

  double tree_growth() override {
    const DeviceScope device(ordinal_);
    double g = has_triangle_tree_ ? growth(triangle_tree_.area_cost(), triangle_tree_.cost_at_build()) : 0.0;
    if (has_edge_tree_) g = std::max(g, growth(edge_tree_.area_cost(), edge_tree_.cost_at_build()));
    return g;
  }

  uint64_t query(const QueryRequest& request, const PairOutput& out, WorkCounts* work) override {
    const DeviceScope device(ordinal_);
    uint64_t total = 0;
    auto run = [&](const auto& pass) { total = run_counted(ws_, {work}, pass)[0]; };
    if (request.kind == QueryKind::kVertexTriangle) with_vt_pass(request, out, run); else with_ee_pass(request, out, run);
    return total;
  }

  std::array<uint64_t, 2> query_vt_ee(const QueryJob& vt, const QueryJob& ee) override {
    const DeviceScope device(ordinal_);
    std::array<uint64_t, 2> totals{};
    with_vt_pass(vt.request, vt.out, [&](const auto& vt_pass) {
      with_ee_pass(ee.request, ee.out, [&](const auto& ee_pass) {
        totals = run_counted(ws_, {vt.work, ee.work}, vt_pass, ee_pass);
      });
    });
    return totals;
  }

 private:
  // Calls fn with the QueryPass of a VT request, or of an EE request.
  template <class Fn>
  void with_vt_pass(const QueryRequest& request, const PairOutput& out, Fn&& fn) {
    const VertexTriangleQueries queries{vertices_.data(), triangles_.data(), vertex_order_.data(), request.r,
                                        request.filters};
    with_pass<true>(request, triangle_tree_.view(), queries, num_vertices_, out, fn);
  }
  template <class Fn>
  void with_ee_pass(const QueryRequest& request, const PairOutput& out, Fn&& fn) {
    const EdgeEdgeQueries queries{vertices_.data(), edges_.data(), edge_tree_.sorted_prims(), request.r, request.filters};
    with_pass<false>(request, edge_tree_.view(), queries, num_edges_, out, fn);
  }

  // The trees the flags ask for, and the VT query order, from the current vertices.
  void build_trees() {
    if (has_triangle_tree_) {
      triangle_tree_.build(triangle_boxes(), num_triangles_);
      DeviceBuffer<uint64_t> keys;
      sort_by_morton(PointBoxes{vertices_.data()}, num_vertices_, keys, vertex_order_);
    }
    if (has_edge_tree_) edge_tree_.build(edge_boxes(), num_edges_);
  }
  TriangleBoxes triangle_boxes() const { return {vertices_.data(), triangles_.data()}; }
  EdgeBoxes edge_boxes() const { return {vertices_.data(), edges_.data()}; }

  DeviceBuffer<Vec3> vertices_;
  DeviceBuffer<Triangle> triangles_;  // only with a triangle tree
  DeviceBuffer<Edge> edges_;
  DeviceBuffer<int32_t> vertex_order_;  // the vertices' Morton order at build: VT query order
  int32_t num_vertices_ = 0, num_triangles_ = 0, num_edges_ = 0;
  bool has_triangle_tree_, has_edge_tree_;
  CudaTree triangle_tree_, edge_tree_;
};

class CudaBoxStore final : public CudaStore<Store> {
 public:
  CudaBoxStore(int ordinal, const Strided& boxes) : CudaStore(ordinal) {
    check(hold_device(), "cudaGetDevice / cudaSetDevice");
    gather_to_device(boxes, boxes_);
    num_boxes_ = int32_t(boxes.count);
    tree_.build(GivenBoxes{boxes_.data()}, num_boxes_);
    finish();
    release_device();
  }
  ~CudaBoxStore() override { hold_device(); }

  void refit(const Strided& boxes) override {
    const DeviceScope device(ordinal_);
    gather_to_device(boxes, boxes_);
    tree_.refit(GivenBoxes{boxes_.data()});
    finish();
  }

  void rebuild(const Strided& boxes) override {
    const DeviceScope device(ordinal_);
    gather_to_device(boxes, boxes_);
    tree_.build(GivenBoxes{boxes_.data()}, num_boxes_);
    finish();
  }

  double tree_growth() override {
    const DeviceScope device(ordinal_);
    return growth(tree_.area_cost(), tree_.cost_at_build());
  }

  uint64_t query(const QueryRequest& request, const PairOutput& out, WorkCounts* work) override {
    const DeviceScope device(ordinal_);
    gather_to_device(request.first, query_first_);
    gather_to_device(request.second, query_second_);
    const UserQueries queries{query_first_.data(), request.second.count == 0 ? nullptr : query_second_.data(),
                              request.r};
    uint64_t total = 0;
    const int32_t n = int32_t(request.first.count);
    auto run = [&](const auto& pass) { total = run_counted(ws_, {work}, pass)[0]; };
    if (request.kind == QueryKind::kUserSpheres) with_pass<true>(request, tree_.view(), queries, n, out, run);
    else with_pass<false>(request, tree_.view(), queries, n, out, run);
    return total;
  }

 private:
  DeviceBuffer<Box> boxes_;
  int32_t num_boxes_ = 0;
  CudaTree tree_;
  DeviceBuffer<Vec3> query_first_, query_second_;  // the last queries' points, kept to be reused
};

class CudaBackend final : public Backend {
 public:
  CudaBackend(int ordinal, const std::string& device_name)
      : ordinal_(ordinal), name_("cuda:" + std::to_string(ordinal) + " (" + device_name + ")"),
        host_(make_cpu_backend()) {}

  std::string name() const override { return name_; }
  bool is_cuda() const override { return true; }

  int64_t first_non_finite(const Strided& values, int floats) override {
    if (values.memory == Memory::kHost) return host_->first_non_finite(values, floats);
    const DeviceScope device(ordinal_);
    if (values.count == 0) return -1;
    DeviceBuffer<unsigned long long> first(1);
    const unsigned long long none = std::numeric_limits<unsigned long long>::max();
    copy(first.data(), &none, sizeof(none), cudaMemcpyHostToDevice);
    launch("first_non_finite_kernel launch", first_non_finite_kernel, values.count, kThreads,
           static_cast<const char*>(values.data), values.stride, values.count, floats, is_aligned4(values),
           first.data());
    unsigned long long result = none;
    copy(&result, first.data(), sizeof(result), cudaMemcpyDeviceToHost);
    return result == none ? -1 : int64_t(result);
  }

  void copy_to_host(void* dst, const void* src, size_t bytes, Memory memory) override {
    if (memory == Memory::kHost) return host_->copy_to_host(dst, src, bytes, memory);
    const DeviceScope device(ordinal_);
    copy(dst, src, bytes, cudaMemcpyDeviceToHost);
  }

  std::unique_ptr<MeshStore> create_mesh_store(const Strided& vertices, std::vector<Triangle> triangles,
                                               std::vector<Edge> edges, bool triangle_tree, bool edge_tree) override {
    return std::make_unique<CudaMeshStore>(ordinal_, vertices, triangles, edges, triangle_tree, edge_tree);
  }
  std::unique_ptr<Store> create_box_store(const Strided& boxes) override {
    return std::make_unique<CudaBoxStore>(ordinal_, boxes);
  }

 private:
  int ordinal_;
  std::string name_;
  std::unique_ptr<Backend> host_;  // host-memory inputs are checked and copied as on the CPU
};

}  // namespace

bool built_with_cuda() { return true; }

int cuda_device_count() {
  int count = 0;
  if (cudaGetDeviceCount(&count) != cudaSuccess) {
    cudaGetLastError();  // no driver or no device: not an error for a count
    return 0;
  }
  return count;
}

std::unique_ptr<Backend> make_cuda_backend(int ordinal) {
  int count = 0;
  const cudaError_t error = cudaGetDeviceCount(&count);
  if (error != cudaSuccess) {
    cudaGetLastError();
    fail(Status::kUnsupported, std::string("no usable CUDA device: ") + cudaGetErrorString(error));
  }
  if (ordinal < 0 || ordinal >= count)
    fail(Status::kUnsupported, "no CUDA device cuda:" + std::to_string(ordinal) + " (" + std::to_string(count) +
                                   " device" + (count == 1 ? "" : "s") + " found)");
  const DeviceScope device(ordinal);  // creates the device's context now, not in the first call
  cudaDeviceProp properties;
  check(cudaGetDeviceProperties(&properties, ordinal), "cudaGetDeviceProperties");
  return std::make_unique<CudaBackend>(ordinal, properties.name);
}

}  // namespace minkq
