// The CPU backend: the stores of store.h over the CPU executor (host vectors, CpuTree, the
// TBB pass runner), and the backend's own input checks.
#include <tbb/task_arena.h>

#include <cmath>
#include <cstring>
#include <utility>

#include "backend.h"
#include "cpu/passes.h"
#include "cpu/tree.h"
#include "store.h"

namespace minkq {
namespace {

// store.h's executor on the host: every call completes before it returns.
class CpuExecutor {
 public:
  struct Device {};
  template <class T>
  using Array = std::vector<T>;
  using Tree = CpuTree;

  explicit CpuExecutor(Device) {}
  struct Scope {};
  Scope scope() const { return {}; }
  void hold() {}
  void release() {}
  void hold_for_teardown() noexcept {}
  void finish() {}

  template <class T>
  void gather(const Strided& values, std::vector<T>& dst) {
    dst = gather_host<T>(values);
  }
  template <class T>
  void upload(std::vector<T>& dst, std::vector<T>&& host) {
    dst = std::move(host);
  }
  template <class T>
  void download(T* host_out, const std::vector<T>& src, size_t count) {
    if (count) std::memcpy(host_out, src.data(), count * sizeof(T));
  }
  template <class Boxes>
  void sort_by_morton(Boxes boxes, int32_t n, std::vector<int32_t>& ids) {
    std::vector<uint64_t> keys;
    minkq::sort_by_morton(boxes, n, keys, ids);
  }
  template <class Work, class... Pass>
  std::array<uint64_t, sizeof...(Pass)> run_passes(const std::array<WorkCounts*, sizeof...(Pass)>& works,
                                                   const Pass&... passes) {
    return cpu::run_passes<Work>(works, passes...);
  }
};

class CpuBackend final : public Backend {
 public:
  std::string name() const override {
    return "cpu (" + std::to_string(tbb::this_task_arena::max_concurrency()) + " threads)";
  }
  bool is_cuda() const override { return false; }
  int64_t first_non_finite(const Strided& values, int floats) override {
    const char* base = static_cast<const char*>(values.data);
    for (int64_t i = 0; i < values.count; ++i) {
      float f[6];
      std::memcpy(f, base + size_t(i) * values.stride, sizeof(float) * size_t(floats));
      for (int k = 0; k < floats; ++k)
        if (!std::isfinite(f[k])) return i;
    }
    return -1;
  }
  void copy_to_host(void* dst, const void* src, size_t bytes, Memory) override {
    if (bytes) std::memcpy(dst, src, bytes);
  }
  void check_device_pointer(const void*, const std::string& what) override {
    fail(Status::kInvalidArgument, what + " is in device memory but the device is " + name());
  }
  std::unique_ptr<MeshStore> create_mesh_store(const Strided& vertices, std::vector<Triangle> triangles,
                                               std::vector<Edge> edges, bool triangle_tree, bool edge_tree) override {
    return std::make_unique<MeshStoreOn<CpuExecutor>>(CpuExecutor::Device{}, vertices, std::move(triangles),
                                                      std::move(edges), triangle_tree, edge_tree);
  }
  std::unique_ptr<Store> create_box_store(const Strided& boxes) override {
    return std::make_unique<BoxStoreOn<CpuExecutor>>(CpuExecutor::Device{}, boxes);
  }
};

}  // namespace

std::unique_ptr<Backend> make_cpu_backend() { return std::make_unique<CpuBackend>(); }

}  // namespace minkq
