// The candidate sets each mode defines (minkq.h), computed by brute force with minkq's own
// shape tests and leaf filters: the mode -> shape mapping, the scenes' geometry in the core's
// types, the set containers, and the interface of an independent traversal computing the same
// sets (the Embree reference). Part of the scene checks (scene_checks.h includes every part).
#pragma once

#include <cstring>
#include <type_traits>

#include "minkq/bvh.h"
#include "minkq/float64.h"
#include "by_id_queries.h"
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
    for (int32_t p = std::is_same<Queries, EdgeEdgeById>::value ? q + 1 : 0; p < num_prims; ++p)
      if (shape.overlaps(boxes(p)) && queries.template accept<Shape>(q, p)) out.push_back({q, p});
  }
  return out;
}

// The geometry of a mesh scene in the core's types; swept (after set_end), the vertices move
// from `vertices` to `vertices1` and the queries and boxes are the swept ones (elements.h).
struct MeshGeometry {
  std::vector<Vec3> vertices;
  std::vector<Triangle> triangles;
  std::vector<Edge> edges;
  std::vector<Vec3> vertices1;  // swept: the positions at t = 1; empty for static positions
  MeshGeometry(const std::vector<float>& xyz, const std::vector<int32_t>& tris, const std::vector<int32_t>& edge_ids)
      : vertices(xyz.size() / 3), triangles(tris.size() / 3), edges(edge_ids.size() / 2) {
    if (!xyz.empty()) std::memcpy(vertices.data(), xyz.data(), vertices.size() * sizeof(Vec3));
    if (!tris.empty()) std::memcpy(triangles.data(), tris.data(), triangles.size() * sizeof(Triangle));
    if (!edge_ids.empty()) std::memcpy(edges.data(), edge_ids.data(), edges.size() * sizeof(Edge));
  }
  int32_t nv() const { return int32_t(vertices.size()); }
  int32_t nt() const { return int32_t(triangles.size()); }
  int32_t ne() const { return int32_t(edges.size()); }
  // Makes the geometry swept: the vertices move to `xyz1` (3 floats per vertex) over the step.
  void set_end(const std::vector<float>& xyz1) {
    vertices1.resize(xyz1.size() / 3);
    if (!xyz1.empty()) std::memcpy(vertices1.data(), xyz1.data(), vertices1.size() * sizeof(Vec3));
  }
  bool swept() const { return !vertices1.empty(); }
  const Vec3* end() const { return swept() ? vertices1.data() : nullptr; }
  // The VT and EE sources by id (by_id_queries.h).
  VertexTriangleById vt(float r, uint32_t filters) const {
    return {{vertices.data(), nullptr, nullptr, r, filters, nullptr, end()}, triangles.data()};
  }
  EdgeEdgeById ee(float r, uint32_t filters) const {
    return {{vertices.data(), nullptr, nullptr, r, filters, nullptr, end()}, edges.data()};
  }
  TriangleBoxes triangle_boxes() const { return {vertices.data(), triangles.data(), end()}; }
  EdgeBoxes edge_boxes() const { return {vertices.data(), edges.data(), end()}; }
};

// ---- Float64 input: the radius the scene queries with ----------------------------------------

// rho of float64 positions: the farthest rounding to nearest float moved a vertex, as the
// library computes it (float64.h, rounding_distance: the exact distance rounded up); 0 for float
// input. A swept step's rho is the larger of its two position sets'.
inline float rounding_rho(const Positions& p) {
  float rho = 0.0f;
  for (size_t v = 0; p.float64() && v < p.count(); ++v) {
    const double* x = &p.xyz64[3 * v];
    rho = std::max(rho, rounding_distance(x, round_to_float(x)));
  }
  return rho;
}
// The radius a query of radius r runs with on a scene whose rounding moved vertices by rho:
// r + 2 rho rounded up (minkq.h, MINKQ_SCENE_FLOAT64; float64.h, widen_radius); r for float input.
inline float scene_radius(float r, float rho) { return widen_radius(r, rho); }

// ---- Swept steps ---------------------------------------------------------------------------

// The shape minkq.h defines for a VT mode on swept positions: the vertex is its path, a
// segment, so every mode is a segment shape, and sphere is capsule_exact. EE runs box mode only.
template <class Fn>
void swept_vt_shape_of_mode(int mode, Fn&& fn) {
  switch (mode) {
    case MINKQ_MODE_BOX: fn(BoxShape{}); return;
    case MINKQ_MODE_CAPSULE_RAY: fn(CapsuleRayShape{}); return;
    default: fn(CapsuleExactShape{}); return;  // sphere and capsule_exact
  }
}

// Candidate sets of a swept step: VT [mode], EE box (the only EE mode swept queries run).
struct SweptSets {
  Pairs vt[4];
  Pairs ee_box;
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
  UserById queries(float r) const { return {{first.data(), second.empty() ? nullptr : second.data(), r}}; }
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
  // The swept sets of a swept geometry (g.swept()); `moved`: as for mesh_sets.
  virtual SweptSets swept_sets(const MeshGeometry& g, float r, uint32_t filters, bool moved) = 0;
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

// The swept step's sets by brute force: each mode's shape of the vertex's path against every
// triangle's swept box, and the edges' swept boxes against each other, with the leaf filter.
inline SweptSets swept_definition_sets(const MeshGeometry& g, float r, uint32_t filters) {
  SweptSets sets;
  for (int mode = 0; mode < 4; ++mode)
    swept_vt_shape_of_mode(mode, [&](auto shape) {
      sets.vt[mode] = definition_set<decltype(shape)>(g.vt(r, filters), g.nv(), g.triangle_boxes(), g.nt());
    });
  sets.ee_box = definition_set<BoxShape>(g.ee(r, filters), g.ne(), g.edge_boxes(), g.ne());
  return sets;
}

// The box mode of a swept step written out plainly, sharing nothing with the core but the
// positions (minkq.h: "the elements' swept boxes"; tests/test_swept.cpp): each element's box
// over its vertices' two positions, a pair when the two boxes' gap (float subtraction) is at most
// r on every axis; incident pairs dropped when asked, EE pairs once (e < f).
struct PlainSweptBoxes {
  std::vector<float> lo, hi;  // 3 per element
  void add(const std::vector<const float*>& points) {
    for (int a = 0; a < 3; ++a) {
      float l = points[0][a], h = points[0][a];
      for (const float* p : points) l = std::min(l, p[a]), h = std::max(h, p[a]);
      lo.push_back(l);
      hi.push_back(h);
    }
  }
  bool within(size_t i, const PlainSweptBoxes& other, size_t j, float r) const {
    for (int a = 0; a < 3; ++a)
      if (!(other.lo[3 * j + a] - hi[3 * i + a] <= r) || !(lo[3 * i + a] - other.hi[3 * j + a] <= r)) return false;
    return true;
  }
};
inline std::pair<Pairs, Pairs> plain_swept_box_sets(const std::vector<float>& x0, const std::vector<float>& x1,
                                                    const std::vector<int32_t>& tris, const std::vector<int32_t>& edges,
                                                    float r, bool drop_incident) {
  auto p0 = [&](int32_t v) { return x0.data() + 3 * size_t(v); };
  auto p1 = [&](int32_t v) { return x1.data() + 3 * size_t(v); };
  const size_t nv = x0.size() / 3, nt = tris.size() / 3, ne = edges.size() / 2;
  PlainSweptBoxes paths, triangles, edge_boxes;
  for (size_t v = 0; v < nv; ++v) paths.add({p0(int32_t(v)), p1(int32_t(v))});
  for (size_t t = 0; t < 3 * nt; t += 3)
    triangles.add({p0(tris[t]), p0(tris[t + 1]), p0(tris[t + 2]), p1(tris[t]), p1(tris[t + 1]), p1(tris[t + 2])});
  for (size_t e = 0; e < 2 * ne; e += 2) edge_boxes.add({p0(edges[e]), p0(edges[e + 1]), p1(edges[e]), p1(edges[e + 1])});
  Pairs vt, ee;
  for (size_t v = 0; v < nv; ++v)
    for (size_t t = 0; t < nt; ++t) {
      const bool incident = tris[3 * t] == int32_t(v) || tris[3 * t + 1] == int32_t(v) || tris[3 * t + 2] == int32_t(v);
      if (!(drop_incident && incident) && paths.within(v, triangles, t, r)) vt.push_back({int32_t(v), int32_t(t)});
    }
  for (size_t e = 0; e < ne; ++e)
    for (size_t f = e + 1; f < ne; ++f) {
      const int32_t a0 = edges[2 * e], a1 = edges[2 * e + 1], b0 = edges[2 * f], b1 = edges[2 * f + 1];
      const bool incident = a0 == b0 || a0 == b1 || a1 == b0 || a1 == b1;
      if (!(drop_incident && incident) && edge_boxes.within(e, edge_boxes, f, r)) ee.push_back({int32_t(e), int32_t(f)});
    }
  return {vt, ee};
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
