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

// Runs every query in fixed blocks, each into its own buffer, then concatenates in block
// order: the output order is deterministic whatever the thread count.
template <class Shape, class Queries, class Work>
uint64_t run_queries(const BvhView& bvh, const Queries& queries, int32_t num_queries, const PairOutput& out,
                     Work* work) {
  constexpr int32_t kBlock = 256;
  const int32_t blocks = (num_queries + kBlock - 1) / kBlock;
  std::vector<std::vector<int32_t>> parts(static_cast<size_t>(blocks));
  std::vector<Work> block_work(static_cast<size_t>(blocks));
  tbb::parallel_for(int32_t(0), blocks, [&](int32_t b) {
    std::vector<int32_t>& part = parts[b];
    auto emit = [&part](int32_t first, int32_t second) {
      part.push_back(first);
      part.push_back(second);
    };
    Work local;
    const int32_t end = std::min(num_queries, (b + 1) * kBlock);
    for (int32_t i = b * kBlock; i < end; ++i) run_query<Shape>(bvh, queries, i, emit, local);
    block_work[b] = local;
  });
  if constexpr (std::is_same<Work, WorkCounts>::value)
    for (const WorkCounts& w : block_work) work->add(w);
  uint64_t total = 0;
  for (const auto& part : parts) total += part.size() / 2;
  if (total > out.capacity) return total;
  int32_t* cursor = out.pairs;
  for (const auto& part : parts) {
    if (!part.empty()) std::memcpy(cursor, part.data(), part.size() * sizeof(int32_t));
    cursor += part.size();
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

template <class Queries>
uint64_t dispatch(const QueryRequest& request, bool point_queries, const BvhView& bvh, const Queries& queries,
                  int32_t num_queries, const PairOutput& out, WorkCounts* work) {
  uint64_t total = 0;
  with_shape(request.mode, point_queries, [&](auto shape) {
    using Shape = decltype(shape);
    if (work) {
      total = run_queries<Shape>(bvh, queries, num_queries, out, work);
    } else {
      NoWork* none = nullptr;
      total = run_queries<Shape>(bvh, queries, num_queries, out, none);
    }
  });
  return total;
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
    if (request.kind == QueryKind::kVertexTriangle) {
      const VertexTriangleQueries queries{vertices_.data(), triangles_.data(), vertex_order_.data(), request.r,
                                          request.filters};
      return dispatch(request, true, triangle_tree_.view(), queries, int32_t(vertices_.size()), out, work);
    }
    const EdgeEdgeQueries queries{vertices_.data(), edges_.data(), edge_tree_.sorted_prims().data(), request.r,
                                  request.filters};
    return dispatch(request, false, edge_tree_.view(), queries, int32_t(edges_.size()), out, work);
  }

 private:
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
    return dispatch(request, request.kind == QueryKind::kUserSpheres, tree_.view(), queries,
                    int32_t(first.size()), out, work);
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
