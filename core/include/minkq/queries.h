// Query sources: where query q's geometry comes from, which primitive boxes a tree holds, and
// which (query, primitive) pairs the leaf filter keeps. run_query ties a source to a shape
// and to the one traversal; backends call it per query and supply only emit(q, prim).
#pragma once

#include "minkq/bvh.h"
#include "minkq/shapes.h"

namespace minkq {

struct Triangle {
  int32_t v[3];
};
struct Edge {
  int32_t v[2];
};

// Filter bits, numbered as the C API's flags.
constexpr uint32_t kDropIncident = 1u;  // VT: vertex of the triangle; EE: edges sharing a vertex
constexpr uint32_t kLeafExact = 2u;     // primitive distance test at the leaves

// ---- Primitive boxes -----------------------------------------------------------------------
struct TriangleBoxes {
  const Vec3* vertices;
  const Triangle* triangles;
  MINKQ_HD Box operator()(int32_t t) const {
    const Triangle tri = triangles[t];
    return box_expand(box_expand(Box::of_point(vertices[tri.v[0]]), vertices[tri.v[1]]), vertices[tri.v[2]]);
  }
};
struct EdgeBoxes {
  const Vec3* vertices;
  const Edge* edges;
  MINKQ_HD Box operator()(int32_t e) const {
    const Edge edge = edges[e];
    return box_expand(Box::of_point(vertices[edge.v[0]]), vertices[edge.v[1]]);
  }
};
struct GivenBoxes {
  const Box* boxes;
  MINKQ_HD Box operator()(int32_t i) const { return boxes[i]; }
};

// ---- Query sources ---------------------------------------------------------------------------
// Vertex v against the triangle tree; pairs (v, t).
struct VertexTriangleQueries {
  const Vec3* vertices;
  const Triangle* triangles;
  float r;
  uint32_t filters;
  MINKQ_HD QueryGeometry geometry(int32_t v) const { return {vertices[v], vertices[v], r}; }
  MINKQ_HD bool accept(int32_t v, int32_t t) const {
    const Triangle tri = triangles[t];
    if ((filters & kDropIncident) && (tri.v[0] == v || tri.v[1] == v || tri.v[2] == v)) return false;
    if (filters & kLeafExact)
      return point_triangle_within(vertices[v], vertices[tri.v[0]], vertices[tri.v[1]], vertices[tri.v[2]], r);
    return true;
  }
};

// Edge e against the edge tree; each unordered pair once, as (e, f) with e < f.
struct EdgeEdgeQueries {
  const Vec3* vertices;
  const Edge* edges;
  float r;
  uint32_t filters;
  MINKQ_HD QueryGeometry geometry(int32_t e) const {
    return {vertices[edges[e].v[0]], vertices[edges[e].v[1]], r};
  }
  MINKQ_HD bool accept(int32_t e, int32_t f) const {
    if (f <= e) return false;
    const Edge a = edges[e], b = edges[f];
    if ((filters & kDropIncident) &&
        (a.v[0] == b.v[0] || a.v[0] == b.v[1] || a.v[1] == b.v[0] || a.v[1] == b.v[1]))
      return false;
    if (filters & kLeafExact)
      return segment_segment_within(vertices[a.v[0]], vertices[a.v[1]], vertices[b.v[0]], vertices[b.v[1]], r);
    return true;
  }
};

// User queries against a tree of user boxes: spheres (p1 == nullptr), capsules, or boxes
// (lo in p0, hi in p1, r == 0). No leaf filter: the node test at a leaf is the exact test.
struct UserQueries {
  const Vec3* p0;
  const Vec3* p1;
  float r;
  MINKQ_HD QueryGeometry geometry(int32_t q) const { return {p0[q], p1 ? p1[q] : p0[q], r}; }
  MINKQ_HD bool accept(int32_t, int32_t) const { return true; }
};

template <class Shape, class Queries, class Emit>
MINKQ_HD void run_query(const BvhView& bvh, const Queries& queries, int32_t q, Emit& emit) {
  const Shape shape = Shape::from(queries.geometry(q));
  auto on_leaf = [&](int32_t prim) {
    if (queries.accept(q, prim)) emit(q, prim);
  };
  traverse(bvh, shape, on_leaf);
}

}  // namespace minkq
