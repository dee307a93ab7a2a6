// Query sources: where query q's geometry comes from and which (query, primitive) pairs the leaf
// filter (leaf_filter.h) keeps, for the five query kinds: VT and EV (vertex against a tree of
// triangles or edges), EE and VV (a tree against itself) and user queries against user boxes.
// The sources read a tree's elements by leaf position only, as the stores keep them
// (leaf_groups.h); testing/by_id_queries.h states the same verdicts pair by pair, by id, for the
// tests and the references.
#pragma once

#include <utility>

#include "minkq/detect.h"
#include "minkq/float64.h"
#include "minkq/leaf_groups.h"
#include "minkq/shapes.h"

namespace minkq {

// Filter bits of a query (capi/query.cpp sets them from the C flags one by one).
constexpr uint32_t kDropIncident = 1u;  // VT: vertex of the triangle; EE: edges sharing a vertex
constexpr uint32_t kLeafExact = 2u;     // primitive distance test at the leaves

// Query i of a batch: the element that asks, and the sorted leaf position its leaves must lie
// after (-1: any leaf; see traverse()).
struct QueryTarget {
  int32_t q;
  int32_t after;
};
struct Pair {
  int32_t first, second;
};
// {a, b} lower first, as a minimum and a maximum (no branch: which is lower is a coin toss).
MINKQ_HD Pair ordered_pair(int32_t a, int32_t b) { return {a < b ? a : b, a < b ? b : a}; }
// A pair as one 64-bit key, first << 32 | second: keys sort as the pairs do lexicographically
// (ids are non-negative).
MINKQ_HD uint64_t pack_pair(int32_t first, int32_t second) { return uint64_t(uint32_t(first)) << 32 | uint32_t(second); }
MINKQ_HD Pair unpack_pair(uint64_t key) { return {int32_t(key >> 32), int32_t(key & 0xffffffffu)}; }

// What run_query asks of a query source Q run with shape S (each source below fulfils it):
//
//   QueryTarget target(int32_t i)      query i of the batch: the element that asks and the leaf
//                                      position its leaves must lie after (-1: any).
//   QueryGeometry geometry(QueryTarget)
//                                      the query's shape is S::from of it.
//   unsigned dropped_lanes(QueryTarget, int64_t base, unsigned hits)
//                                      the lanes of hits (leaf group base / 4) whose primitive
//                                      the incidence filter drops.
//   bool tests_rest<S>()               whether accept_rest tests anything (else every lane
//                                      left is a candidate).
//   bool accept_rest<S>(QueryTarget, int32_t prim, int64_t p)
//                                      the filter's other tests, prim being at leaf position p.
//   Pair pair(int32_t q, int32_t prim) the pair reported.
//
// Checked member by member where a source is used (run_query); tests/test_contracts.cpp checks
// the sources here fulfil it.
namespace source_contract {
template <class Q>
using Target = decltype(std::declval<const Q&>().target(int32_t()));
template <class Q>
using Geometry = decltype(std::declval<const Q&>().geometry(std::declval<QueryTarget>()));
template <class Q>
using DroppedLanes = decltype(std::declval<const Q&>().dropped_lanes(std::declval<QueryTarget>(), int64_t(), 0u));
template <class Q, class S>
using TestsRest = decltype(std::declval<const Q&>().template tests_rest<S>());
template <class Q, class S>
using AcceptRest =
    decltype(std::declval<const Q&>().template accept_rest<S>(std::declval<QueryTarget>(), int32_t(), int64_t()));
template <class Q>
using MakePair = decltype(std::declval<const Q&>().pair(int32_t(), int32_t()));
template <class Q>
constexpr bool kTarget = detected_as<QueryTarget, Target, Q>;
template <class Q>
constexpr bool kGeometry = detected_as<QueryGeometry, Geometry, Q>;
template <class Q>
constexpr bool kDroppedLanes = detected_as<unsigned, DroppedLanes, Q>;
template <class Q, class S>
constexpr bool kTestsRest = detected_as<bool, TestsRest, Q, S>;
template <class Q, class S>
constexpr bool kAcceptRest = detected_as<bool, AcceptRest, Q, S>;
template <class Q>
constexpr bool kPair = detected_as<Pair, MakePair, Q>;
}  // namespace source_contract

template <class Q, class S>
constexpr bool is_query_source = source_contract::kTarget<Q> && source_contract::kGeometry<Q> &&
                                 source_contract::kDroppedLanes<Q> && source_contract::kTestsRest<Q, S> &&
                                 source_contract::kAcceptRest<Q, S> && source_contract::kPair<Q>;

// Instantiated where a source is used: one message for each member Q lacks.
template <class Q, class S>
struct QuerySourceContract {
  static_assert(source_contract::kTarget<Q>, "query source: needs QueryTarget target(int32_t i) const");
  static_assert(source_contract::kGeometry<Q>, "query source: needs QueryGeometry geometry(QueryTarget) const");
  static_assert(source_contract::kDroppedLanes<Q>,
                "query source: needs unsigned dropped_lanes(QueryTarget, int64_t base, unsigned hits) const");
  static_assert(source_contract::kTestsRest<Q, S>, "query source: needs template <class Shape> bool tests_rest() const");
  static_assert(source_contract::kAcceptRest<Q, S>,
                "query source: needs template <class Shape> bool accept_rest(QueryTarget, int32_t prim, int64_t p) const");
  static_assert(source_contract::kPair<Q>, "query source: needs Pair pair(int32_t q, int32_t prim) const");
  static constexpr bool value = is_query_source<Q, S>;
};

// The geometry of vertex v as a query: the point, or swept (vertices1 set) its path.
MINKQ_HD QueryGeometry vertex_geometry(const Vec3* vertices, const Vec3* vertices1, int32_t v, float r) {
  return {vertices[v], vertices1 ? vertices1[v] : vertices[v], r};
}

// Edge e as a query: the segment, or swept (vertices1 set) its swept box, as the box from its
// low to its high corner (box mode only: the front end refuses the segment modes); radius r.
MINKQ_HD QueryGeometry edge_geometry(const Vec3* vertices, const Vec3* vertices1, const Edge& e, float r) {
  if (vertices1) {
    const Box b = element_box(vertices, vertices1, e);
    return {b.lo, b.hi, r};
  }
  return {vertices[e.v[0]], vertices[e.v[1]], r};
}

// Vertex v against the tree of `Prim`s, triangles (VT) or edges (EV); pairs (v, p). Queries run
// in `order` when given (the vertices' Morton order: neighbouring queries then walk the same
// nodes). Swept (vertices1 set), vertex v is its path, the segment from vertices[v] to
// vertices1[v], against the primitives' swept boxes: segment shapes (capsules), and no
// leaf-exact test (the front end refuses it).
template <class Prim>
struct VertexPrimQueries {
  const Vec3* vertices;
  const LeafGroup<Prim>* leaf_prims;  // the tree's elements in leaf order
  const int32_t* order;  // or nullptr: vertex i is query i
  float r;
  uint32_t filters;
  const float* rho = nullptr;  // float64 input: how far rounding moved the vertices (float64.h)
  const Vec3* vertices1 = nullptr;  // swept: the positions at t = 1
  const float* thickness = nullptr;  // per vertex (thickness.h), or none
  MINKQ_HD float radius() const { return query_radius(r, rho); }
  MINKQ_HD QueryTarget target(int32_t i) const { return {order ? order[i] : i, -1}; }
  MINKQ_HD QueryGeometry geometry(QueryTarget t) const {
    return vertex_geometry(vertices, vertices1, t.q, reach(radius(), vertex_thickness(thickness, t.q)));
  }
  // The lanes of `hits` (group `base` of the tree's leaf order) that the incidence filter drops.
  MINKQ_HD unsigned dropped_lanes(QueryTarget target, int64_t base, unsigned hits) const {
    if (!(filters & kDropIncident)) return 0;
    return incident_lanes(leaf_prims[base >> 2], target.q, target.q, hits);
  }
  // What the filter tests after incidence, and whether it tests anything (else every lane the
  // incidence filter leaves is a candidate).
  template <class Shape>
  MINKQ_HD bool tests_rest() const {
    return (filters & kLeafExact) != 0;
  }
  // Primitive t is at leaf position p.
  template <class Shape>
  MINKQ_HD bool accept_rest(QueryTarget target, int32_t, int64_t p) const {
    return keeps(target.q, leaf_element(leaf_prims, p));
  }
  // Whether the tests after incidence keep vertex v against element e: the leaf-exact test
  // where asked.
  MINKQ_HD bool keeps(int32_t v, const Prim& e) const {
    if (!(filters & kLeafExact)) return true;
    return point_within(vertices, vertices[v], e,
                        reach(radius(), vertex_thickness(thickness, v), element_thickness(thickness, e)));
  }
  MINKQ_HD Pair pair(int32_t v, int32_t t) const { return {v, t}; }
};
using VertexTriangleQueries = VertexPrimQueries<Triangle>;
using VertexEdgeQueries = VertexPrimQueries<Edge>;

// The edge tree against itself, query i being the edge at sorted leaf position i: it reaches
// only the leaves after it, so each unordered pair is met once and reported as (e, f), e < f.
// The pair is met from whichever edge comes first in leaf order; the leaf filter also applies
// the node test the other way round, so the candidate set does not depend on that order:
// {e, f} is a candidate when Shape(e) overlaps box(f) and Shape(f) overlaps box(e).
struct EdgeEdgeQueries {
  const Vec3* vertices;
  const EdgeGroup* leaf_edges;  // the edges in the tree's leaf order
  const int32_t* sorted_edges;  // the edge tree's leaf order
  float r;
  uint32_t filters;
  const float* rho = nullptr;  // float64 input: how far rounding moved the vertices (float64.h)
  const Vec3* vertices1 = nullptr;  // swept: the positions at t = 1
  const float* thickness = nullptr;  // per vertex (thickness.h), or none
  MINKQ_HD float radius() const { return query_radius(r, rho); }
  MINKQ_HD QueryTarget target(int32_t i) const { return {sorted_edges[i], i}; }
  // The edge at leaf position p.
  MINKQ_HD Edge edge_at(int64_t p) const { return leaf_element(leaf_edges, p); }
  // Static: the edge as a segment. Swept: the edge's swept box, as the box from its low to its
  // high corner (box mode only: the front end refuses the segment modes).
  MINKQ_HD QueryGeometry geometry_of(const Edge& e) const {
    return edge_geometry(vertices, vertices1, e, reach(radius(), element_thickness(thickness, e)));
  }
  MINKQ_HD QueryGeometry geometry(QueryTarget t) const { return geometry_of(edge_at(t.after)); }
  // The lanes of `hits` (group `base` of the edge tree's leaf order) that the incidence filter
  // drops.
  MINKQ_HD unsigned dropped_lanes(QueryTarget target, int64_t base, unsigned hits) const {
    if (!(filters & kDropIncident)) return 0;
    const Edge a = edge_at(target.after);
    return incident_lanes(leaf_edges[base >> 2], a.v[0], a.v[1], hits);
  }
  // The box test is symmetric (box_gap_within) and passed; the finer tests are not: Shape(f)'s
  // finer test against e's box (nothing for the box mode), then the leaf-exact test.
  template <class Shape>
  MINKQ_HD bool tests_rest() const {
    return !is_box_shape<Shape>() || (filters & kLeafExact) != 0;
  }
  // Edge f is at leaf position p.
  template <class Shape>
  MINKQ_HD bool accept_rest(QueryTarget target, int32_t f, int64_t p) const {
    return keeps<Shape>(target.q, edge_at(target.after), f, edge_at(p));
  }
  // Whether the tests after incidence keep edges e (a) and f (b), Shape(e) overlapping f's box.
  template <class Shape>
  MINKQ_HD bool keeps(int32_t e, const Edge& a, int32_t f, const Edge& b) const {
    if (!Shape::from(geometry_of(b)).finer(reach_box(vertices, vertices1, thickness, a))) return false;
    if (!(filters & kLeafExact)) return true;
    // In the pair's own order (lower id first): rounding makes the test's arguments unequal.
    const Edge lo = e < f ? a : b, hi = e < f ? b : a;
    return segment_segment_within(vertices[lo.v[0]], vertices[lo.v[1]], vertices[hi.v[0]], vertices[hi.v[1]],
                                  reach(radius(), element_thickness(thickness, lo), element_thickness(thickness, hi)));
  }
  MINKQ_HD Pair pair(int32_t e, int32_t f) const { return ordered_pair(e, f); }
};

// The vertex tree against itself (VV: points of codimensional meshes), query i being the
// vertex at sorted leaf position i: as EdgeEdgeQueries, each unordered pair is met once,
// reported as (v, w), v < w, and kept when the node test passes both ways. Swept, each vertex
// is its path (segment shapes against the paths' boxes), with no leaf-exact test. No pair is
// incident (a vertex never pairs with itself). The vertices have no leaf form: the tests read
// them by id.
struct VertexVertexQueries {
  const Vec3* vertices;
  const int32_t* sorted_vertices;  // the vertex tree's leaf order
  float r;
  uint32_t filters;
  const float* rho = nullptr;       // float64 input: how far rounding moved the vertices (float64.h)
  const Vec3* vertices1 = nullptr;  // swept: the positions at t = 1
  const float* thickness = nullptr;  // per vertex (thickness.h), or none
  MINKQ_HD float radius() const { return query_radius(r, rho); }
  MINKQ_HD float radius_of(int32_t v) const { return reach(radius(), vertex_thickness(thickness, v)); }
  MINKQ_HD QueryTarget target(int32_t i) const { return {sorted_vertices[i], i}; }
  MINKQ_HD QueryGeometry geometry(QueryTarget t) const { return vertex_geometry(vertices, vertices1, t.q, radius_of(t.q)); }
  MINKQ_HD unsigned dropped_lanes(QueryTarget, int64_t, unsigned) const { return 0; }
  template <class Shape>
  MINKQ_HD bool tests_rest() const {
    return !is_box_shape<Shape>() || (filters & kLeafExact) != 0;
  }
  template <class Shape>
  MINKQ_HD bool accept_rest(QueryTarget target, int32_t w, int64_t) const {
    const int32_t v = target.q;
    if (!Shape::from(vertex_geometry(vertices, vertices1, w, radius_of(w))).finer(GrownBoxes<PointBoxes>{{vertices, vertices1}, thickness}(v)))
      return false;
    if (!(filters & kLeafExact)) return true;
    const int32_t lo = v < w ? v : w, hi = v < w ? w : v;  // in the pair's own order, as EE
    return point_point_within(vertices[lo], vertices[hi],
                              reach(radius(), vertex_thickness(thickness, lo), vertex_thickness(thickness, hi)));
  }
  MINKQ_HD Pair pair(int32_t v, int32_t w) const { return ordered_pair(v, w); }
};

// User queries against a tree of user boxes: spheres (p1 == nullptr), capsules, or boxes
// (lo in p0, hi in p1, r == 0). No leaf filter: the node test at a leaf is the exact test.
struct UserQueries {
  const Vec3* p0;
  const Vec3* p1;
  float r;
  MINKQ_HD QueryTarget target(int32_t i) const { return {i, -1}; }
  MINKQ_HD QueryGeometry geometry(QueryTarget t) const { return {p0[t.q], p1 ? p1[t.q] : p0[t.q], r}; }
  MINKQ_HD unsigned dropped_lanes(QueryTarget, int64_t, unsigned) const { return 0; }
  template <class Shape>
  MINKQ_HD bool tests_rest() const {
    return false;
  }
  template <class Shape>
  MINKQ_HD bool accept_rest(QueryTarget, int32_t, int64_t) const { return true; }
  MINKQ_HD Pair pair(int32_t q, int32_t b) const { return {q, b}; }
};

}  // namespace minkq
