// Query sources: where query q's geometry comes from, which primitive boxes a tree holds, and
// which (query, primitive) pairs the leaf filter keeps. run_query ties a source to a shape
// and to the one traversal; backends call it per query and supply only emit(first, second).
#pragma once

#include <type_traits>

#include "minkq/float64.h"
#include "minkq/traversal.h"
#include "minkq/shapes.h"

namespace minkq {

struct Triangle {
  int32_t v[3];
};
struct Edge {
  int32_t v[2];
};

// Whether triangle t (edge e) has vertex v, and whether two edges share a vertex: the incidence
// the kDropIncident filter drops.
MINKQ_HD bool has_vertex(const Triangle& t, int32_t v) { return t.v[0] == v || t.v[1] == v || t.v[2] == v; }
MINKQ_HD bool has_vertex(const Edge& e, int32_t v) { return e.v[0] == v || e.v[1] == v; }
MINKQ_HD bool share_vertex(const Edge& a, const Edge& b) {
  return a.v[0] == b.v[0] || a.v[0] == b.v[1] || a.v[1] == b.v[0] || a.v[1] == b.v[1];
}

// A tree's elements (triangles or edges) at four consecutive leaf positions, by lane as a
// BoxGroup holds their boxes: the store keeps a tree's elements in this form only, so that its
// leaf filters read them in leaf order, four at a time on the host, and a refit reads them
// sequentially (LeafBoxes). Lanes past the last element hold -1 (no vertex).
template <class Prim>
struct LeafGroup {
  static constexpr int kVertices = int(sizeof(Prim) / sizeof(int32_t));
  int32_t v[kVertices][4];
  // The element in lane k.
  MINKQ_HD Prim at(int k) const {
    Prim e;
    for (int j = 0; j < kVertices; ++j) e.v[j] = v[j][k];
    return e;
  }
  MINKQ_HD void set(int k, const Prim& e) {
    for (int j = 0; j < kVertices; ++j) v[j][k] = e.v[j];
  }
};
// The element at leaf position p of a tree whose elements `groups` holds.
template <class Prim>
MINKQ_HD Prim leaf_element(const LeafGroup<Prim>* groups, int64_t p) {
  return groups[p >> 2].at(int(p & 3));
}
// Element `id`, at leaf position p (-1: not known): from the elements in leaf order where given,
// else by id (the query sources' two forms).
template <class Prim>
MINKQ_HD Prim element_at(const Prim* by_id, const LeafGroup<Prim>* leaf, int32_t id, int64_t p) {
  return p >= 0 && leaf ? leaf_element(leaf, p) : by_id[id];
}
using TriangleGroup = LeafGroup<Triangle>;
using EdgeGroup = LeafGroup<Edge>;
static_assert(sizeof(TriangleGroup) == 48 && sizeof(EdgeGroup) == 32, "a group holds four elements and nothing else");

// Group g of the tree whose leaf order is sorted_prims (n elements), from the elements by id.
template <class Prim>
MINKQ_HD void fill_leaf_group(int64_t g, const Prim* prims, const int32_t* sorted_prims, int32_t n,
                              LeafGroup<Prim>& out) {
  for (int k = 0; k < 4; ++k) {
    const int64_t p = 4 * g + k;
    Prim none;
    for (int j = 0; j < LeafGroup<Prim>::kVertices; ++j) none.v[j] = -1;
    out.set(k, p < n ? prims[sorted_prims[p]] : none);
  }
}
// The inverse: group g's elements back to their ids (a rebuild reads the elements by id).
template <class Prim>
MINKQ_HD void scatter_leaf_group(int64_t g, const LeafGroup<Prim>& group, const int32_t* sorted_prims, int32_t n,
                                 Prim* prims) {
  for (int k = 0; k < 4; ++k)
    if (4 * g + k < n) prims[sorted_prims[4 * g + k]] = group.at(k);
}

// The lanes of `lanes` whose element has vertex a or vertex b (a vertex's own triangles or
// edges: a == b; the edges sharing a vertex with edge (a, b)): has_vertex and share_vertex,
// lane by lane.
template <class Prim>
MINKQ_HD unsigned incident_lanes(const LeafGroup<Prim>& g, int32_t a, int32_t b, unsigned lanes) {
#if defined(__CUDACC__)
  return lanes_where(lanes, [&](int k) {
    bool any = false;
    for (int j = 0; j < LeafGroup<Prim>::kVertices; ++j) any |= g.v[j][k] == a || g.v[j][k] == b;
    return any;
  });
#else
  simd4::M4 any = {0, 0, 0, 0};
  for (int j = 0; j < LeafGroup<Prim>::kVertices; ++j) {
    const simd4::M4 u = simd4::load(g.v[j]);
    any |= (u == a) | (u == b);
  }
  return lanes & simd4::mask_bits(any);
#endif
}

// Filter bits of a query (capi/query.cpp sets them from the C flags one by one).
constexpr uint32_t kDropIncident = 1u;  // VT: vertex of the triangle; EE: edges sharing a vertex
constexpr uint32_t kLeafExact = 2u;     // primitive distance test at the leaves

// ---- Primitive boxes -----------------------------------------------------------------------
// A swept scene (vertices moving linearly from `vertices` to `vertices1`) boxes each element
// over both positions: every position between holds it, since each of its points at time t is
// a convex combination of its vertices' two positions.
MINKQ_HD Box element_box(const Vec3* vertices, const Vec3* vertices1, const Triangle& tri) {
  Box b = box_expand(box_expand(Box::of_point(vertices[tri.v[0]]), vertices[tri.v[1]]), vertices[tri.v[2]]);
  if (vertices1)
    for (int k = 0; k < 3; ++k) b = box_expand(b, vertices1[tri.v[k]]);
  return b;
}
MINKQ_HD Box element_box(const Vec3* vertices, const Vec3* vertices1, const Edge& edge) {
  Box b = box_expand(Box::of_point(vertices[edge.v[0]]), vertices[edge.v[1]]);
  if (vertices1) b = box_expand(box_expand(b, vertices1[edge.v[0]]), vertices1[edge.v[1]]);
  return b;
}
// The box of element i, by id.
template <class Prim>
struct ElementBoxes {
  const Vec3* vertices;
  const Prim* prims;
  const Vec3* vertices1 = nullptr;  // swept: the positions at t = 1
  MINKQ_HD Box operator()(int32_t i) const { return element_box(vertices, vertices1, prims[i]); }
};
using TriangleBoxes = ElementBoxes<Triangle>;
using EdgeBoxes = ElementBoxes<Edge>;
// The box of the element at leaf position p, from the elements in leaf order (a refit's
// source: kByLeafPosition, tree.h).
template <class Prim>
struct LeafBoxes {
  static constexpr bool kByLeafPosition = true;
  const Vec3* vertices;
  const LeafGroup<Prim>* groups;
  const Vec3* vertices1 = nullptr;  // swept: the positions at t = 1
  MINKQ_HD Box operator()(int32_t p) const { return element_box(vertices, vertices1, leaf_element(groups, p)); }
};
struct PointBoxes {
  const Vec3* points;
  const Vec3* points1 = nullptr;  // swept: the positions at t = 1 (the box of the path)
  MINKQ_HD Box operator()(int32_t i) const {
    const Box b = Box::of_point(points[i]);
    return points1 ? box_expand(b, points1[i]) : b;
  }
};

// ---- Query sources ---------------------------------------------------------------------------
// Query i of a batch: the element that asks, and the sorted leaf position its leaves must lie
// after (-1: any leaf; see traverse()).
struct QueryTarget {
  int32_t q;
  int32_t after;
};
struct Pair {
  int32_t first, second;
};
// A pair as one 64-bit key, first << 32 | second: keys sort as the pairs do lexicographically
// (ids are non-negative).
MINKQ_HD uint64_t pack_pair(int32_t first, int32_t second) { return uint64_t(uint32_t(first)) << 32 | uint32_t(second); }
MINKQ_HD Pair unpack_pair(uint64_t key) { return {int32_t(key >> 32), int32_t(key & 0xffffffffu)}; }

// The leaf-exact test of a vertex against a triangle or an edge.
MINKQ_HD bool point_within(const Vec3* vertices, Vec3 p, const Triangle& t, float r) {
  return point_triangle_within(p, vertices[t.v[0]], vertices[t.v[1]], vertices[t.v[2]], r);
}
MINKQ_HD bool point_within(const Vec3* vertices, Vec3 p, const Edge& e, float r) {
  return point_segment_within(p, vertices[e.v[0]], vertices[e.v[1]], r);
}

// Vertex v against the tree of `Prim`s, triangles (VT) or edges (EV); pairs (v, p). Queries run
// in `order` when given (the vertices' Morton order: neighbouring queries then walk the same
// nodes). Swept (vertices1 set), vertex v is its path, the segment from vertices[v] to
// vertices1[v], against the primitives' swept boxes: segment shapes (capsules), and no
// leaf-exact test (the front end refuses it).
template <class Prim>
struct VertexPrimQueries {
  const Vec3* vertices;
  const Prim* prims;     // by id: the one-pair verdict accept() reads them (nullptr: leaf_prims only)
  const int32_t* order;  // or nullptr: vertex i is query i
  float r;
  uint32_t filters;
  const float* rho = nullptr;  // float64 input: how far rounding moved the vertices (float64.h)
  const Vec3* vertices1 = nullptr;  // swept: the positions at t = 1
  const LeafGroup<Prim>* leaf_prims = nullptr;  // the tree's elements in leaf order (or nullptr)
  MINKQ_HD float radius() const { return query_radius(r, rho); }
  MINKQ_HD QueryTarget target(int32_t i) const { return {order ? order[i] : i, -1}; }
  MINKQ_HD Prim element(int32_t t, int64_t p) const { return element_at(prims, leaf_prims, t, p); }
  MINKQ_HD QueryGeometry geometry(int32_t v) const {
    return {vertices[v], vertices1 ? vertices1[v] : vertices[v], radius()};
  }
  MINKQ_HD QueryGeometry geometry(QueryTarget t) const { return geometry(t.q); }
  // Whether the leaf filter keeps (v, t), reached because Shape(v) overlaps t's box: not
  // incident (where dropped), then accept_rest.
  template <class Shape>
  MINKQ_HD bool accept(int32_t v, int32_t t) const {
    if ((filters & kDropIncident) && has_vertex(prims[t], v)) return false;
    return accept_rest<Shape>({v, -1}, t, -1);
  }
  // The lanes of `hits` (group `base` of the tree's leaf order) that the incidence filter drops:
  // four at a time from leaf_prims, else element by element.
  MINKQ_HD unsigned dropped_lanes(QueryTarget target, int64_t base, unsigned hits, const int32_t* sorted_prims) const {
    if (!(filters & kDropIncident)) return 0;
    const int32_t v = target.q;
    if (leaf_prims) return incident_lanes(leaf_prims[base >> 2], v, v, hits);
    return lanes_where(hits, [&](int k) { return has_vertex(prims[sorted_prims[base + k]], v); });
  }
  // What the filter tests after incidence, and whether it tests anything (else every lane the
  // incidence filter leaves is a candidate).
  template <class Shape>
  MINKQ_HD bool tests_rest() const {
    return (filters & kLeafExact) != 0;
  }
  // Primitive t is at leaf position p (-1: not known).
  template <class Shape>
  MINKQ_HD bool accept_rest(QueryTarget target, int32_t t, int64_t p) const {
    const int32_t v = target.q;
    if (filters & kLeafExact) return point_within(vertices, vertices[v], element(t, p), radius());
    return true;
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
  const Edge* edges;  // by id: the one-pair verdict accept() reads them (nullptr: leaf_edges only)
  const int32_t* sorted_edges;  // the edge tree's leaf order
  float r;
  uint32_t filters;
  const float* rho = nullptr;  // float64 input: how far rounding moved the vertices (float64.h)
  const Vec3* vertices1 = nullptr;  // swept: the positions at t = 1
  const EdgeGroup* leaf_edges = nullptr;  // the edges in the tree's leaf order (or nullptr)
  MINKQ_HD float radius() const { return query_radius(r, rho); }
  MINKQ_HD QueryTarget target(int32_t i) const { return {sorted_edges[i], i}; }
  MINKQ_HD Edge edge(int32_t e, int64_t p) const { return element_at(edges, leaf_edges, e, p); }
  // Static: the edge as a segment. Swept: the edge's swept box, as the box from its low to its
  // high corner (box mode only: the front end refuses the segment modes).
  MINKQ_HD QueryGeometry geometry_of(const Edge& e) const {
    if (vertices1) {
      const Box b = element_box(vertices, vertices1, e);
      return {b.lo, b.hi, radius()};
    }
    return {vertices[e.v[0]], vertices[e.v[1]], radius()};
  }
  MINKQ_HD QueryGeometry geometry(int32_t e) const { return geometry_of(edges[e]); }
  MINKQ_HD QueryGeometry geometry(QueryTarget t) const { return geometry_of(edge(t.q, t.after)); }
  // Whether the leaf filter keeps {e, f}, reached because Shape(e) overlaps f's box: not
  // sharing a vertex (where dropped), then accept_rest.
  template <class Shape>
  MINKQ_HD bool accept(int32_t e, int32_t f) const {
    if ((filters & kDropIncident) && share_vertex(edges[e], edges[f])) return false;
    return accept_rest<Shape>({e, -1}, f, -1);
  }
  // The lanes of `hits` (group `base` of the edge tree's leaf order) that the incidence filter
  // drops: four at a time from leaf_edges, else edge by edge.
  MINKQ_HD unsigned dropped_lanes(QueryTarget target, int64_t base, unsigned hits, const int32_t* sorted_prims) const {
    if (!(filters & kDropIncident)) return 0;
    const Edge a = edge(target.q, target.after);
    if (leaf_edges) return incident_lanes(leaf_edges[base >> 2], a.v[0], a.v[1], hits);
    return lanes_where(hits, [&](int k) { return share_vertex(a, edges[sorted_prims[base + k]]); });
  }
  // The box test is symmetric (box_gap_within) and passed; the finer tests are not: Shape(f)'s
  // finer test against e's box (nothing for the box mode), then the leaf-exact test.
  template <class Shape>
  MINKQ_HD bool tests_rest() const {
    return !is_box_shape<Shape>() || (filters & kLeafExact) != 0;
  }
  // Edge f is at leaf position p (-1: not known).
  template <class Shape>
  MINKQ_HD bool accept_rest(QueryTarget target, int32_t f, int64_t p) const {
    const int32_t e = target.q;
    const Edge a = edge(e, target.after), b = edge(f, p);
    if (!Shape::from(geometry_of(b)).finer(element_box(vertices, vertices1, a))) return false;
    if (!(filters & kLeafExact)) return true;
    // In the pair's own order (lower id first): rounding makes the test's arguments unequal.
    const Edge lo = e < f ? a : b, hi = e < f ? b : a;
    return segment_segment_within(vertices[lo.v[0]], vertices[lo.v[1]], vertices[hi.v[0]], vertices[hi.v[1]], radius());
  }
  MINKQ_HD Pair pair(int32_t e, int32_t f) const { return e < f ? Pair{e, f} : Pair{f, e}; }
};

// The vertex tree against itself (VV: points of codimensional meshes), query i being the
// vertex at sorted leaf position i: as EdgeEdgeQueries, each unordered pair is met once,
// reported as (v, w), v < w, and kept when the node test passes both ways. Swept, each vertex
// is its path (segment shapes against the paths' boxes), with no leaf-exact test. No pair is
// incident (a vertex never pairs with itself).
struct VertexVertexQueries {
  const Vec3* vertices;
  const int32_t* sorted_vertices;  // the vertex tree's leaf order
  float r;
  uint32_t filters;
  const float* rho = nullptr;       // float64 input: how far rounding moved the vertices (float64.h)
  const Vec3* vertices1 = nullptr;  // swept: the positions at t = 1
  MINKQ_HD float radius() const { return query_radius(r, rho); }
  MINKQ_HD QueryTarget target(int32_t i) const { return {sorted_vertices[i], i}; }
  MINKQ_HD QueryGeometry geometry(int32_t v) const {
    return {vertices[v], vertices1 ? vertices1[v] : vertices[v], radius()};
  }
  MINKQ_HD QueryGeometry geometry(QueryTarget t) const { return geometry(t.q); }
  template <class Shape>
  MINKQ_HD bool accept(int32_t v, int32_t w) const {
    return accept_rest<Shape>({v, -1}, w, -1);
  }
  MINKQ_HD unsigned dropped_lanes(QueryTarget, int64_t, unsigned, const int32_t*) const { return 0; }
  template <class Shape>
  MINKQ_HD bool tests_rest() const {
    return !is_box_shape<Shape>() || (filters & kLeafExact) != 0;
  }
  template <class Shape>
  MINKQ_HD bool accept_rest(QueryTarget target, int32_t w, int64_t) const {
    const int32_t v = target.q;
    if (!Shape::from(geometry(w)).finer(PointBoxes{vertices, vertices1}(v))) return false;
    if (!(filters & kLeafExact)) return true;
    const int32_t lo = v < w ? v : w, hi = v < w ? w : v;  // in the pair's own order, as EE
    return point_point_within(vertices[lo], vertices[hi], radius());
  }
  MINKQ_HD Pair pair(int32_t v, int32_t w) const { return v < w ? Pair{v, w} : Pair{w, v}; }
};

// User queries against a tree of user boxes: spheres (p1 == nullptr), capsules, or boxes
// (lo in p0, hi in p1, r == 0). No leaf filter: the node test at a leaf is the exact test.
struct UserQueries {
  const Vec3* p0;
  const Vec3* p1;
  float r;
  MINKQ_HD QueryTarget target(int32_t i) const { return {i, -1}; }
  MINKQ_HD QueryGeometry geometry(int32_t q) const { return {p0[q], p1 ? p1[q] : p0[q], r}; }
  MINKQ_HD QueryGeometry geometry(QueryTarget t) const { return geometry(t.q); }
  template <class Shape>
  MINKQ_HD bool accept(int32_t, int32_t) const { return true; }
  MINKQ_HD unsigned dropped_lanes(QueryTarget, int64_t, unsigned, const int32_t*) const { return 0; }
  template <class Shape>
  MINKQ_HD bool tests_rest() const {
    return false;
  }
  template <class Shape>
  MINKQ_HD bool accept_rest(QueryTarget, int32_t, int64_t) const { return true; }
  MINKQ_HD Pair pair(int32_t q, int32_t b) const { return {q, b}; }
};

// Whether an emitter only counts pairs (a static kCountsOnly member and add(n)): the leaf
// filter then adds a group's candidates at once instead of emitting them one by one.
template <class Emit>
MINKQ_HD constexpr auto counts_only(int) -> decltype(bool(Emit::kCountsOnly)) {
  return Emit::kCountsOnly;
}
template <class Emit>
MINKQ_HD constexpr bool counts_only(long) {
  return false;
}

// The leaf filter of a query target (element q; a self-query's at leaf position `after`), a leaf
// group's hits at a time (positions base + k for the bits k of hits, each a primitive whose box
// the shape overlaps): each is counted, the incidence filter drops lanes (dropped_lanes: four at
// once where the source can), the source's other tests (accept_rest, told the leaf position)
// keep or drop the rest one by one where it has any, and each kept one is emitted as the
// source's pair. accept(q, prim) is the same verdict for one pair, by id. The sources read a
// query's element and the primitives by leaf position where they keep them in leaf order.
template <class Shape, class Queries, class Emit, class Work>
struct LeafFilter {
  const Queries& queries;
  const int32_t* sorted_prims;
  QueryTarget target;
  Emit& emit;
  Work& work;
  MINKQ_HD void operator()(int64_t base, unsigned hits, const BoxGroup& /*group*/) const {
    work.test_primitives(unsigned(popcount(hits)));
    hits &= ~queries.dropped_lanes(target, base, hits, sorted_prims);
    const bool rest = queries.template tests_rest<Shape>();
    if constexpr (counts_only<Emit>(0)) {
      if (!rest) {
        work.emit_candidates(unsigned(popcount(hits)));
        emit.add(unsigned(popcount(hits)));
        return;
      }
    }
    for (; hits != 0; hits &= hits - 1u) {
      const int k = lowest_bit(hits);
      const int32_t prim = sorted_prims[base + k];
      if (rest && !queries.template accept_rest<Shape>(target, prim, base + k)) continue;
      work.emit_candidate();
      const Pair pair = queries.pair(target.q, prim);
      emit(pair.first, pair.second);
    }
  }
};

// Query i of the batch: emit(first, second) for each pair it finds; work counts (or not).
template <class Shape, class Queries, class Emit, class Work>
MINKQ_HD void run_query(const BvhView& bvh, const Queries& queries, int32_t i, Emit& emit, Work& work) {
  const QueryTarget target = queries.target(i);
  const Shape shape = Shape::from(queries.geometry(target));
  LeafFilter<Shape, Queries, Emit, Work> on_hits{queries, bvh.sorted_prims, target, emit, work};
  traverse_groups(bvh, shape, target.after, on_hits, work);
}

}  // namespace minkq
