// The CPU backend: the stores of store.h over the CPU executor (host vectors, CpuTree, the
// TBB pass runner), and the backend's own input checks. Compiled once per instruction-set level
// (cpu/isa.h): a wider level's copy defines only its entry point, MINKQ_CPU_LEVEL_ENTRY.
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cstring>
#include <utility>

#include "backend.h"
#include "cpu/isa.h"
#include "cpu/passes.h"
#include "cpu/tree.h"
#include "store.h"

namespace minkq {
namespace {

// first_non_finite_host in parallel: each block of records scanned in order up to its first bad
// one, the lowest of those kept (a block past a bad one already found is skipped).
int64_t first_non_finite(const Strided& values, int floats) {
  const auto lowest = [](int64_t a, int64_t b) { return a < 0 ? b : b < 0 ? a : std::min(a, b); };
  return tbb::parallel_reduce(
      tbb::blocked_range<int64_t>(0, values.count, 4096), int64_t(-1),
      [&](const tbb::blocked_range<int64_t>& range, int64_t found) {
        if (found >= 0 && found < range.begin()) return found;
        Strided part = values;
        part.data = static_cast<const char*>(values.data) + size_t(range.begin()) * values.stride;
        part.count = int64_t(range.size());
        const int64_t bad = first_non_finite_host(part, floats);
        return bad < 0 ? found : lowest(found, range.begin() + bad);
      },
      lowest);
}

template <class T>
void gather_records(const Strided& values, T* out) {
  parallel_for_each(values.count, [&](int64_t i) { gather_record(values, i, out[i]); });
}

}  // namespace

void gather_host(const Strided& values, Vec3* out) { gather_records(values, out); }
void gather_host(const Strided& values, Box* out) { gather_records(values, out); }

float gather_float64_host(const Strided& values, Vec3* out) {
  return tbb::parallel_reduce(
      tbb::blocked_range<int64_t>(0, values.count, 1024), 0.0f,
      [&](const tbb::blocked_range<int64_t>& range, float rho) {
        for (int64_t i = range.begin(); i != range.end(); ++i) rho = std::max(rho, round_float64_record(values, i, out[i]));
        return rho;
      },
      [](float a, float b) { return std::max(a, b); });
}

namespace {

// store.h's executor on the host: every call completes before it returns.
class CpuExecutor {
 public:
  struct Device {};
  template <class T>
  using Array = HostVector<T>;
  using Tree = CpuTree;

  explicit CpuExecutor(Device) {}
  struct Scope {};
  Scope scope() const { return {}; }
  Scope scope_on(Stream) const { return {}; }  // asynchronous calls run to completion here
  void wait(Stream) {}
  void hold() {}
  void release() {}
  void hold_for_teardown() noexcept {}
  void finish() {}

  // Into dst's own memory (no allocation once it has the size), in parallel.
  template <class T>
  void gather(const Strided& values, HostVector<T>& dst) {
    dst.resize(size_t(values.count));
    gather_host(values, dst.data());
  }
  void gather_float64(const Strided& values, HostVector<Vec3>& dst, HostVector<float>& rho, bool accumulate) {
    const float moved = gather_float64_to(values, dst);
    rho.resize(1, 0.0f);
    rho[0] = accumulate ? std::max(rho[0], moved) : moved;
  }
  // Float64 vertices rounded into dst (resized to them); returns their rho.
  static float gather_float64_to(const Strided& values, HostVector<Vec3>& dst) {
    dst.resize(size_t(values.count));
    return gather_float64_host(values, dst.data());
  }
  template <class T>
  void upload(HostVector<T>& dst, std::vector<T>&& host) {
    dst.assign(host.begin(), host.end());
  }
  template <class T>
  void download(T* host_out, const HostVector<T>& src, size_t count) {
    if (count) std::memcpy(host_out, src.data(), count * sizeof(T));
  }
  template <class Boxes>
  void sort_by_morton(Boxes boxes, int32_t n, HostVector<int32_t>& ids) {
    SortScratch local;
    minkq::sort_by_morton(boxes, n, ids, sort_reserved_ ? sort_ : local);
  }
  template <class Prim>
  void fill_groups(const Prim* prims, const int32_t* sorted_prims, int32_t n, HostVector<LeafGroup<Prim>>& out) {
    out.resize(size_t(box_group_count(n)));
    parallel_for_each(box_group_count(n), [&](int64_t g) { fill_leaf_group(g, prims, sorted_prims, n, out[size_t(g)]); });
  }
  template <class Prim>
  void scatter_groups(const HostVector<LeafGroup<Prim>>& groups, const int32_t* sorted_prims, int32_t n,
                      HostVector<Prim>& out) {
    out.resize(size_t(n));
    parallel_for_each(box_group_count(n), [&](int64_t g) { scatter_leaf_group(g, groups[size_t(g)], sorted_prims, n, out.data()); });
  }
  template <class Work, class... Pass>
  std::array<uint64_t, sizeof...(Pass)> run_passes(const std::array<WorkCounts*, sizeof...(Pass)>& works,
                                                   const Pass&... passes) {
    const std::array<uint64_t, sizeof...(Pass)> totals = cpu::run_passes<Work>(works, passes...);
    size_t k = 0;
    auto write_count = [&](const auto& pass) {  // asynchronous queries: the count to caller memory
      if (pass.out.count) *pass.out.count = totals[k];
      ++k;
    };
    (write_count(passes), ...);
    return totals;
  }

  // Asynchronous calls need nothing reserved (host vectors grow as they need, and the check
  // before the copy needs no staging); a rebuild reservation keeps the builds' and the vertex
  // sort's scratch and the room for the elements by id, so that rebuilds of the scene
  // allocate nothing.
  void reserve_staging(HostVector<Vec3>&, int32_t) {}
  void reserve_pending() {}
  void reserve_canonical(size_t) {}
  template <class T>
  void reserve_scratch(HostVector<T>& scratch, int32_t n) {
    scratch.reserve(size_t(std::max(n, 0)));
  }
  void reserve_nodes(CpuTree&, int32_t) {}  // host vectors: no captured graph reads them
  template <class Boxes>
  void reserve_build(CpuTree& tree, Boxes, int32_t n) {
    tree.reserve_build(n);
  }
  template <class Boxes>
  void reserve_sort(Boxes, int32_t n) {
    sort_.reserve(n);
    sort_reserved_ = true;
  }
  void commit_finite(const Strided& values, HostVector<Vec3>&, HostVector<Vec3>& dst, float* rho,
                     PendingError::Call call, int64_t first) {
    if (const int64_t bad = minkq::first_non_finite(values, 3); bad >= 0) {
      if (pending_.call == PendingError::kNone) pending_ = {call, first + bad};
      return;
    }
    if (values.scalar == Scalar::kFloat64) *rho = gather_float64_to(values, dst); else gather(values, dst);
  }
  void commit_finite_swept(const Strided& x0, const Strided& x1, HostVector<Vec3>&, HostVector<Vec3>&,
                           HostVector<Vec3>& dst0, HostVector<Vec3>& dst1, float* rho, PendingError::Call call,
                           int64_t first) {
    const int64_t bad0 = minkq::first_non_finite(x0, 3), bad1 = minkq::first_non_finite(x1, 3);
    if (bad0 >= 0 || bad1 >= 0) {
      if (pending_.call == PendingError::kNone)
        pending_ = {call, first + (bad0 >= 0 && (bad1 < 0 || bad0 < bad1) ? bad0 : bad1)};
      dst1 = dst0;  // at rest where it was
      return;
    }
    if (x0.scalar == Scalar::kFloat64) {
      *rho = std::max(gather_float64_to(x0, dst0), gather_float64_to(x1, dst1));
    } else {
      gather(x0, dst0);
      gather(x1, dst1);
    }
  }
  PendingError take_pending() { return std::exchange(pending_, PendingError{}); }

 private:
  PendingError pending_;
  bool sort_reserved_ = false;
  SortScratch sort_;  // the vertex order's sort scratch, kept once reserved
};

class CpuBackend final : public Backend {
 public:
  std::string name() const override {
    return "cpu (" + std::to_string(tbb::this_task_arena::max_concurrency()) + " threads, " +
           cpu::isa_name(cpu::kCompiledIsa) + ")";
  }
  bool is_cuda() const override { return false; }
  int64_t first_non_finite(const Strided& values, int floats) override {
    return minkq::first_non_finite(values, floats);
  }
  void copy_to_host(void* dst, const void* src, size_t bytes, Memory) override {
    if (bytes) std::memcpy(dst, src, bytes);
  }
  void check_device_pointer(const void*, const std::string& what) override {
    fail(Status::kInvalidArgument, what + " is in device memory but the device is " + name());
  }
  std::unique_ptr<MeshStore> create_mesh_store(std::vector<GeometryInput> geometries) override {
    return std::make_unique<MeshStoreOn<CpuExecutor>>(CpuExecutor::Device{}, std::move(geometries));
  }
  std::unique_ptr<Store> create_box_store(const Strided& boxes) override {
    return std::make_unique<BoxStoreOn<CpuExecutor>>(CpuExecutor::Device{}, boxes);
  }
};

}  // namespace

#if defined(MINKQ_CPU_LEVEL_ENTRY)
extern "C" Backend* MINKQ_CPU_LEVEL_ENTRY() { return new CpuBackend(); }
#else
std::unique_ptr<Backend> cpu::make_baseline_backend() { return std::make_unique<CpuBackend>(); }
#endif

}  // namespace minkq
