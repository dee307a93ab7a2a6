// Device memory and streams for the stream-ordered calls' tests on CUDA (test_cuda_async.cpp,
// test_cuda_geometries.cpp): async_checks.h's AsyncMemory on a stream of the test's own, a
// CUDA graph captured from minkq calls, and their fixture. Needs the CUDA runtime (MINKQ_TEST_HAVE_CUDART).
#pragma once

#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "async_checks.h"
#include "cuda_checks.h"

#if defined(MINKQ_TEST_HAVE_CUDART)
#include <cuda_runtime.h>

namespace minkq::cuda_test {

// Device memory and a stream of the test's own (not the per-thread default stream the
// blocking calls use), for async_checks.h.
class DeviceAsyncMemory final : public test::AsyncMemory {
 public:
  DeviceAsyncMemory() { EXPECT_EQ(cudaStreamCreateWithFlags(&stream_, cudaStreamNonBlocking), cudaSuccess); }
  ~DeviceAsyncMemory() override {
    cudaStreamSynchronize(stream_);
    for (void* p : blocks_) cudaFree(p);
    cudaStreamDestroy(stream_);
  }
  void* allocate(size_t bytes) override {
    void* p = nullptr;
    EXPECT_EQ(cudaMalloc(&p, bytes ? bytes : 1), cudaSuccess);
    blocks_.push_back(p);
    return p;
  }
  void write(void* dst, const void* host, size_t bytes) override {
    EXPECT_EQ(cudaMemcpyAsync(dst, host, bytes, cudaMemcpyHostToDevice, stream_), cudaSuccess);
    EXPECT_EQ(cudaStreamSynchronize(stream_), cudaSuccess);
  }
  void read(void* host, const void* src, size_t bytes) override {
    EXPECT_EQ(cudaMemcpyAsync(host, src, bytes, cudaMemcpyDeviceToHost, stream_), cudaSuccess);
    EXPECT_EQ(cudaStreamSynchronize(stream_), cudaSuccess);
  }
  minkq_stream stream() override { return stream_; }
  void wait() override { EXPECT_EQ(cudaStreamSynchronize(stream_), cudaSuccess); }
  minkq_memory kind() override { return MINKQ_MEMORY_DEVICE; }

 private:
  cudaStream_t stream_ = nullptr;
  std::vector<void*> blocks_;
};

// A CUDA graph recorded from what `record(check)` enqueues on `stream` (global capture mode)
// and instantiated: `record` passes each minkq call's status to check(), which expects success
// and keeps the message. ok() once recorded and instantiated without an error.
class CapturedGraph {
 public:
  template <class Record>
  CapturedGraph(cudaStream_t stream, Record record) : stream_(stream) {
    EXPECT_EQ(cudaStreamBeginCapture(stream, cudaStreamCaptureModeGlobal), cudaSuccess);
    bool called = true;
    record([&](minkq_status status) {
      EXPECT_EQ(status, MINKQ_SUCCESS) << minkq_last_error_message();
      called = called && status == MINKQ_SUCCESS;
    });
    EXPECT_EQ(cudaStreamEndCapture(stream, &graph_), cudaSuccess);
    if (called && graph_) EXPECT_EQ(cudaGraphInstantiate(&exec_, graph_, 0), cudaSuccess);
  }
  CapturedGraph(const CapturedGraph&) = delete;
  CapturedGraph& operator=(const CapturedGraph&) = delete;
  ~CapturedGraph() {
    if (exec_) cudaGraphExecDestroy(exec_);
    if (graph_) cudaGraphDestroy(graph_);
  }
  bool ok() const { return exec_ != nullptr; }
  cudaError_t launch() const { return cudaGraphLaunch(exec_, stream_); }

 private:
  cudaStream_t stream_;
  cudaGraph_t graph_ = nullptr;
  cudaGraphExec_t exec_ = nullptr;
};

// The fixture of the stream-ordered calls' CUDA tests: a CPU and a CUDA device, and device
// memory on a stream of its own (made only where a GPU is present).
class CudaAsync : public Cuda {
 protected:
  void SetUp() override {
    Cuda::SetUp();
    if (IsSkipped()) return;
    cpu = std::make_unique<test::Device>("cpu");
    cuda = std::make_unique<test::Device>("cuda");
    device_memory = std::make_unique<DeviceAsyncMemory>();
  }
  std::unique_ptr<test::Device> cpu, cuda;
  std::unique_ptr<DeviceAsyncMemory> device_memory;  // made only where a GPU is present
  DeviceAsyncMemory& memory() { return *device_memory; }
};

}  // namespace minkq::cuda_test

#endif  // MINKQ_TEST_HAVE_CUDART
