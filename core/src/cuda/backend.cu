// The CUDA backend: the stores of store.h over the CUDA executor (device buffers, CudaTree,
// the one-launch pass runner, each call on the store's device), and the backend's own input
// checks. The one translation unit of CUDA code: runtime.cuh, tree.cuh and passes.cuh are
// included here only.
#include <cuda_runtime.h>

#include <limits>
#include <string>
#include <utility>

#include "backend.h"
#include "cuda/job_passes.cuh"
#include "cuda/passes.cuh"
#include "cuda/runtime.cuh"
#include "cuda/tree.cuh"
#include "store.h"

namespace minkq {
namespace {

using namespace cuda;

// Group g of a tree's elements in leaf order, from the elements by id (leaf_groups.h), and back.
template <class Prim>
static __global__ void fill_groups_kernel(const Prim* prims, const int32_t* sorted_prims, int32_t n,
                                          LeafGroup<Prim>* out) {
  const int64_t g = global_index();
  if (g < box_group_count(n)) fill_leaf_group(g, prims, sorted_prims, n, out[g]);
}
template <class Prim>
static __global__ void scatter_groups_kernel(const LeafGroup<Prim>* groups, const int32_t* sorted_prims, int32_t n,
                                             Prim* out) {
  const int64_t g = global_index();
  if (g < box_group_count(n)) scatter_leaf_group(g, groups[g], sorted_prims, n, out);
}

// The scope of one call: its device, then its stream (runtime.cuh's call stream).
class CallScope {
 public:
  CallScope(int ordinal, cudaStream_t stream, bool asynchronous) : device_(ordinal), stream_(stream, asynchronous) {}

 private:
  DeviceScope device_;
  StreamScope stream_;
};

// store.h's executor on a CUDA device. Every call selects the device for its duration
// (scope(): blocking calls on the per-thread default stream; scope_on(): asynchronous ones on
// the caller's); a store's construction and teardown hold it from hold() on, so the members are
// allocated and freed on it even when a constructor fails; device_ (destroyed after every
// member of the store) gives the caller's device back, or release() at the end of a
// constructor. finish() synchronises the stream: a call's errors belong to that call.
class CudaExecutor {
 public:
  using Device = int;  // the ordinal
  template <class T>
  using Array = DeviceBuffer<T>;
  using Tree = CudaTree;

  explicit CudaExecutor(int ordinal) : ordinal_(ordinal) {}
  CallScope scope() const { return CallScope(ordinal_, cudaStreamPerThread, false); }
  CallScope scope_on(Stream stream) const { return CallScope(ordinal_, static_cast<cudaStream_t>(stream), true); }
  void wait(Stream stream) { check(cudaStreamSynchronize(static_cast<cudaStream_t>(stream)), "cudaStreamSynchronize"); }
  void hold() { check(device_.enter(ordinal_), "cudaGetDevice / cudaSetDevice"); }
  void release() noexcept { device_.leave(); }
  void hold_for_teardown() noexcept { device_.enter(ordinal_); }  // a destructor cannot report
  void finish() { check(cudaStreamSynchronize(stream()), "cudaStreamSynchronize"); }

  template <class T>
  void gather(const Strided& values, DeviceBuffer<T>& dst) {
    gather_to_device(values, dst);
  }
  void gather_float64(const Strided& values, DeviceBuffer<Vec3>& dst, DeviceBuffer<float>& rho, bool accumulate) {
    gather_float64_to_device(values, dst, rho, accumulate);
  }
  template <class T>
  void upload(DeviceBuffer<T>& dst, std::vector<T>&& host) {
    cuda::upload(dst, host.data(), host.size());
  }
  template <class T>
  void download(T* host_out, const DeviceBuffer<T>& src, size_t count) {
    copy(host_out, src.data(), count * sizeof(T), cudaMemcpyDeviceToHost);
  }
  template <class Boxes>
  void sort_by_morton(Boxes boxes, int32_t n, DeviceBuffer<int32_t>& ids) {
    SortScratch local;
    cuda::sort_by_morton(boxes, n, sort_reserved_ ? sort_ : local, ids);
  }
  // Sized at the scene's first build (an asynchronous rebuild only fills it).
  template <class Prim>
  void fill_groups(const Prim* prims, const int32_t* sorted_prims, int32_t n, DeviceBuffer<LeafGroup<Prim>>& out) {
    out.ensure(size_t(box_group_count(n)));
    launch("fill_groups_kernel launch", fill_groups_kernel<Prim>, box_group_count(n), kThreads, prims, sorted_prims, n,
           out.data());
  }
  // out: reserved (reserve_scratch) for an asynchronous rebuild.
  template <class Prim>
  void scatter_groups(const DeviceBuffer<LeafGroup<Prim>>& groups, const int32_t* sorted_prims, int32_t n,
                      DeviceBuffer<Prim>& out) {
    out.ensure(size_t(n));
    launch("scatter_groups_kernel launch", scatter_groups_kernel<Prim>, box_group_count(n), kThreads, groups.data(),
           sorted_prims, n, out.data());
  }
  template <class Work, class... Pass>
  std::array<uint64_t, sizeof...(Pass)> run_passes(const std::array<WorkCounts*, sizeof...(Pass)>& works,
                                                   const Pass&... passes) {
    // Asynchronous calls count no work (job passes: compiled in job_passes_*.cu).
    if constexpr (std::is_same<Work, NoWork>::value)
      if ((passes.out.count || ...)) {  // an asynchronous call's (all of its passes)
        run_passes_async<Work>(async_ws_, passes...);
        return {};
      }
    return cuda::run_passes<Work>(ws_, works, passes...);
  }

  // Asynchronous calls.
  void reserve_staging(DeviceBuffer<Vec3>& staging, int32_t n) { staging.ensure(size_t(n)); }
  void reserve_pending() {
    pending_.ensure(3);
    zero(pending_, 3);
  }
  void reserve_canonical(size_t capacity) { cuda::reserve_canonical(async_ws_, capacity); }
  template <class T>
  void reserve_scratch(DeviceBuffer<T>& scratch, int32_t n) {
    scratch.ensure(size_t(n));
  }
  void reserve_nodes(CudaTree& tree, int32_t n) { tree.reserve_nodes(n); }
  template <class Boxes>
  void reserve_build(CudaTree& tree, Boxes, int32_t n) {
    tree.reserve_build(n);
  }
  template <class Boxes>
  void reserve_sort(Boxes, int32_t n) {
    cuda::reserve_sort(sort_, n);
    sort_reserved_ = true;
  }
  // Gathers and checks into staging, then takes the vertices only if all are finite (runtime.cuh's
  // two kernels): pending_[0] is this call's first bad vertex, pending_[1] the recorded error,
  // pending_[2] float64 input's rho until it is taken.
  void commit_finite(const Strided& values, DeviceBuffer<Vec3>& staging, DeviceBuffer<Vec3>& dst, float* rho,
                     PendingError::Call call, int64_t first) {
    if (values.count == 0) return;
    begin_check(values);
    stage(values, staging);
    commit(staging, dst, values, rho, nullptr, call, first);
  }
  // Both positions of a swept step checked together; on a bad one dst1 = dst0 (kept).
  void commit_finite_swept(const Strided& x0, const Strided& x1, DeviceBuffer<Vec3>& staging0,
                           DeviceBuffer<Vec3>& staging1, DeviceBuffer<Vec3>& dst0, DeviceBuffer<Vec3>& dst1, float* rho,
                           PendingError::Call call, int64_t first) {
    if (x0.count == 0) return;
    begin_check(x0);
    stage(x0, staging0);
    stage(x1, staging1);
    commit(staging0, dst0, x0, rho, nullptr, call, first);
    commit(staging1, dst1, x1, rho, dst0.data(), call, first);
  }
  PendingError take_pending() {
    unsigned long long recorded = 0;
    copy(&recorded, pending_.data() + 1, sizeof(recorded), cudaMemcpyDeviceToHost);
    if (recorded == 0) return {};
    zero(pending_.data() + 1, 1);
    finish();
    return {static_cast<PendingError::Call>(recorded >> 32), int64_t(recorded & 0xFFFFFFFFull)};
  }

 private:
  // commit_finite's steps: reset this call's check words, stage one buffer, commit one.
  void begin_check(const Strided& values) {
    check(cudaMemsetAsync(pending_.data(), 0xFF, sizeof(unsigned long long), stream()), "cudaMemsetAsync");
    if (values.scalar == Scalar::kFloat64)
      check(cudaMemsetAsync(pending_.data() + 2, 0, sizeof(unsigned long long), stream()), "cudaMemsetAsync");
  }
  void stage(const Strided& values, DeviceBuffer<Vec3>& staging) {
    launch("gather_checked_kernel launch", gather_checked_kernel, values.count, kThreads,
           static_cast<const char*>(values.data), values.stride, values.count, values.scalar == Scalar::kFloat64,
           is_aligned(values), staging.data(), pending_.data());
  }
  void commit(const DeviceBuffer<Vec3>& staging, DeviceBuffer<Vec3>& dst, const Strided& values, float* rho,
              const Vec3* keep, PendingError::Call call, int64_t first) {
    launch("commit_checked_kernel launch", commit_checked_kernel, values.count, kThreads, staging.data(), values.count,
           static_cast<unsigned long long>(call), static_cast<unsigned long long>(first), dst.data(),
           values.scalar == Scalar::kFloat64 ? rho : nullptr, keep, pending_.data());
  }

  int ordinal_;
  DeviceSwitch device_;  // declared before the buffers: destroyed after them
  // The blocking queries' scratch, grown as they need, and the asynchronous ones', sized only by
  // reserve_canonical: a blocking query never moves what a captured canonical sort writes to.
  QueryWorkspace ws_, async_ws_;
  SortScratch sort_;  // the VT query order's Morton sort, kept once reserved
  bool sort_reserved_ = false;
  DeviceBuffer<unsigned long long> pending_;  // asynchronous refits' checks (commit_finite)
};

class CudaBackend final : public Backend {
 public:
  CudaBackend(int ordinal, const std::string& device_name, bool pageable_access)
      : ordinal_(ordinal), name_("cuda:" + std::to_string(ordinal) + " (" + device_name + ")"),
        pageable_access_(pageable_access), host_(make_cpu_backend()) {}

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
           static_cast<const char*>(values.data), values.stride, values.count, floats,
           values.scalar == Scalar::kFloat64, is_aligned(values), first.data());
    unsigned long long result = none;
    copy(&result, first.data(), sizeof(result), cudaMemcpyDeviceToHost);
    return result == none ? -1 : int64_t(result);
  }

  void copy_to_host(void* dst, const void* src, size_t bytes, Memory memory) override {
    if (memory == Memory::kHost) return host_->copy_to_host(dst, src, bytes, memory);
    const DeviceScope device(ordinal_);
    copy(dst, src, bytes, cudaMemcpyDefault);  // `src` may be host memory the device reads (runtime.cuh)
  }

  // Device memory of this device, managed memory, mapped pinned host memory, or (where the
  // device reads pageable memory: HMM / ATS systems) any host memory. Anything else would
  // fault the first kernel that reads it, with an error that sticks to the context.
  void check_device_pointer(const void* data, const std::string& what) override {
    const DeviceScope device(ordinal_);
    cudaPointerAttributes attributes{};
    if (const cudaError_t error = cudaPointerGetAttributes(&attributes, data); error != cudaSuccess) {
      cudaGetLastError();
      fail(Status::kInvalidArgument, what + " is not memory the CUDA runtime knows (" +
                                         cudaGetErrorString(error) + ") but its memory is MINKQ_MEMORY_DEVICE");
    }
    switch (attributes.type) {
      case cudaMemoryTypeManaged: return;
      case cudaMemoryTypeDevice:
        if (attributes.device == ordinal_) return;
        fail(Status::kInvalidArgument, what + " is memory of cuda:" + std::to_string(attributes.device) +
                                           " but the device is " + name_);
      case cudaMemoryTypeHost:
        if (attributes.devicePointer == data) return;  // mapped pinned memory, same address
        fail(Status::kInvalidArgument, what + " is pinned host memory not mapped at the same address on " +
                                           name_ + ": pass MINKQ_MEMORY_HOST");
      default:
        if (pageable_access_) return;
        fail(Status::kInvalidArgument, what + " is host memory but its memory is MINKQ_MEMORY_DEVICE (" + name_ +
                                           " cannot read pageable host memory): pass MINKQ_MEMORY_HOST");
    }
  }

  std::unique_ptr<MeshStore> create_mesh_store(std::vector<GeometryInput> geometries) override {
    return std::make_unique<MeshStoreOn<CudaExecutor>>(ordinal_, std::move(geometries));
  }
  std::unique_ptr<Store> create_box_store(const Strided& boxes) override {
    return std::make_unique<BoxStoreOn<CudaExecutor>>(ordinal_, boxes);
  }

 private:
  int ordinal_;
  std::string name_;
  bool pageable_access_;  // the device reads pageable host memory (cudaDevAttrPageableMemoryAccess)
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
  int pageable = 0;
  check(cudaDeviceGetAttribute(&pageable, cudaDevAttrPageableMemoryAccess, ordinal), "cudaDeviceGetAttribute");
  return std::make_unique<CudaBackend>(ordinal, properties.name, pageable != 0);
}

}  // namespace minkq
