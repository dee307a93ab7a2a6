// CPU backend: the shared per-element steps of bvh.h and queries.h, run in parallel with TBB.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <type_traits>
#include <utility>

#include "backend.h"
#include "cpu_tree.h"

namespace minkq {

std::vector<Vec3> gather_vec3(const Strided& values) {
  std::vector<Vec3> out(static_cast<size_t>(values.count));
  const char* base = static_cast<const char*>(values.data);
  for (int64_t i = 0; i < values.count; ++i) std::memcpy(&out[i], base + size_t(i) * values.stride, sizeof(Vec3));
  return out;
}

std::vector<Box> gather_boxes(const Strided& values) {
  std::vector<Box> out(static_cast<size_t>(values.count));
  const char* base = static_cast<const char*>(values.data);
  for (int64_t i = 0; i < values.count; ++i) std::memcpy(&out[i], base + size_t(i) * values.stride, sizeof(Box));
  return out;
}

namespace {

// Queries per block: each block runs its queries in order into its own buffer.
constexpr int32_t kBlock = 256;

template <class Work, class Pass>
void run_block(const Pass& pass, int32_t block, std::vector<int32_t>& part, Work& work) {
  auto emit = [&part](int32_t first, int32_t second) {
    part.push_back(first);
    part.push_back(second);
  };
  const int32_t end = std::min(pass.num_queries, (block + 1) * kBlock);
  for (int32_t i = block * kBlock; i < end; ++i) run_query<typename Pass::Shape>(pass.bvh, pass.queries, i, emit, work);
}

// Writes a pass's blocks, concatenated in block order, and sorts them if asked; returns the
// total, writing nothing if it exceeds the capacity.
uint64_t write_pass(const std::vector<int32_t>* parts, int32_t blocks, const PairOutput& out) {
  uint64_t total = 0;
  for (int32_t b = 0; b < blocks; ++b) total += parts[b].size() / 2;
  if (total > out.capacity) return total;
  int32_t* cursor = out.pairs;
  for (int32_t b = 0; b < blocks; ++b) {
    if (!parts[b].empty()) std::memcpy(cursor, parts[b].data(), parts[b].size() * sizeof(int32_t));
    cursor += parts[b].size();
  }
  if (out.canonical) {
    std::vector<uint64_t> packed(total);
    parallel_for_each(int64_t(total), [&](int64_t i) {
      packed[i] = uint64_t(uint32_t(out.pairs[2 * i])) << 32 | uint32_t(out.pairs[2 * i + 1]);
    });
    tbb::parallel_sort(packed.begin(), packed.end());
    parallel_for_each(int64_t(total), [&](int64_t i) {
      out.pairs[2 * i] = int32_t(packed[i] >> 32);
      out.pairs[2 * i + 1] = int32_t(packed[i] & 0xffffffffu);
    });
  }
  return total;
}

// Runs the passes' queries in one parallel loop over fixed blocks (each block within one pass),
// each block into its own buffer, then concatenates each pass's blocks in order: the output
// order is deterministic whatever the thread count. Returns each pass's total.
template <class Work, class... Pass>
std::array<uint64_t, sizeof...(Pass)> run_passes(const std::array<WorkCounts*, sizeof...(Pass)>& works,
                                                 const Pass&... passes) {
  constexpr size_t kPasses = sizeof...(Pass);
  const std::array<int32_t, kPasses> num_queries{passes.num_queries...};
  std::array<int32_t, kPasses + 1> first_block{};
  for (size_t k = 0; k < kPasses; ++k) first_block[k + 1] = first_block[k] + (num_queries[k] + kBlock - 1) / kBlock;
  const int32_t blocks = first_block[kPasses];
  std::vector<std::vector<int32_t>> parts(static_cast<size_t>(blocks));
  std::vector<Work> block_work(static_cast<size_t>(blocks));
  tbb::parallel_for(int32_t(0), blocks, [&](int32_t b) {
    size_t k = 0;
    auto run_if_owner = [&](const auto& pass) {
      if (b >= first_block[k] && b < first_block[k + 1]) run_block(pass, b - first_block[k], parts[b], block_work[b]);
      ++k;
    };
    (run_if_owner(passes), ...);
  });
  const std::array<PairOutput, kPasses> outs{passes.out...};
  std::array<uint64_t, kPasses> totals{};
  for (size_t k = 0; k < kPasses; ++k) {
    if constexpr (std::is_same<Work, WorkCounts>::value)
      if (works[k])
        for (int32_t b = first_block[k]; b < first_block[k + 1]; ++b) works[k]->add(block_work[b]);
    totals[k] = write_pass(parts.data() + first_block[k], first_block[k + 1] - first_block[k], outs[k]);
  }
  return totals;
}

template <class... Pass>
std::array<uint64_t, sizeof...(Pass)> run_counted(const std::array<WorkCounts*, sizeof...(Pass)>& works,
                                                  const Pass&... passes) {
  return with_work(works, [&](auto work) { return run_passes<decltype(work)>(works, passes...); });
}

class CpuMeshStore final : public MeshStore {
 public:
  CpuMeshStore(const Strided& vertices, std::vector<Triangle> triangles, std::vector<Edge> edges, bool triangle_tree,
               bool edge_tree)
      : vertices_(gather_vec3(vertices)), triangles_(triangle_tree ? std::move(triangles) : std::vector<Triangle>()),
        edges_(std::move(edges)),
        has_triangle_tree_(triangle_tree), has_edge_tree_(edge_tree) {
    build_trees();
  }

  void copy_edges(Edge* host_out) override {
    if (!edges_.empty()) std::memcpy(host_out, edges_.data(), edges_.size() * sizeof(Edge));
  }

  void refit(const Strided& vertices) override {
    vertices_ = gather_vec3(vertices);
    if (has_triangle_tree_) triangle_tree_.refit(TriangleBoxes{vertices_.data(), triangles_.data()});
    if (has_edge_tree_) edge_tree_.refit(EdgeBoxes{vertices_.data(), edges_.data()});
  }

  void rebuild(const Strided& vertices) override {
    vertices_ = gather_vec3(vertices);
    build_trees();
  }

  double tree_growth() override {
    double g = has_triangle_tree_ ? growth(triangle_tree_.area_cost(), triangle_tree_.cost_at_build()) : 0.0;
    if (has_edge_tree_) g = std::max(g, growth(edge_tree_.area_cost(), edge_tree_.cost_at_build()));
    return g;
  }

  uint64_t query(const QueryRequest& request, const PairOutput& out, WorkCounts* work) override {
    uint64_t total = 0;
    auto run = [&](const auto& pass) { total = run_counted({work}, pass)[0]; };
    if (request.kind == QueryKind::kVertexTriangle) with_vt_pass(request, out, run); else with_ee_pass(request, out, run);
    return total;
  }

  std::array<uint64_t, 2> query_vt_ee(const QueryJob& vt, const QueryJob& ee) override {
    std::array<uint64_t, 2> totals{};
    with_vt_pass(vt.request, vt.out, [&](const auto& vt_pass) {
      with_ee_pass(ee.request, ee.out, [&](const auto& ee_pass) { totals = run_counted({vt.work, ee.work}, vt_pass, ee_pass); });
    });
    return totals;
  }

 private:
  // Calls fn with the QueryPass of a VT request, or of an EE request.
  template <class Fn>
  void with_vt_pass(const QueryRequest& request, const PairOutput& out, Fn&& fn) {
    const VertexTriangleQueries queries{vertices_.data(), triangles_.data(), vertex_order_.data(), request.r,
                                        request.filters};
    with_pass<true>(request, triangle_tree_.view(), queries, int32_t(vertices_.size()), out, fn);
  }
  template <class Fn>
  void with_ee_pass(const QueryRequest& request, const PairOutput& out, Fn&& fn) {
    const EdgeEdgeQueries queries{vertices_.data(), edges_.data(), edge_tree_.sorted_prims().data(), request.r, request.filters};
    with_pass<false>(request, edge_tree_.view(), queries, int32_t(edges_.size()), out, fn);
  }

  // The trees the flags ask for, and the VT query order, from the current vertices.
  void build_trees() {
    if (has_triangle_tree_) {
      triangle_tree_.build(TriangleBoxes{vertices_.data(), triangles_.data()}, int32_t(triangles_.size()));
      std::vector<uint64_t> keys;
      sort_by_morton(PointBoxes{vertices_.data()}, int32_t(vertices_.size()), keys, vertex_order_);
    }
    if (has_edge_tree_) edge_tree_.build(EdgeBoxes{vertices_.data(), edges_.data()}, int32_t(edges_.size()));
  }

  std::vector<Vec3> vertices_;
  std::vector<Triangle> triangles_;  // only with a triangle tree
  std::vector<Edge> edges_;
  std::vector<int32_t> vertex_order_;  // the vertices' Morton order at build: VT query order
  bool has_triangle_tree_, has_edge_tree_;
  CpuTree triangle_tree_, edge_tree_;
};

class CpuBoxStore final : public Store {
 public:
  explicit CpuBoxStore(const Strided& boxes) : boxes_(gather_boxes(boxes)) {
    tree_.build(GivenBoxes{boxes_.data()}, int32_t(boxes_.size()));
  }
  void refit(const Strided& boxes) override {
    boxes_ = gather_boxes(boxes);
    tree_.refit(GivenBoxes{boxes_.data()});
  }
  void rebuild(const Strided& boxes) override {
    boxes_ = gather_boxes(boxes);
    tree_.build(GivenBoxes{boxes_.data()}, int32_t(boxes_.size()));
  }
  double tree_growth() override { return growth(tree_.area_cost(), tree_.cost_at_build()); }
  uint64_t query(const QueryRequest& request, const PairOutput& out, WorkCounts* work) override {
    const std::vector<Vec3> first = gather_vec3(request.first);
    const std::vector<Vec3> second = gather_vec3(request.second);
    const UserQueries queries{first.data(), second.empty() ? nullptr : second.data(), request.r};
    uint64_t total = 0;
    auto run = [&](const auto& pass) { total = run_counted({work}, pass)[0]; };
    if (request.kind == QueryKind::kUserSpheres) with_pass<true>(request, tree_.view(), queries, int32_t(first.size()), out, run);
    else with_pass<false>(request, tree_.view(), queries, int32_t(first.size()), out, run);
    return total;
  }

 private:
  std::vector<Box> boxes_;
  CpuTree tree_;
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
  std::unique_ptr<MeshStore> create_mesh_store(const Strided& vertices, std::vector<Triangle> triangles,
                                               std::vector<Edge> edges, bool triangle_tree, bool edge_tree) override {
    return std::make_unique<CpuMeshStore>(vertices, std::move(triangles), std::move(edges), triangle_tree, edge_tree);
  }
  std::unique_ptr<Store> create_box_store(const Strided& boxes) override {
    return std::make_unique<CpuBoxStore>(boxes);
  }
};

}  // namespace

std::unique_ptr<Backend> make_cpu_backend() { return std::make_unique<CpuBackend>(); }

}  // namespace minkq
