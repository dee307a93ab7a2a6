// The scene stores, written once for both backends: a mesh store (vertices, topology, the
// triangle and edge trees, VT and EE queries) and a box store (user boxes, their tree, user
// queries). What differs between the CPU and CUDA backends is supplied by an executor, X, whose
// contract executor.h states and checks. cpu/backend.cpp and cuda/backend.cu define the two
// executors; a query's pairs, counts and work counters are the same on both.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <utility>
#include <vector>

#include "backend.h"
#include "executor.h"

namespace minkq {

// Calls fn with a default-constructed value of the shape type that `mode` selects, for point
// queries (VT, user spheres: kPoints) or segment and box queries; only the shapes a kind can
// use are compiled for it. Points are zero-length capsules: capsule_ray tests the box, and
// capsule_exact the sphere. The front end rejects sphere mode for segments and any non-box mode
// for box queries before calling.
template <bool kPoints, class Fn>
void with_shape(Mode mode, Fn&& fn) {
  switch (mode) {
    case Mode::kBox: return fn(BoxShape{});
    case Mode::kSphere:
      if constexpr (kPoints) return fn(SphereShape{});
      break;
    case Mode::kCapsuleRay:
      if constexpr (kPoints) return fn(BoxShape{}); else return fn(CapsuleRayShape{});
    case Mode::kCapsuleExact:
      if constexpr (kPoints) return fn(SphereShape{}); else return fn(CapsuleExactShape{});
  }
  fail(Status::kInternal, "mode not available for these queries");
}

// Calls fn with the QueryPass of a request (its shape chosen by with_shape).
template <bool kPoints, class Queries, class Fn>
void with_pass(const QueryRequest& request, const BvhView& bvh, const Queries& queries, int32_t num_queries,
               const PairOutput& out, Fn&& fn) {
  with_shape<kPoints>(request.mode, [&](auto shape) {
    fn(QueryPass<decltype(shape), Queries>{request.kind, bvh, queries, num_queries, out});
  });
}

// Runs the passes of one call on executor x with the work type they need: the counted
// traversal if any pass counts (the others' counts are then dropped), else the uncounted one.
template <class X, class... Pass>
std::array<uint64_t, sizeof...(Pass)> run_counted(X& x, const std::array<WorkCounts*, sizeof...(Pass)>& works,
                                                  const Pass&... passes) {
  for (WorkCounts* w : works)
    if (w) return x.template run_passes<WorkCounts>(works, passes...);
  return x.template run_passes<NoWork>(works, passes...);
}

// A tree's area cost (sum of node_area over the root's half area) now over its value at its
// last build. A tree without area (its boxes on one axis-parallel line or at one point, or no
// nodes) costs 0: the ratio is then 1 while it stays so, and infinite once it has area.
inline double growth(double cost_now, double cost_at_build) {
  if (cost_at_build > 0.0) return cost_now / cost_at_build;
  return cost_now > 0.0 ? HUGE_VAL : 1.0;
}
template <class Tree>
double tree_growth_of(const Tree& tree) {
  return growth(tree.area_cost(), tree.cost_at_build());
}

template <class X>
class MeshStoreOn final : public MeshStore {
  static_assert(ExecutorContract<X>::value, "a store runs on an executor (executor.h)");
  template <class T>
  using Array = typename X::template Array<T>;

 public:
  MeshStoreOn(typename X::Device device, const Strided& vertices, std::vector<Triangle> triangles,
              std::vector<Edge> edges, const MeshTrees& trees)
      : x_(device), num_vertices_(int32_t(vertices.count)), num_triangles_(int32_t(triangles.size())),
        num_edges_(int32_t(edges.size())), has_triangle_tree_(trees.triangles), has_edge_tree_(trees.edges),
        has_vertex_tree_(trees.vertices), keeps_vertex_order_(trees.vertex_order),
        float64_(vertices.scalar == Scalar::kFloat64) {
    x_.hold();
    gather_vertices(vertices);
    // The elements by id, only until their trees hold them (edges without an edge tree: kept).
    Array<Triangle> triangles_by_id;
    Array<Edge> edges_by_id;
    if (has_triangle_tree_) x_.upload(triangles_by_id, std::move(triangles));
    x_.upload(has_edge_tree_ ? edges_by_id : edges_, std::move(edges));
    build_trees(triangles_by_id, edges_by_id);
    x_.finish();
    x_.release();
  }
  ~MeshStoreOn() override { x_.hold_for_teardown(); }

  void copy_edges(Edge* host_out) override {
    [[maybe_unused]] const auto scope = x_.scope();
    if (!has_edge_tree_) return x_.download(host_out, edges_, size_t(num_edges_));
    Array<Edge> by_id;
    x_.scatter_groups(leaf_edges_, edge_tree_.view().sorted_prims, num_edges_, by_id);
    x_.download(host_out, by_id, size_t(num_edges_));
  }

  void refit(const Strided& vertices) override {
    [[maybe_unused]] const auto scope = x_.scope();
    swept_ = false;
    gather_vertices(vertices);
    refit_trees();
    x_.finish();
  }

  void rebuild(const Strided& vertices) override {
    [[maybe_unused]] const auto scope = x_.scope();
    swept_ = false;
    gather_vertices(vertices);
    rebuild_trees();
    x_.finish();
  }

  void refit_swept(const Strided& x0, const Strided& x1) override {
    [[maybe_unused]] const auto scope = x_.scope();
    gather_swept(x0, x1);
    refit_trees();
    x_.finish();
  }

  void rebuild_swept(const Strided& x0, const Strided& x1) override {
    [[maybe_unused]] const auto scope = x_.scope();
    gather_swept(x0, x1);
    rebuild_trees();
    x_.finish();
  }
  bool swept() const override { return swept_; }

  double tree_growth() override {
    [[maybe_unused]] const auto scope = x_.scope();
    double g = has_triangle_tree_ ? tree_growth_of(triangle_tree_) : 0.0;
    if (has_edge_tree_) g = std::max(g, tree_growth_of(edge_tree_));
    if (has_vertex_tree_) g = std::max(g, tree_growth_of(vertex_tree_));
    return g;
  }

  uint64_t query(const QueryRequest& request, const PairOutput& out, WorkCounts* work) override {
    [[maybe_unused]] const auto scope = x_.scope();
    uint64_t total = 0;
    with_mesh_pass(request, out, [&](const auto& pass) { total = run_counted(x_, {work}, pass)[0]; });
    return total;
  }

  std::array<uint64_t, 2> query_vt_ee(const QueryJob& vt, const QueryJob& ee) override {
    [[maybe_unused]] const auto scope = x_.scope();
    std::array<uint64_t, 2> totals{};
    with_vt_pass(vt.request, vt.out, [&](const auto& vt_pass) {
      with_ee_pass(ee.request, ee.out,
                   [&](const auto& ee_pass) { totals = run_counted(x_, {vt.work, ee.work}, vt_pass, ee_pass); });
    });
    return totals;
  }

  // ---- Asynchronous calls ------------------------------------------------------------------

  void reserve(const Reservation& wanted) override {
    [[maybe_unused]] const auto scope = x_.scope();
    fix_nodes();
    if ((wanted.refit || wanted.rebuild) && !reserved_.refit) {
      x_.reserve_staging(staging_, num_vertices_);
      x_.reserve_pending();
      reserved_.refit = true;
    }
    if (wanted.swept && !reserved_.swept) {
      x_.reserve_staging(staging1_, num_vertices_);
      x_.reserve_staging(vertices1_, num_vertices_);
      reserved_.swept = true;
    }
    if (wanted.rebuild && !reserved_.rebuild) {
      if (has_triangle_tree_) {
        x_.reserve_build(triangle_tree_, triangle_boxes(), num_triangles_);
        x_.reserve_scratch(triangle_scratch_, num_triangles_);
      }
      if (keeps_vertex_order_) x_.reserve_sort(PointBoxes{vertices_.data()}, num_vertices_);
      if (has_edge_tree_) {
        x_.reserve_build(edge_tree_, edge_boxes(), num_edges_);
        x_.reserve_scratch(edge_scratch_, num_edges_);
      }
      if (has_vertex_tree_) x_.reserve_build(vertex_tree_, vertex_boxes(), num_vertices_);
      reserved_.rebuild = true;
    }
    if (wanted.canonical_capacity > reserved_.canonical_capacity) {
      x_.reserve_canonical(wanted.canonical_capacity);
      reserved_.canonical_capacity = wanted.canonical_capacity;
    }
    x_.finish();
  }
  const Reservation& reservation() const override { return reserved_; }

  void refit_async(const Strided& vertices, Stream stream) override {
    [[maybe_unused]] const auto scope = x_.scope_on(stream);
    fix_nodes();
    swept_ = false;
    x_.commit_finite(vertices, staging_, vertices_, rho(), PendingError::kRefit);
    refit_trees();
  }

  void rebuild_async(const Strided& vertices, Stream stream) override {
    [[maybe_unused]] const auto scope = x_.scope_on(stream);
    fix_nodes();
    swept_ = false;
    x_.commit_finite(vertices, staging_, vertices_, rho(), PendingError::kRebuild);
    rebuild_trees();
  }

  void refit_swept_async(const Strided& x0, const Strided& x1, Stream stream) override {
    [[maybe_unused]] const auto scope = x_.scope_on(stream);
    fix_nodes();
    swept_ = true;
    x_.commit_finite_swept(x0, x1, staging_, staging1_, vertices_, vertices1_, rho(), PendingError::kRefitSwept);
    refit_trees();
  }

  void rebuild_swept_async(const Strided& x0, const Strided& x1, Stream stream) override {
    [[maybe_unused]] const auto scope = x_.scope_on(stream);
    fix_nodes();
    swept_ = true;
    x_.commit_finite_swept(x0, x1, staging_, staging1_, vertices_, vertices1_, rho(), PendingError::kRebuildSwept);
    rebuild_trees();
  }

  void query_async(const QueryRequest& request, const PairOutput& out, Stream stream) override {
    [[maybe_unused]] const auto scope = x_.scope_on(stream);
    fix_nodes();
    with_mesh_pass(request, out, [&](const auto& pass) { run_counted(x_, {nullptr}, pass); });
  }

  void query_vt_ee_async(const QueryRequest& vt, const PairOutput& vt_out, const QueryRequest& ee,
                         const PairOutput& ee_out, Stream stream) override {
    [[maybe_unused]] const auto scope = x_.scope_on(stream);
    fix_nodes();
    with_vt_pass(vt, vt_out, [&](const auto& vt_pass) {
      with_ee_pass(ee, ee_out, [&](const auto& ee_pass) { run_counted(x_, {nullptr, nullptr}, vt_pass, ee_pass); });
    });
  }

  PendingError take_pending_error(Stream stream) override {
    [[maybe_unused]] const auto scope = x_.scope();
    x_.wait(stream);
    return reserved_.refit ? x_.take_pending() : PendingError{};
  }

 private:
  // Calls fn with the QueryPass of a request of any mesh kind.
  template <class Fn>
  void with_mesh_pass(const QueryRequest& request, const PairOutput& out, Fn&& fn) {
    switch (request.kind) {
      case QueryKind::kVertexTriangle: return with_vt_pass(request, out, fn);
      case QueryKind::kEdgeEdge: return with_ee_pass(request, out, fn);
      case QueryKind::kVertexEdge: {
        const VertexEdgeQueries queries{vertices_.data(), leaf_edges_.data(), vertex_order_.data(), request.r,
                                        request.filters, rho(), vertices1()};
        return with_vertex_pass(request, edge_tree_.view(), queries, out, fn);
      }
      case QueryKind::kVertexVertex: {
        const BvhView tree = vertex_tree_.view();
        const VertexVertexQueries queries{vertices_.data(), tree.sorted_prims, request.r, request.filters, rho(),
                                          vertices1()};
        return with_vertex_pass(request, tree, queries, out, fn);
      }
      default: fail(Status::kInternal, "not a mesh query kind");
    }
  }
  // Calls fn with the QueryPass of a VT request, or of an EE request.
  template <class Fn>
  void with_vt_pass(const QueryRequest& request, const PairOutput& out, Fn&& fn) {
    const VertexTriangleQueries queries{vertices_.data(), leaf_triangles_.data(), vertex_order_.data(), request.r,
                                        request.filters, rho(), vertices1()};
    with_vertex_pass(request, triangle_tree_.view(), queries, out, fn);
  }
  // Vertex queries (VT, EV, VV): points, or swept each vertex's path, a segment: the segment
  // shapes, sphere mode as capsule_exact.
  template <class Queries, class Fn>
  void with_vertex_pass(const QueryRequest& request, const BvhView& tree, const Queries& queries,
                        const PairOutput& out, Fn&& fn) {
    if (!swept_) return with_pass<true>(request, tree, queries, num_vertices_, out, fn);
    QueryRequest path = request;
    if (path.mode == Mode::kSphere) path.mode = Mode::kCapsuleExact;
    with_pass<false>(path, tree, queries, num_vertices_, out, fn);
  }
  template <class Fn>
  void with_ee_pass(const QueryRequest& request, const PairOutput& out, Fn&& fn) {
    const BvhView edge_tree = edge_tree_.view();
    const EdgeEdgeQueries queries{vertices_.data(), leaf_edges_.data(), edge_tree.sorted_prims, request.r,
                                  request.filters, rho(), vertices1()};
    with_pass<false>(request, edge_tree, queries, num_edges_, out, fn);
  }

  // The scene's vertices from the caller's (float64 ones rounded, with rho, the larger of both
  // positions' for a swept scene).
  void gather_vertices(const Strided& vertices) { gather_into(vertices, vertices_, false); }
  void gather_swept(const Strided& x0, const Strided& x1) {
    gather_into(x0, vertices_, false);
    gather_into(x1, vertices1_, true);
    swept_ = true;
  }
  void gather_into(const Strided& values, Array<Vec3>& dst, bool accumulate) {
    if (float64_) x_.gather_float64(values, dst, rho_, accumulate); else x_.gather(values, dst);
  }
  const Vec3* vertices1() const { return swept_ ? vertices1_.data() : nullptr; }
  void refit_trees() {
    if (has_triangle_tree_) triangle_tree_.refit(triangle_boxes());
    if (has_edge_tree_) edge_tree_.refit(edge_boxes());
    if (has_vertex_tree_) vertex_tree_.refit(vertex_boxes());
  }
  // Where the queries read rho (executor memory): nullptr for float input, whose radius stays r.
  float* rho() { return float64_ ? rho_.data() : nullptr; }

  // The trees the flags ask for, and the VT / EV query order, from the current vertices;
  // triangles and edges: the elements by id (with their trees), which they then hold in leaf
  // order.
  void build_trees(const Array<Triangle>& triangles, const Array<Edge>& edges) {
    if (has_triangle_tree_) {
      triangle_tree_.build(TriangleBoxes{vertices_.data(), triangles.data(), vertices1()}, num_triangles_);
      x_.fill_groups(triangles.data(), triangle_tree_.view().sorted_prims, num_triangles_, leaf_triangles_);
    }
    if (keeps_vertex_order_) x_.sort_by_morton(PointBoxes{vertices_.data()}, num_vertices_, vertex_order_);
    if (has_edge_tree_) {
      edge_tree_.build(EdgeBoxes{vertices_.data(), edges.data(), vertices1()}, num_edges_);
      x_.fill_groups(edges.data(), edge_tree_.view().sorted_prims, num_edges_, leaf_edges_);
    }
    if (has_vertex_tree_) vertex_tree_.build(vertex_boxes(), num_vertices_);
  }
  // The same for a rebuild: the elements back in id order first, into the scratch members once
  // a rebuild is reserved (an asynchronous one allocates nothing), else into this call's own.
  void rebuild_trees() {
    Array<Triangle> local_triangles;
    Array<Edge> local_edges;
    Array<Triangle>& triangles = reserved_.rebuild ? triangle_scratch_ : local_triangles;
    Array<Edge>& edges = reserved_.rebuild ? edge_scratch_ : local_edges;
    if (has_triangle_tree_)
      x_.scatter_groups(leaf_triangles_, triangle_tree_.view().sorted_prims, num_triangles_, triangles);
    if (has_edge_tree_) x_.scatter_groups(leaf_edges_, edge_tree_.view().sorted_prims, num_edges_, edges);
    build_trees(triangles, edges);
  }
  // The elements' boxes by leaf position, for refits (a build reads them by id: build_trees).
  LeafBoxes<Triangle> triangle_boxes() const { return {vertices_.data(), leaf_triangles_.data(), vertices1()}; }
  LeafBoxes<Edge> edge_boxes() const { return {vertices_.data(), leaf_edges_.data(), vertices1()}; }
  PointBoxes vertex_boxes() const { return {vertices_.data(), vertices1()}; }

  X x_;  // first: holds its device while the members below are created and destroyed
  Array<Vec3> vertices_;
  Array<TriangleGroup> leaf_triangles_;  // with a triangle tree: the triangles, in its leaf order only
  Array<EdgeGroup> leaf_edges_;          // with an edge tree: the edges, in its leaf order only
  Array<Edge> edges_;                    // without an edge tree: the edges by id (copy_edges)
  Array<Triangle> triangle_scratch_;     // a reserved rebuild's: the elements by id (rebuild_trees)
  Array<Edge> edge_scratch_;
  Array<int32_t> vertex_order_;  // the vertices' Morton order at build: VT and EV query order
  Array<Vec3> staging_;  // asynchronous refits: new positions, checked before they are taken
  Array<Vec3> staging1_;  // asynchronous swept steps: the end positions, checked likewise
  Array<Vec3> vertices1_;  // swept: the positions at the end of the step (vertices_: at its start)
  Array<float> rho_;     // float64 input: rho[0], how far rounding moved the vertices at most
  int32_t num_vertices_, num_triangles_, num_edges_;
  bool has_triangle_tree_, has_edge_tree_, has_vertex_tree_, keeps_vertex_order_;
  bool float64_;  // vertices come as float64 (every call: the scene's scalar type)
  bool swept_ = false;  // the last positions were swept ones (vertices_ to vertices1_)
  Reservation reserved_;
  bool nodes_fixed_ = false;  // fix_nodes() has run

  // The trees' node storage fixed at its bound (max_node_count), once: by any reservation and by
  // the first stream-ordered call. A build such a call enqueues then never reads its node count
  // back (a host copy, refused in an asynchronous call), and a graph captured from such calls keeps
  // the nodes' addresses across later rebuilds that keep more nodes. Blocking-only scenes keep
  // the smaller room that their builds size (cuda/tree.cuh).
  void fix_nodes() {
    if (nodes_fixed_) return;
    if (has_triangle_tree_) x_.reserve_nodes(triangle_tree_, num_triangles_);
    if (has_edge_tree_) x_.reserve_nodes(edge_tree_, num_edges_);
    if (has_vertex_tree_) x_.reserve_nodes(vertex_tree_, num_vertices_);
    nodes_fixed_ = true;
  }
  typename X::Tree triangle_tree_, edge_tree_, vertex_tree_;
};

template <class X>
class BoxStoreOn final : public Store {
  static_assert(ExecutorContract<X>::value, "a store runs on an executor (executor.h)");
  template <class T>
  using Array = typename X::template Array<T>;

 public:
  BoxStoreOn(typename X::Device device, const Strided& boxes) : x_(device), num_boxes_(int32_t(boxes.count)) {
    x_.hold();
    x_.gather(boxes, boxes_);
    tree_.build(GivenBoxes{boxes_.data()}, num_boxes_);
    x_.finish();
    x_.release();
  }
  ~BoxStoreOn() override { x_.hold_for_teardown(); }

  void refit(const Strided& boxes) override {
    [[maybe_unused]] const auto scope = x_.scope();
    x_.gather(boxes, boxes_);
    tree_.refit(GivenBoxes{boxes_.data()});
    x_.finish();
  }

  void rebuild(const Strided& boxes) override {
    [[maybe_unused]] const auto scope = x_.scope();
    x_.gather(boxes, boxes_);
    tree_.build(GivenBoxes{boxes_.data()}, num_boxes_);
    x_.finish();
  }

  double tree_growth() override {
    [[maybe_unused]] const auto scope = x_.scope();
    return tree_growth_of(tree_);
  }

  uint64_t query(const QueryRequest& request, const PairOutput& out, WorkCounts* work) override {
    [[maybe_unused]] const auto scope = x_.scope();
    x_.gather(request.first, query_first_);
    x_.gather(request.second, query_second_);
    const UserQueries queries{query_first_.data(), request.second.count == 0 ? nullptr : query_second_.data(),
                              request.r};
    const int32_t n = int32_t(request.first.count);
    uint64_t total = 0;
    auto run = [&](const auto& pass) { total = run_counted(x_, {work}, pass)[0]; };
    if (request.kind == QueryKind::kUserSpheres) with_pass<true>(request, tree_.view(), queries, n, out, run);
    else with_pass<false>(request, tree_.view(), queries, n, out, run);
    return total;
  }

 private:
  X x_;  // first: holds its device while the members below are created and destroyed
  Array<Box> boxes_;
  int32_t num_boxes_;
  typename X::Tree tree_;
  Array<Vec3> query_first_, query_second_;  // the last queries' points, kept to be reused
};

}  // namespace minkq
