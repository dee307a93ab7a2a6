// The candidate sets each mode defines (minkq.h), computed by brute force with minkq's own
// shape tests and leaf filters: the mode -> shape mapping, the scenes' geometry in the core's
// types, the set containers, and the interface of an independent traversal computing the same
// sets (the Embree reference). Part of the scene checks (scene_checks.h includes every part).
#pragma once

#include <cstring>
#include <type_traits>

#include "minkq/queries.h"
#include "scene_types.h"

namespace minkq::fuzz {

// ---- Modes --------------------------------------------------------------------------------------

inline const char* mode_name(int mode) {
  static const char* names[] = {"box", "sphere", "capsule_ray", "capsule_exact"};
  return mode >= 0 && mode < 4 ? names[mode] : "?";
}

// The shape that minkq.h defines for a mode: points are zero-length capsules, so for points
// capsule_ray is the box test and capsule_exact the sphere test. (Written here independently
// of the backend's own mapping, which this checks.)
template <class Fn>
void shape_of_mode(int mode, bool points, Fn&& fn) {
  switch (mode) {
    case MINKQ_MODE_BOX: fn(BoxShape{}); return;
    case MINKQ_MODE_SPHERE: fn(SphereShape{}); return;
    case MINKQ_MODE_CAPSULE_RAY:
      if (points) fn(BoxShape{}); else fn(CapsuleRayShape{});
      return;
    default:
      if (points) fn(SphereShape{}); else fn(CapsuleExactShape{});
      return;
  }
}

// The candidate set a mode defines: the shape's node test applied to every primitive box,
// AND the leaf filter; EE (the edges against themselves) over the pairs q < p only.
template <class Shape, class Queries, class Boxes>
Pairs definition_set(const Queries& queries, int32_t num_queries, const Boxes& boxes, int32_t num_prims) {
  Pairs out;
  for (int32_t q = 0; q < num_queries; ++q) {
    const Shape shape = Shape::from(queries.geometry(q));
    for (int32_t p = std::is_same<Queries, EdgeEdgeQueries>::value ? q + 1 : 0; p < num_prims; ++p)
      if (shape.overlaps(boxes(p)) && queries.template accept<Shape>(q, p)) out.push_back({q, p});
  }
  return out;
}

// The geometry of a mesh scene in the core's types.
struct MeshGeometry {
  std::vector<Vec3> vertices;
  std::vector<Triangle> triangles;
  std::vector<Edge> edges;
  MeshGeometry(const std::vector<float>& xyz, const std::vector<int32_t>& tris, const std::vector<int32_t>& edge_ids)
      : vertices(xyz.size() / 3), triangles(tris.size() / 3), edges(edge_ids.size() / 2) {
    if (!xyz.empty()) std::memcpy(vertices.data(), xyz.data(), vertices.size() * sizeof(Vec3));
    if (!tris.empty()) std::memcpy(triangles.data(), tris.data(), triangles.size() * sizeof(Triangle));
    if (!edge_ids.empty()) std::memcpy(edges.data(), edge_ids.data(), edges.size() * sizeof(Edge));
  }
  int32_t nv() const { return int32_t(vertices.size()); }
  int32_t nt() const { return int32_t(triangles.size()); }
  int32_t ne() const { return int32_t(edges.size()); }
  VertexTriangleQueries vt(float r, uint32_t filters) const {
    return {vertices.data(), triangles.data(), nullptr, r, filters};
  }
  EdgeEdgeQueries ee(float r, uint32_t filters) const { return {vertices.data(), edges.data(), nullptr, r, filters}; }
  TriangleBoxes triangle_boxes() const { return {vertices.data(), triangles.data()}; }
  EdgeBoxes edge_boxes() const { return {vertices.data(), edges.data()}; }
};

// Candidate sets of a mesh scene: [mode][leaf_exact]; EE has no sphere mode (index 1 unused).
struct MeshSets {
  Pairs vt[4][2];
  Pairs ee[4][2];
};
inline bool ee_mode(int mode) { return mode != MINKQ_MODE_SPHERE; }

// Sets of a user-box scene: [mode]; the modes a shape allows (see minkq_shape).
struct BoxSets {
  Pairs by_mode[4];
};
inline bool box_scene_mode(minkq_shape shape, int mode) {
  if (shape == MINKQ_SHAPE_BOX) return mode == MINKQ_MODE_BOX;
  if (shape == MINKQ_SHAPE_CAPSULE) return mode != MINKQ_MODE_SPHERE;
  return true;
}

// The user-box scene in the core's types.
struct BoxGeometry {
  std::vector<Box> boxes;
  std::vector<Vec3> first, second;
  BoxGeometry(const std::vector<float>& b, const std::vector<float>& f, const std::vector<float>& s)
      : boxes(b.size() / 6), first(f.size() / 3), second(s.size() / 3) {
    if (!b.empty()) std::memcpy(boxes.data(), b.data(), boxes.size() * sizeof(Box));
    if (!f.empty()) std::memcpy(first.data(), f.data(), first.size() * sizeof(Vec3));
    if (!s.empty()) std::memcpy(second.data(), s.data(), second.size() * sizeof(Vec3));
  }
  UserQueries queries(float r) const { return {first.data(), second.empty() ? nullptr : second.data(), r}; }
  GivenBoxes given_boxes() const { return {boxes.data()}; }
  int32_t nq() const { return int32_t(first.size()); }
  int32_t nb() const { return int32_t(boxes.size()); }
};

// An independent traversal computing the sets of the same definitions (the Embree reference).
// `moved` says the positions changed since the previous call for the same scene (a refit).
class IndependentSets {
 public:
  virtual ~IndependentSets() = default;
  // False where the independent traversal cannot take the input (Embree drops huge coordinates).
  virtual bool accepts(const std::vector<float>& coordinates, float r) const = 0;
  virtual MeshSets mesh_sets(const MeshGeometry& g, float r, uint32_t filters, bool moved) = 0;
  virtual BoxSets box_sets(const BoxGeometry& g, minkq_shape shape, float r, bool moved) = 0;
  virtual void reset() = 0;  // release what the previous scene left
};

inline MeshSets definition_sets(const MeshGeometry& g, float r, uint32_t filters) {
  MeshSets sets;
  for (int leaf = 0; leaf < 2; ++leaf) {
    const uint32_t f = filters | (leaf ? kLeafExact : 0u);
    for (int mode = 0; mode < 4; ++mode) {
      shape_of_mode(mode, true, [&](auto shape) {
        sets.vt[mode][leaf] = definition_set<decltype(shape)>(g.vt(r, f), g.nv(), g.triangle_boxes(), g.nt());
      });
      if (ee_mode(mode))
        shape_of_mode(mode, false, [&](auto shape) {
          sets.ee[mode][leaf] = definition_set<decltype(shape)>(g.ee(r, f), g.ne(), g.edge_boxes(), g.ne());
        });
    }
  }
  return sets;
}

inline BoxSets definition_sets(const BoxGeometry& g, minkq_shape shape, float r) {
  BoxSets sets;
  for (int mode = 0; mode < 4; ++mode)
    if (box_scene_mode(shape, mode))
      shape_of_mode(mode, shape == MINKQ_SHAPE_SPHERE, [&](auto s) {
        sets.by_mode[mode] = definition_set<decltype(s)>(g.queries(r), g.nq(), g.given_boxes(), g.nb());
      });
  return sets;
}

}  // namespace minkq::fuzz
