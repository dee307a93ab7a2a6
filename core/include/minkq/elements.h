// The elements of a mesh scene: triangles and edges by their vertex ids, the incidence the
// kDropIncident filter drops, their boxes (static, or swept over a step's two positions), the
// boxes of points, and the leaf-exact test of a vertex against an element.
#pragma once

#include "minkq/predicates.h"
#include "minkq/thickness.h"

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
// The box a tree holds for an element: its box grown by its thickness (thickness.h; the box
// itself without a thickness array).
template <class Prim>
MINKQ_HD Box reach_box(const Vec3* vertices, const Vec3* vertices1, const float* thickness, const Prim& e) {
  return grow_box(element_box(vertices, vertices1, e), element_thickness(thickness, e));
}
// The box of element i, by id; thickness_of(t, i) its thickness.
template <class Prim>
struct ElementBoxes {
  const Vec3* vertices;
  const Prim* prims;
  const Vec3* vertices1 = nullptr;  // swept: the positions at t = 1
  MINKQ_HD Box operator()(int32_t i) const { return element_box(vertices, vertices1, prims[i]); }
  MINKQ_HD float thickness_of(const float* thickness, int32_t i) const { return element_thickness(thickness, prims[i]); }
};
using TriangleBoxes = ElementBoxes<Triangle>;
using EdgeBoxes = ElementBoxes<Edge>;
// The box of point i (a vertex tree's element): the point, or swept the box of its path.
struct PointBoxes {
  const Vec3* points;
  const Vec3* points1 = nullptr;  // swept: the positions at t = 1 (the box of the path)
  MINKQ_HD Box operator()(int32_t i) const {
    const Box b = Box::of_point(points[i]);
    return points1 ? box_expand(b, points1[i]) : b;
  }
  MINKQ_HD float thickness_of(const float* thickness, int32_t i) const { return vertex_thickness(thickness, i); }
};

// Boxes (ElementBoxes, PointBoxes, LeafBoxes) grown by their elements' thickness: what a tree
// holds for a geometry with thickness. A type of its own, so that a tree without thickness runs
// the plain boxes' code.
template <class Boxes>
struct GrownBoxes : Boxes {
  const float* thickness;
  MINKQ_HD Box operator()(int32_t i) const { return grow_box(Boxes::operator()(i), Boxes::thickness_of(thickness, i)); }
};

// The leaf-exact test of a vertex against a triangle or an edge.
MINKQ_HD bool point_within(const Vec3* vertices, Vec3 p, const Triangle& t, float r) {
  return point_triangle_within(p, vertices[t.v[0]], vertices[t.v[1]], vertices[t.v[2]], r);
}
MINKQ_HD bool point_within(const Vec3* vertices, Vec3 p, const Edge& e, float r) {
  return point_segment_within(p, vertices[e.v[0]], vertices[e.v[1]], r);
}

}  // namespace minkq
