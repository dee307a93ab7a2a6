// Cross query sources: the elements of one geometry of a scene against the tree of another
// (VT and EV: its vertices against the other's triangles or edges; EE: its edges against the
// other's edges; VV: its vertices against the other's vertices). They fulfil the query-source
// contract of query_sources.h as the one-mesh sources do, with two differences: no pair is
// incident (two geometries share no vertex), and the two sides have their own positions,
// thickness and float64 rounding. A symmetric kind (EE, VV) keeps a pair when the node test
// passes both ways, as the self sources do, and runs its leaf-exact test in the pair's global
// order, so the set does not depend on which geometry queried.
#pragma once

#include "minkq/query_sources.h"

namespace minkq {

// One geometry of a cross query: its positions (and swept, those at t = 1), thickness per vertex
// and float64 rounding distance, each null where it has none.
struct GeometrySide {
  const Vec3* vertices;
  const Vec3* vertices1 = nullptr;
  const float* thickness = nullptr;
  const float* rho = nullptr;
};

// The radius of a query between geometries rounded by at most rho_a and rho_b: r + rho_a +
// rho_b rounded up (float64.h's reasoning: each side's points move by at most its rho), r itself
// for float input.
MINKQ_HD float cross_radius(float r, const GeometrySide& a, const GeometrySide& b) {
  return reach(r, a.rho ? *a.rho : 0.0f, b.rho ? *b.rho : 0.0f);
}

// The leaf-exact test of vertex v of `vertices` against element e of `prims` at radius r: within
// r plus both thicknesses (the cross and reversed VT and EV sources' test).
template <class Prim>
MINKQ_HD bool vertex_within(const GeometrySide& vertices, int32_t v, const GeometrySide& prims, const Prim& e, float r) {
  return point_within(prims.vertices, vertices.vertices[v], e,
                      reach(r, vertex_thickness(vertices.thickness, v), element_thickness(prims.thickness, e)));
}

// The vertices of `query` against the tree of `Prim`s (triangles: VT, edges: EV) of `tree`;
// pairs (vertex, primitive), in the geometries' own ids. Queries run in `order` when given (the
// vertices' Morton order).
template <class Prim>
struct CrossVertexPrimQueries {
  GeometrySide query, tree;
  const LeafGroup<Prim>* leaf_prims;  // the tree's elements in leaf order
  const int32_t* order;               // or nullptr: vertex i is query i
  float r;
  uint32_t filters;  // kLeafExact
  MINKQ_HD float radius() const { return cross_radius(r, query, tree); }
  MINKQ_HD QueryTarget target(int32_t i) const { return {order ? order[i] : i, -1}; }
  MINKQ_HD QueryGeometry geometry(QueryTarget t) const {
    return vertex_geometry(query.vertices, query.vertices1, t.q, reach(radius(), vertex_thickness(query.thickness, t.q)));
  }
  MINKQ_HD unsigned dropped_lanes(QueryTarget, int64_t, unsigned) const { return 0; }
  template <class Shape>
  MINKQ_HD bool tests_rest() const {
    return (filters & kLeafExact) != 0;
  }
  template <class Shape>
  MINKQ_HD bool accept_rest(QueryTarget t, int32_t, int64_t p) const {
    return vertex_within(query, t.q, tree, leaf_element(leaf_prims, p), radius());
  }
  MINKQ_HD Pair pair(int32_t v, int32_t prim) const { return {v, prim}; }
};
using CrossVertexTriangleQueries = CrossVertexPrimQueries<Triangle>;
using CrossVertexEdgeQueries = CrossVertexPrimQueries<Edge>;

// The same pairs as CrossVertexPrimQueries, walked the other way round: the primitives of
// `prims` (query i: its element at leaf position i of its own tree) against the vertex tree of
// `vertices`, for a geometry with many more vertices than the other has primitives (a large static
// body against a cloth's triangles: the walk then grows with the body's depth, not its size). The
// walk's node test is the box test, its radius covering every pair the vertex side's own test
// accepts; the leaf filter then runs that test itself (Forward, the pass's shape, from the vertex
// against the primitive's box, then the leaf-exact test), so the pairs are exactly those the vertex
// side would find.
template <class Prim_>
struct CrossPrimVertexQueries {
  using Prim = Prim_;
  GeometrySide vertices, prims;
  const LeafGroup<Prim>* leaf_prims;  // the primitives in their tree's leaf order
  const int32_t* sorted_prims;        // that tree's leaf order
  float r;
  uint32_t filters;              // kLeafExact
  float vertex_thickness_max;    // the largest thickness of the vertex side
  MINKQ_HD float radius() const { return cross_radius(r, vertices, prims); }
  // A vertex accepted by its own box test lies within next_up(reach(R, t)) of the primitive's box
  // in each axis (box_gap_within), and its tree box is its box grown by t: so within R plus two
  // ulps of R + t of the vertex's tree box, which a relative 2^-21 of R + the largest t covers.
  MINKQ_HD float node_radius() const {
    const double reach_r = double(radius());
    return next_up(float_at_or_above(reach_r + (reach_r + double(vertex_thickness_max)) * 0x1p-21));
  }
};

// CrossPrimVertexQueries as a query source whose node test is the box (run with BoxShape) and
// whose leaf filter runs the vertex side's own test, Forward (the pass's shape).
template <class Prim, class Forward>
struct ReversedVertexPrimQueries {
  CrossPrimVertexQueries<Prim> q;
  MINKQ_HD QueryTarget target(int32_t i) const { return {i, -1}; }
  MINKQ_HD Box prim_box(int32_t position) const {
    return reach_box(q.prims.vertices, q.prims.vertices1, q.prims.thickness, leaf_element(q.leaf_prims, position));
  }
  MINKQ_HD QueryGeometry geometry(QueryTarget t) const {
    const Box b = prim_box(t.q);
    return {b.lo, b.hi, q.node_radius()};
  }
  MINKQ_HD unsigned dropped_lanes(QueryTarget, int64_t, unsigned) const { return 0; }
  template <class Shape>
  MINKQ_HD bool tests_rest() const {
    return true;
  }
  template <class Shape>
  MINKQ_HD bool accept_rest(QueryTarget t, int32_t v, int64_t) const {
    const GeometrySide& side = q.vertices;
    const float reach_r = q.radius(), tv = vertex_thickness(side.thickness, v);
    if (!Forward::from(vertex_geometry(side.vertices, side.vertices1, v, reach(reach_r, tv))).overlaps(prim_box(t.q)))
      return false;
    if (!(q.filters & kLeafExact)) return true;
    return vertex_within(side, v, q.prims, leaf_element(q.leaf_prims, t.q), reach_r);
  }
  MINKQ_HD Pair pair(int32_t position, int32_t v) const { return {v, q.sorted_prims[position]}; }
};

// The edges of `query` (query i: its edge at leaf position i of its own edge tree) against the
// edge tree of `tree`; pairs (query edge, tree edge) in the geometries' own ids. query_first:
// the query geometry's global ids are the lower ones (the order of the leaf-exact test's
// arguments).
struct CrossEdgeEdgeQueries {
  GeometrySide query, tree;
  const EdgeGroup* query_edges;   // the query geometry's edges in its edge tree's leaf order
  const int32_t* query_sorted;    // that tree's leaf order
  const EdgeGroup* leaf_edges;    // the tree geometry's edges in its leaf order
  float r;
  uint32_t filters;  // kLeafExact
  bool query_first;
  MINKQ_HD float radius() const { return cross_radius(r, query, tree); }
  MINKQ_HD QueryGeometry geometry_of(const GeometrySide& side, const Edge& e) const {
    return edge_geometry(side.vertices, side.vertices1, e, reach(radius(), element_thickness(side.thickness, e)));
  }
  MINKQ_HD QueryTarget target(int32_t i) const { return {i, -1}; }
  MINKQ_HD QueryGeometry geometry(QueryTarget t) const { return geometry_of(query, leaf_element(query_edges, t.q)); }
  MINKQ_HD unsigned dropped_lanes(QueryTarget, int64_t, unsigned) const { return 0; }
  template <class Shape>
  MINKQ_HD bool tests_rest() const {
    return !is_box_shape<Shape>() || (filters & kLeafExact) != 0;
  }
  template <class Shape>
  MINKQ_HD bool accept_rest(QueryTarget t, int32_t, int64_t p) const {
    const Edge a = leaf_element(query_edges, t.q), b = leaf_element(leaf_edges, p);
    if (!Shape::from(geometry_of(tree, b)).finer(reach_box(query.vertices, query.vertices1, query.thickness, a)))
      return false;
    if (!(filters & kLeafExact)) return true;
    const float ta = element_thickness(query.thickness, a), tb = element_thickness(tree.thickness, b);
    const Vec3 a0 = query.vertices[a.v[0]], a1 = query.vertices[a.v[1]];
    const Vec3 b0 = tree.vertices[b.v[0]], b1 = tree.vertices[b.v[1]];
    return query_first ? segment_segment_within(a0, a1, b0, b1, reach(radius(), ta, tb))
                       : segment_segment_within(b0, b1, a0, a1, reach(radius(), tb, ta));
  }
  MINKQ_HD Pair pair(int32_t q, int32_t f) const { return {query_sorted[q], f}; }
};

// The vertices of `query` against the vertex tree of `tree` (VV); pairs (query vertex, tree
// vertex) in the geometries' own ids; query_first as for EE.
struct CrossVertexVertexQueries {
  GeometrySide query, tree;
  float r;
  uint32_t filters;  // kLeafExact
  bool query_first;
  MINKQ_HD float radius() const { return cross_radius(r, query, tree); }
  MINKQ_HD float radius_of(const GeometrySide& side, int32_t v) const {
    return reach(radius(), vertex_thickness(side.thickness, v));
  }
  MINKQ_HD QueryTarget target(int32_t i) const { return {i, -1}; }
  MINKQ_HD QueryGeometry geometry(QueryTarget t) const {
    return vertex_geometry(query.vertices, query.vertices1, t.q, radius_of(query, t.q));
  }
  MINKQ_HD unsigned dropped_lanes(QueryTarget, int64_t, unsigned) const { return 0; }
  template <class Shape>
  MINKQ_HD bool tests_rest() const {
    return !is_box_shape<Shape>() || (filters & kLeafExact) != 0;
  }
  template <class Shape>
  MINKQ_HD bool accept_rest(QueryTarget t, int32_t w, int64_t) const {
    const int32_t v = t.q;
    const Box own = GrownBoxes<PointBoxes>{{query.vertices, query.vertices1}, query.thickness}(v);
    if (!Shape::from(vertex_geometry(tree.vertices, tree.vertices1, w, radius_of(tree, w))).finer(own)) return false;
    if (!(filters & kLeafExact)) return true;
    const float tv = vertex_thickness(query.thickness, v), tw = vertex_thickness(tree.thickness, w);
    return query_first ? point_point_within(query.vertices[v], tree.vertices[w], reach(radius(), tv, tw))
                       : point_point_within(tree.vertices[w], query.vertices[v], reach(radius(), tw, tv));
  }
  MINKQ_HD Pair pair(int32_t v, int32_t w) const { return {v, w}; }
};

}  // namespace minkq
