// The CUDA backend's runtime helpers: error checks, the current-device switch, owning device
// buffers, copies on the backend's stream, the one-thread-per-element launch, strided gathers
// from host or device memory, and CUB's size-then-run calls. The counterpart of cpu/runtime.h.
// Included by cuda/backend.cu only (one translation unit holds every kernel).
#pragma once

#include <cuda_runtime.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "backend.h"

namespace minkq::cuda {

constexpr int kThreads = 256;  // element-wise kernels

// The stream of the calling thread's current library call. Blocking calls run on the
// per-thread default stream, so scenes used from different host threads do not serialise on
// the legacy stream, and every host read of device results synchronises it. Asynchronous calls
// run on the caller's stream and may neither allocate nor copy to or from the host (they may be
// recorded into a CUDA graph): DeviceBuffer::ensure and copy() refuse, so that a missing
// reservation is an error, not a broken capture.
struct CallStream {
  cudaStream_t stream = cudaStreamPerThread;
  bool asynchronous = false;
};
inline CallStream& call_stream() {
  static thread_local CallStream current;
  return current;
}
inline cudaStream_t stream() { return call_stream().stream; }

// Sets the calling thread's call stream for a scope and restores the previous one after.
class StreamScope {
 public:
  StreamScope(cudaStream_t stream, bool asynchronous) : previous_(call_stream()) {
    call_stream() = CallStream{stream, asynchronous};
  }
  StreamScope(const StreamScope&) = delete;
  StreamScope& operator=(const StreamScope&) = delete;
  ~StreamScope() { call_stream() = previous_; }

 private:
  CallStream previous_;
};

// ---- Errors and memory ------------------------------------------------------------------------

inline void check(cudaError_t error, const char* call) {
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
    if (call_stream().asynchronous)
      fail(Status::kInternal, "an asynchronous call needed " + std::to_string(count) + " elements of scratch where " +
                                  std::to_string(size_) + " were reserved");
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

// cudaMemcpy on the call's stream, complete on return (the host may reuse or read its side at
// once). Not in asynchronous calls.
inline void copy(void* dst, const void* src, size_t bytes, cudaMemcpyKind kind) {
  if (bytes == 0) return;
  if (call_stream().asynchronous) fail(Status::kInternal, "a host copy in an asynchronous call");
  check(cudaMemcpyAsync(dst, src, bytes, kind, stream()), "cudaMemcpyAsync");
  check(cudaStreamSynchronize(stream()), "cudaStreamSynchronize");
}

template <class T>
void zero(T* data, size_t count) {
  if (count) check(cudaMemsetAsync(data, 0, count * sizeof(T), stream()), "cudaMemsetAsync");
}
template <class T>
void zero(DeviceBuffer<T>& buffer, size_t count) {
  zero(buffer.data(), count);
}

template <class T>
void upload(DeviceBuffer<T>& dst, const T* src, size_t count) {
  dst.ensure(count);
  copy(dst.data(), src, count * sizeof(T), cudaMemcpyHostToDevice);
}

// Whether every launch waits for its kernel (environment MINKQ_CUDA_SYNC set and not "0"): a
// debugging switch that reports a kernel's fault at its own launch, named, instead of at the
// next copy or synchronisation, at the cost of a host wait per launch.
inline bool sync_each_launch() {
  static const bool on = [] {
    const char* value = std::getenv("MINKQ_CUDA_SYNC");
    return value != nullptr && *value != '\0' && std::strcmp(value, "0") != 0;
  }();
  return on;
}

// One thread per element i < n.
template <class Kernel, class... Args>
void launch(const char* name, Kernel kernel, int64_t n, int threads, Args... args) {
  if (n <= 0) return;
  kernel<<<unsigned((n + threads - 1) / threads), threads, 0, stream()>>>(args...);
  check(cudaGetLastError(), name);
  // Not in asynchronous calls: their stream may be capturing, where a wait is an error.
  if (sync_each_launch() && !call_stream().asynchronous) check(cudaStreamSynchronize(stream()), name);
}

__device__ inline int64_t global_index() { return int64_t(blockIdx.x) * blockDim.x + threadIdx.x; }

// The threads the current device holds at once (multiprocessors times threads per one): the
// grid of a grid-stride loop that should cover its work in one wave.
inline int64_t resident_threads() {
  int device = 0, multiprocessors = 0, per_multiprocessor = 0;
  check(cudaGetDevice(&device), "cudaGetDevice");
  check(cudaDeviceGetAttribute(&multiprocessors, cudaDevAttrMultiProcessorCount, device), "cudaDeviceGetAttribute");
  check(cudaDeviceGetAttribute(&per_multiprocessor, cudaDevAttrMaxThreadsPerMultiProcessor, device),
        "cudaDeviceGetAttribute");
  return std::max<int64_t>(int64_t(multiprocessors) * per_multiprocessor, kThreads);
}

// ---- Strided input ------------------------------------------------------------------------

// Coordinate k (a float or a double) of a record: read whole where the records are aligned to
// it (caller-supplied strides need not be), else byte by byte.
template <class T>
__device__ inline T load_scalar(const char* record, int k, bool aligned) {
  if (aligned) return reinterpret_cast<const T*>(record)[k];
  unsigned char bytes[sizeof(T)];
  for (int b = 0; b < int(sizeof(T)); ++b) bytes[b] = static_cast<unsigned char>(record[sizeof(T) * k + b]);
  T value;
  memcpy(&value, bytes, sizeof(T));
  return value;
}
__device__ inline float load_float(const char* record, int k, bool aligned) { return load_scalar<float>(record, k, aligned); }
__device__ inline double load_double(const char* record, int k, bool aligned) {
  return load_scalar<double>(record, k, aligned);
}

template <size_t kBytes>
bool is_aligned_to(const Strided& values) {
  return (reinterpret_cast<uintptr_t>(values.data) % kBytes == 0) && values.stride % kBytes == 0;
}
inline bool is_aligned4(const Strided& values) { return is_aligned_to<4>(values); }
inline bool is_aligned8(const Strided& values) { return is_aligned_to<8>(values); }
// Whether records of `values` can be read whole (4-aligned floats, 8-aligned doubles).
inline bool is_aligned(const Strided& values) {
  return values.scalar == Scalar::kFloat64 ? is_aligned8(values) : is_aligned4(values);
}
// Coordinate k of a record as the float minkq keeps: float64 ones rounded to nearest.
__device__ inline float load_coordinate(const char* record, int k, bool float64, bool aligned) {
  return float64 ? float(load_double(record, k, aligned)) : load_float(record, k, aligned);
}

// A float64 vertex of a record, and rho: the largest rounding_distance (non-negative floats
// order as their bits), atomically kept in *rho_bits.
__device__ inline Vec3 load_float64_vertex(const char* record, bool aligned, unsigned int* rho_bits) {
  const double p[3] = {load_double(record, 0, aligned), load_double(record, 1, aligned), load_double(record, 2, aligned)};
  const Vec3 v = round_to_float(p);
  const float moved = rounding_distance(p, v);
  unsigned int bits;
  memcpy(&bits, &moved, 4);
  if (moved == moved) atomicMax(rho_bits, bits);  // a NaN input is reported, not kept
  return v;
}
static __global__ void gather_float64_kernel(const char* base, size_t stride, int64_t n, bool aligned, Vec3* out,
                                             unsigned int* rho_bits) {
  const int64_t i = global_index();
  if (i < n) out[i] = load_float64_vertex(base + size_t(i) * stride, aligned, rho_bits);
}

static __global__ void gather_kernel(const char* base, size_t stride, int64_t n, int floats, bool aligned,
                                     float* out) {
  const int64_t i = global_index();
  if (i >= n) return;
  const char* record = base + size_t(i) * stride;
  for (int k = 0; k < floats; ++k) out[i * floats + k] = load_float(record, k, aligned);
}

static __global__ void first_non_finite_kernel(const char* base, size_t stride, int64_t n, int floats, bool float64,
                                               bool aligned, unsigned long long* first) {
  const int64_t i = global_index();
  if (i >= n) return;
  const char* record = base + size_t(i) * stride;
  for (int k = 0; k < floats; ++k)
    if (!isfinite(load_coordinate(record, k, float64, aligned))) {
      atomicMin(first, static_cast<unsigned long long>(i));
      return;
    }
}

// Asynchronous refits: the caller's strided vertices gathered into `staging`, with the
// smallest index of a vertex holding a NaN or infinity atomically kept in words[0] (set to
// kNoVertex first); float64 ones rounded, their rho kept in the low half of words[2] (zeroed
// first).
constexpr unsigned long long kNoVertex = ~0ull;
static __global__ void gather_checked_kernel(const char* base, size_t stride, int64_t n, bool float64, bool aligned,
                                             Vec3* staging, unsigned long long* words) {
  const int64_t i = global_index();
  if (i >= n) return;
  const char* record = base + size_t(i) * stride;
  const Vec3 v = float64 ? load_float64_vertex(record, aligned, reinterpret_cast<unsigned int*>(&words[2]))
                         : Vec3{load_float(record, 0, aligned), load_float(record, 1, aligned), load_float(record, 2, aligned)};
  staging[i] = v;
  if (!isfinite(v.x) || !isfinite(v.y) || !isfinite(v.z)) atomicMin(&words[0], static_cast<unsigned long long>(i));
}

// Then the staged vertices become the scene's if all were finite (and thread 0 sets *rho, for
// float64 input); otherwise they become `keep` where given (a swept step's end: its kept
// start), and thread 0 records (call, first + vertex) in words[1] unless an error is pending
// there (0: none).
static __global__ void commit_checked_kernel(const Vec3* staging, int64_t n, unsigned long long call,
                                             unsigned long long first, Vec3* vertices, float* rho, const Vec3* keep,
                                             unsigned long long* words) {
  const int64_t i = global_index();
  if (i >= n) return;
  const unsigned long long bad = words[0];
  if (bad == kNoVertex) {
    vertices[i] = staging[i];
    if (rho && i == 0) memcpy(rho, &words[2], sizeof(float));  // the low half: little-endian
    return;
  }
  if (keep) vertices[i] = keep[i];
  if (i == 0 && words[1] == 0) {
    words[1] = (call << 32) | (first + bad);  // vertex indices are below 2^31
  }
}

static __global__ void max_into_kernel(unsigned int* bits, float value) {
  unsigned int value_bits;
  memcpy(&value_bits, &value, 4);
  atomicMax(bits, value_bits);  // non-negative floats order as their bits
}

// Room for `count` records of host staging, left unwritten (a std::vector would zero it on one
// thread before the parallel gather writes it).
template <class T>
std::unique_ptr<T[]> packed_host(size_t count) {
  static_assert(std::is_trivially_default_constructible<T>::value, "records are left unwritten");
  return std::unique_ptr<T[]>(new T[count]);
}

// Float64 vertices (host or device memory) rounded into a device array, rho[0] set (or, with
// accumulate, raised to their rho where that is larger).
inline void gather_float64_to_device(const Strided& values, DeviceBuffer<Vec3>& dst, DeviceBuffer<float>& rho,
                                     bool accumulate) {
  const size_t count = size_t(values.count);
  dst.ensure(count);
  rho.ensure(1);
  if (!accumulate) zero(rho, 1);
  if (values.memory == Memory::kHost) {
    const std::unique_ptr<Vec3[]> packed = packed_host<Vec3>(count);
    const float moved = gather_float64_host(values, packed.get());
    upload(dst, packed.get(), count);
    launch("max_into_kernel launch", max_into_kernel, 1, 1, reinterpret_cast<unsigned int*>(rho.data()), moved);
    return;
  }
  launch("gather_float64_kernel launch", gather_float64_kernel, values.count, kThreads,
         static_cast<const char*>(values.data), values.stride, values.count, is_aligned8(values), dst.data(),
         reinterpret_cast<unsigned int*>(rho.data()));
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
    const std::unique_ptr<T[]> packed = packed_host<T>(count);
    gather_host(values, packed.get());
    return upload(dst, packed.get(), count);
  }
  // Memory marked device may be host memory the device reads (mapped pinned, or pageable where
  // the device has pageable access: check_device_pointer): a device-to-device copy is undefined
  // there, so the runtime finds each side's kind from its address (unified addressing).
  if (values.stride == sizeof(T)) return copy(dst.data(), values.data, count * sizeof(T), cudaMemcpyDefault);
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


}  // namespace minkq::cuda
