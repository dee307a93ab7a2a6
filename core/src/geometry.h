// One geometry of a scene on a backend: its vertices (and swept, their end positions), thickness,
// topology and trees, built, refit and rebuilt on an executor X (executor.h) that the scene's store
// (store.h) owns and lends each call. The one-mesh query sources of a self query, and the sides and
// trees the cross sources read (cross_queries.h), come from here.
#pragma once

#include <algorithm>
#include <cmath>
#include <type_traits>
#include <utility>
#include <vector>

#include "backend.h"
#include "executor.h"
#include "minkq/cross_queries.h"

namespace minkq {

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
class GeometryOn {
  template <class T>
  using Array = typename X::template Array<T>;

 public:
  // Takes the input's topology and thickness over; the caller holds x's device.
  GeometryOn(X& x, GeometryInput input)
      : num_vertices_(int32_t(input.vertices.count)), num_triangles_(int32_t(input.triangles.size())),
        num_edges_(int32_t(input.edges.size())), has_triangle_tree_(input.trees.triangles),
        has_edge_tree_(input.trees.edges), has_vertex_tree_(input.trees.vertices),
        keeps_vertex_order_(input.trees.vertex_order), float64_(input.vertices.scalar == Scalar::kFloat64),
        has_thickness_(!input.thickness.empty()) {
    for (float t : input.thickness) max_thickness_ = std::max(max_thickness_, t);
    gather_into(x, input.vertices, vertices_, false);
    if (has_thickness_) x.upload(thickness_, std::move(input.thickness));
    // The elements by id, only until their trees hold them (edges without an edge tree: kept).
    Array<Triangle> triangles_by_id;
    Array<Edge> edges_by_id;
    if (has_triangle_tree_) x.upload(triangles_by_id, std::move(input.triangles));
    x.upload(has_edge_tree_ ? edges_by_id : edges_, std::move(input.edges));
    build_trees(x, triangles_by_id, edges_by_id);
  }

  int32_t num_vertices() const { return num_vertices_; }
  int32_t num_triangles() const { return num_triangles_; }
  int32_t num_edges() const { return num_edges_; }
  bool has_triangle_tree() const { return has_triangle_tree_; }
  bool has_edge_tree() const { return has_edge_tree_; }
  bool has_vertex_tree() const { return has_vertex_tree_; }
  bool swept() const { return swept_; }
  float max_thickness() const { return max_thickness_; }  // the largest vertex thickness, 0 without

  // The geometry's edges, by id, to host memory (num_edges entries).
  void copy_edges(X& x, Edge* host_out) {
    if (!has_edge_tree_) return x.download(host_out, edges_, size_t(num_edges_));
    Array<Edge> by_id;
    x.scatter_groups(leaf_edges_, edge_tree_.view().sorted_prims, num_edges_, by_id);
    x.download(host_out, by_id, size_t(num_edges_));
  }

  // New positions (x1: swept, the end positions), refitting the trees or building them afresh.
  void move(X& x, const Strided& x0, const Strided* x1, bool rebuild) {
    gather_into(x, x0, vertices_, false);
    swept_ = x1 != nullptr;
    if (x1) gather_into(x, *x1, vertices1_, true);
    if (rebuild) rebuild_trees(x); else refit_trees();
  }

  double tree_growth() const {
    double g = has_triangle_tree_ ? tree_growth_of(triangle_tree_) : 0.0;
    if (has_edge_tree_) g = std::max(g, tree_growth_of(edge_tree_));
    if (has_vertex_tree_) g = std::max(g, tree_growth_of(vertex_tree_));
    return g;
  }

  // ---- Asynchronous calls (store.h) ---------------------------------------------------------
  void reserve(X& x, const Reservation& wanted) {
    fix_nodes(x);
    if ((wanted.refit || wanted.rebuild) && !reserved_.refit) {
      x.reserve_staging(staging_, num_vertices_);
      x.reserve_pending();
      reserved_.refit = true;
    }
    if (wanted.swept && !reserved_.swept) {
      x.reserve_staging(staging1_, num_vertices_);
      x.reserve_staging(vertices1_, num_vertices_);
      reserved_.swept = true;
    }
    if (wanted.rebuild && !reserved_.rebuild) {
      if (has_triangle_tree_) {
        x.reserve_build(triangle_tree_, triangle_boxes(), num_triangles_);
        x.reserve_scratch(triangle_scratch_, num_triangles_);
      }
      if (keeps_vertex_order_) x.reserve_sort(PointBoxes{vertices_.data()}, num_vertices_);
      if (has_edge_tree_) {
        x.reserve_build(edge_tree_, edge_boxes(), num_edges_);
        x.reserve_scratch(edge_scratch_, num_edges_);
      }
      if (has_vertex_tree_) x.reserve_build(vertex_tree_, vertex_boxes(), num_vertices_);
      reserved_.rebuild = true;
    }
    if (wanted.canonical_capacity > reserved_.canonical_capacity) {
      x.reserve_canonical(wanted.canonical_capacity);
      reserved_.canonical_capacity = wanted.canonical_capacity;
    }
  }
  const Reservation& reservation() const { return reserved_; }

  // New positions in executor memory, checked on the device (executor.h's commit_finite; a
  // pending error names vertex `first` + i: where x0 starts in the caller's buffer).
  void move_async(X& x, const Strided& x0, const Strided* x1, bool rebuild, int64_t first = 0) {
    fix_nodes(x);
    swept_ = x1 != nullptr;
    const PendingError::Call call = x1 ? (rebuild ? PendingError::kRebuildSwept : PendingError::kRefitSwept)
                                       : (rebuild ? PendingError::kRebuild : PendingError::kRefit);
    if (x1) x.commit_finite_swept(x0, *x1, staging_, staging1_, vertices_, vertices1_, rho(), call, first);
    else x.commit_finite(x0, staging_, vertices_, rho(), call, first);
    if (rebuild) rebuild_trees(x); else refit_trees();
  }

  // The trees' node storage fixed at its bound (max_node_count), once: by any reservation and by
  // the first stream-ordered call. A build such a call enqueues then never reads its node count
  // back (a host copy, refused in an asynchronous call), and a graph captured from such calls keeps
  // the nodes' addresses across later rebuilds that keep more nodes. Blocking-only scenes keep
  // the smaller room that their builds size (cuda/tree.cuh).
  bool nodes_fixed() const { return nodes_fixed_; }
  void fix_nodes(X& x) {
    if (nodes_fixed_) return;
    if (has_triangle_tree_) x.reserve_nodes(triangle_tree_, num_triangles_);
    if (has_edge_tree_) x.reserve_nodes(edge_tree_, num_edges_);
    if (has_vertex_tree_) x.reserve_nodes(vertex_tree_, num_vertices_);
    nodes_fixed_ = true;
  }

  // ---- What queries read ----------------------------------------------------------------------
  // The addresses of everything the query sources and trees below hand out, and whether the
  // geometry is swept: while these stay, sources built from it stay valid (the store's job
  // tables are keyed by them).
  void layout(std::vector<const void*>& key) const {
    const BvhView trees[3] = {triangle_tree(), edge_tree(), vertex_tree()};
    key.insert(key.end(), {vertices_.data(), vertices1(), thickness(), rho_.data(), leaf_triangles_.data(),
                           leaf_edges_.data(), vertex_order_.data()});
    for (const BvhView& tree : trees) key.insert(key.end(), {tree.nodes, tree.leaf_groups, tree.sorted_prims});
  }
  // Whether the geometry's queries read end positions: set by its moves, and by the store only
  // while it plans job tables for the arrangements a stream-ordered move reaches.
  void set_swept(bool swept) { swept_ = swept; }

  // The one-mesh sources of a self query (query_sources.h) with r and the filters.
  VertexTriangleQueries vt_queries(float r, uint32_t filters) {
    return {vertices_.data(), leaf_triangles_.data(), vertex_order_.data(), r, filters, rho(), vertices1(), thickness()};
  }
  VertexEdgeQueries ev_queries(float r, uint32_t filters) {
    return {vertices_.data(), leaf_edges_.data(), vertex_order_.data(), r, filters, rho(), vertices1(), thickness()};
  }
  EdgeEdgeQueries ee_queries(float r, uint32_t filters) {
    return {vertices_.data(), leaf_edges_.data(), edge_tree_.view().sorted_prims, r, filters, rho(), vertices1(),
            thickness()};
  }
  VertexVertexQueries vv_queries(float r, uint32_t filters) {
    return {vertices_.data(), vertex_tree_.view().sorted_prims, r, filters, rho(), vertices1(), thickness()};
  }
  // The same by primitive type (Triangle: the triangle tree, Edge: the edge tree).
  template <class Prim>
  VertexPrimQueries<Prim> vertex_prim_queries(float r, uint32_t filters) {
    if constexpr (std::is_same<Prim, Triangle>::value) return vt_queries(r, filters); else return ev_queries(r, filters);
  }
  template <class Prim>
  BvhView prim_tree() const {
    if constexpr (std::is_same<Prim, Triangle>::value) return triangle_tree(); else return edge_tree();
  }
  template <class Prim>
  const LeafGroup<Prim>* leaf_prims() const {
    if constexpr (std::is_same<Prim, Triangle>::value) return leaf_triangles(); else return leaf_edges();
  }
  template <class Prim>
  int32_t num_prims() const {
    if constexpr (std::is_same<Prim, Triangle>::value) return num_triangles(); else return num_edges();
  }
  // This geometry as one side of a cross query.
  GeometrySide side() { return {vertices_.data(), vertices1(), thickness(), rho()}; }
  const int32_t* vertex_order() const { return keeps_vertex_order_ ? vertex_order_.data() : nullptr; }
  const TriangleGroup* leaf_triangles() const { return leaf_triangles_.data(); }
  const EdgeGroup* leaf_edges() const { return leaf_edges_.data(); }
  BvhView triangle_tree() const { return triangle_tree_.view(); }
  BvhView edge_tree() const { return edge_tree_.view(); }
  BvhView vertex_tree() const { return vertex_tree_.view(); }

 private:
  // Positions from the caller's (float64 ones rounded, with rho, the larger of both positions'
  // for a swept step: accumulate).
  void gather_into(X& x, const Strided& values, Array<Vec3>& dst, bool accumulate) {
    if (float64_) x.gather_float64(values, dst, rho_, accumulate); else x.gather(values, dst);
  }
  const Vec3* vertices1() const { return swept_ ? vertices1_.data() : nullptr; }
  const float* thickness() const { return has_thickness_ ? thickness_.data() : nullptr; }
  // Where the queries read rho (executor memory): nullptr for float input, whose radius stays r.
  float* rho() { return float64_ ? rho_.data() : nullptr; }
  // Calls fn with `boxes`, grown by their elements' thickness where the geometry has any.
  template <class Boxes, class Fn>
  void with_grown(const Boxes& boxes, Fn&& fn) const {
    if (has_thickness_) fn(GrownBoxes<Boxes>{boxes, thickness_.data()}); else fn(boxes);
  }
  void refit_trees() {
    if (has_triangle_tree_) with_grown(triangle_boxes(), [&](const auto& boxes) { triangle_tree_.refit(boxes); });
    if (has_edge_tree_) with_grown(edge_boxes(), [&](const auto& boxes) { edge_tree_.refit(boxes); });
    if (has_vertex_tree_) with_grown(vertex_boxes(), [&](const auto& boxes) { vertex_tree_.refit(boxes); });
  }
  // The trees the flags ask for, and the VT / EV query order, from the current vertices;
  // triangles and edges: the elements by id (with their trees), which they then hold in leaf
  // order.
  void build_trees(X& x, const Array<Triangle>& triangles, const Array<Edge>& edges) {
    if (has_triangle_tree_) {
      with_grown(TriangleBoxes{vertices_.data(), triangles.data(), vertices1()},
                 [&](const auto& boxes) { triangle_tree_.build(boxes, num_triangles_); });
      x.fill_groups(triangles.data(), triangle_tree_.view().sorted_prims, num_triangles_, leaf_triangles_);
    }
    if (keeps_vertex_order_) x.sort_by_morton(PointBoxes{vertices_.data()}, num_vertices_, vertex_order_);
    if (has_edge_tree_) {
      with_grown(EdgeBoxes{vertices_.data(), edges.data(), vertices1()},
                 [&](const auto& boxes) { edge_tree_.build(boxes, num_edges_); });
      x.fill_groups(edges.data(), edge_tree_.view().sorted_prims, num_edges_, leaf_edges_);
    }
    if (has_vertex_tree_) with_grown(vertex_boxes(), [&](const auto& boxes) { vertex_tree_.build(boxes, num_vertices_); });
  }
  // The same for a rebuild: the elements back in id order first, into the scratch members once
  // a rebuild is reserved (an asynchronous one allocates nothing), else into this call's own.
  void rebuild_trees(X& x) {
    Array<Triangle> local_triangles;
    Array<Edge> local_edges;
    Array<Triangle>& triangles = reserved_.rebuild ? triangle_scratch_ : local_triangles;
    Array<Edge>& edges = reserved_.rebuild ? edge_scratch_ : local_edges;
    if (has_triangle_tree_)
      x.scatter_groups(leaf_triangles_, triangle_tree_.view().sorted_prims, num_triangles_, triangles);
    if (has_edge_tree_) x.scatter_groups(leaf_edges_, edge_tree_.view().sorted_prims, num_edges_, edges);
    build_trees(x, triangles, edges);
  }
  // The elements' boxes by leaf position, for refits (a build reads them by id: build_trees).
  // The elements' boxes, ungrown (with_grown grows them).
  LeafBoxes<Triangle> triangle_boxes() const { return {vertices_.data(), leaf_triangles_.data(), vertices1()}; }
  LeafBoxes<Edge> edge_boxes() const { return {vertices_.data(), leaf_edges_.data(), vertices1()}; }
  PointBoxes vertex_boxes() const { return {vertices_.data(), vertices1()}; }

  Array<Vec3> vertices_;
  Array<float> thickness_;               // per vertex, when the geometry has any
  Array<TriangleGroup> leaf_triangles_;  // with a triangle tree: the triangles, in its leaf order only
  Array<EdgeGroup> leaf_edges_;          // with an edge tree: the edges, in its leaf order only
  Array<Edge> edges_;                    // without an edge tree: the edges by id (copy_edges)
  Array<Triangle> triangle_scratch_;     // a reserved rebuild's: the elements by id (rebuild_trees)
  Array<Edge> edge_scratch_;
  Array<int32_t> vertex_order_;  // the vertices' Morton order at build: VT and EV query order
  Array<Vec3> staging_;   // asynchronous refits: new positions, checked before they are taken
  Array<Vec3> staging1_;  // asynchronous swept steps: the end positions, checked likewise
  Array<Vec3> vertices1_;  // swept: the positions at the end of the step (vertices_: at its start)
  Array<float> rho_;       // float64 input: rho[0], how far rounding moved the vertices at most
  int32_t num_vertices_, num_triangles_, num_edges_;
  bool has_triangle_tree_, has_edge_tree_, has_vertex_tree_, keeps_vertex_order_;
  bool float64_;  // vertices come as float64 (every call: the geometry's scalar type)
  bool has_thickness_;
  float max_thickness_ = 0.0f;
  bool swept_ = false;  // the last positions were swept ones (vertices_ to vertices1_)
  Reservation reserved_;
  bool nodes_fixed_ = false;  // fix_nodes() has run
  typename X::Tree triangle_tree_, edge_tree_, vertex_tree_;
};

}  // namespace minkq
