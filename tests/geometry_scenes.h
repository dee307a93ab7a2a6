// Test-side helpers for scenes of many geometries (minkq_scene_create_geometries): the C
// descriptions of the oracle's reference::Geometry list, and the check of every mode's pairs
// against the oracle's contacts in the global numbering.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "capi_util.h"
#include "minkq.h"
#include "minkq_reference.h"

namespace minkq::test {

namespace ref = reference;

// The oracle's bit values are the C API's.
static_assert(ref::kKindVT == MINKQ_SCENE_VT && ref::kKindEE == MINKQ_SCENE_EE && ref::kKindVV == MINKQ_SCENE_VV &&
              ref::kKindEV == MINKQ_SCENE_EV);
static_assert(ref::kSelf == MINKQ_GEOMETRY_SELF && ref::kDropIncident == MINKQ_GEOMETRY_DROP_INCIDENT &&
              ref::kFloat64 == MINKQ_GEOMETRY_FLOAT64 && ref::kStatic == MINKQ_GEOMETRY_STATIC);

inline constexpr uint32_t kAllKinds = ref::kKindVT | ref::kKindEE | ref::kKindVV | ref::kKindEV;
inline const ref::Kind kAllQueryKinds[] = {ref::Kind::VT, ref::Kind::EE, ref::Kind::VV, ref::Kind::EV};

inline minkq_query_kind query_kind(ref::Kind kind) {
  switch (kind) {
    case ref::Kind::VT: return MINKQ_QUERY_VT;
    case ref::Kind::EE: return MINKQ_QUERY_EE;
    case ref::Kind::VV: return MINKQ_QUERY_VV;
    case ref::Kind::EV: return MINKQ_QUERY_EV;
  }
  return MINKQ_QUERY_VT;
}
inline const char* kind_name(ref::Kind kind) {
  const char* names[] = {"VT", "EE", "VV", "EV"};
  return names[int(kind)];
}
inline std::vector<minkq_mode> modes_of(ref::Kind kind) {
  if (kind == ref::Kind::EE) return {MINKQ_MODE_BOX, MINKQ_MODE_CAPSULE_RAY, MINKQ_MODE_CAPSULE_EXACT};
  return {MINKQ_MODE_BOX, MINKQ_MODE_SPHERE, MINKQ_MODE_CAPSULE_RAY, MINKQ_MODE_CAPSULE_EXACT};
}

inline ref::Geometry make_geometry(ref::Mesh mesh, uint32_t kinds, uint32_t flags, int32_t world = 0) {
  ref::Geometry g;
  g.mesh = std::move(mesh);
  g.kinds = kinds;
  g.flags = flags;
  g.world = world;
  return g;
}

// A geometry's vertices as the scene reads them: its double input with FLOAT64, else floats.
inline minkq_buffer geometry_vertices(const ref::Geometry& g) {
  if (g.flags & MINKQ_GEOMETRY_FLOAT64) return host_buffer(g.mesh.xyz64.data(), g.mesh.xyz64.size() / 3);
  return host_buffer(g.mesh.xyz.data(), g.mesh.xyz.size() / 3);
}

// The C descriptions of the geometries, with the float thickness they point to. Edges are
// passed when the mesh holds them (the oracle's rule: given edges are kept), else derived.
struct Descriptions {
  std::vector<minkq_geometry_desc> descs;
  std::vector<std::vector<float>> thickness;

  explicit Descriptions(const std::vector<ref::Geometry>& geometries) : thickness(geometries.size()) {
    for (size_t i = 0; i < geometries.size(); ++i) {
      const ref::Geometry& g = geometries[i];
      minkq_geometry_desc d;
      minkq_geometry_desc_init(&d);
      d.kinds = g.kinds, d.flags = g.flags, d.world = g.world, d.group = g.group, d.mask = g.mask;
      d.vertices = geometry_vertices(g);
      d.triangles = host_buffer(g.mesh.tris.data(), g.mesh.tris.size() / 3);
      d.edges = host_buffer(g.mesh.edges.data(), g.mesh.edges.size() / 2);
      thickness[i].assign(g.thickness.begin(), g.thickness.end());
      d.thickness = host_buffer(thickness[i].data(), thickness[i].size());
      descs.push_back(d);
    }
  }
  minkq_status create(minkq_device* device, minkq_scene** out) const {
    return minkq_scene_create_geometries(device, descs.data(), descs.size(), out);
  }
};

// Thickness is given to the scene as floats: the oracle takes the same values.
inline void set_thickness(ref::Geometry& g, const std::vector<float>& t) { g.thickness.assign(t.begin(), t.end()); }

inline cxx::Scene new_geometry_scene(minkq_device* device, const std::vector<ref::Geometry>& geometries) {
  const Descriptions d(geometries);
  return created<cxx::Scene>([&](minkq_scene** out) { return d.create(device, out); });
}

// rho of minkq.h over the double geometries: the farthest rounding to float moves a vertex.
inline double rounding_rho(const std::vector<ref::Geometry>& geometries) {
  double rho = 0;
  for (const ref::Geometry& g : geometries)
    for (size_t v = 0; (g.flags & MINKQ_GEOMETRY_FLOAT64) && v < g.mesh.vertex_count(); ++v) {
      double d2 = 0;
      for (int k = 0; k < 3; ++k) {
        const double d = g.mesh.xyz64[3 * v + k] - double(float(g.mesh.xyz64[3 * v + k]));
        d2 += d * d;
      }
      rho = std::max(rho, std::sqrt(d2));
    }
  return rho;
}

// The pairs of every mode of `kind`, with and without LEAF_EXACT, against the oracle: no
// contact lost, no pair the rules exclude (worlds, groups, masks, SELF, incident, each pair
// once), finer modes inside coarser ones (points: capsule_ray is box, capsule_exact sphere),
// leaf-exact pairs inside their mode's, and leaf-exact extras within their reach
// r + t(a) + t(b) plus the slack of minkq_scene_query. For double input that reach is grown by
// 2 rho on the rounded positions, which lie up to rho from the double ones at each end of the
// pair: within 4 rho more on the double input that the oracle measures. Returns the oracle's
// contacts.
inline Pairs check_kind(minkq_scene* scene, const std::vector<ref::Geometry>& geometries, ref::Kind kind, float r,
                        const std::string& what) {
  SCOPED_TRACE(what + " " + kind_name(kind) + " r=" + std::to_string(r));
  const Pairs truth = ref::geometry_contacts(geometries, kind, double(r));
  const double rho4 = 4 * rounding_rho(geometries);
  Pairs plain[4];
  for (uint32_t flags : {0u, uint32_t(MINKQ_QUERY_LEAF_EXACT)})
    for (minkq_mode mode : modes_of(kind)) {
      const Pairs got = Scene::query_pairs(scene, query_kind(kind), mode, r, flags);
      const std::string at = std::string(" mode ") + std::to_string(mode) + " flags " + std::to_string(flags);
      EXPECT_TRUE(is_subset(truth, got)) << "lost" << at << ": " << describe(difference(truth, got));
      EXPECT_TRUE(std::adjacent_find(got.begin(), got.end()) == got.end()) << "a pair twice" << at;
      const Pairs excluded = ref::not_allowed(geometries, kind, got);
      EXPECT_TRUE(excluded.empty()) << "pairs the rules exclude" << at << ": " << describe(excluded);
      if (!flags) {
        plain[mode] = got;
        continue;
      }
      EXPECT_TRUE(is_subset(got, plain[mode])) << "leaf-exact pairs outside the mode's" << at;
      const Pairs extras = difference(got, truth);
      const auto measured = ref::measure_pairs(geometries, kind, extras, double(r));
      for (size_t i = 0; i < extras.size(); ++i)
        EXPECT_LE(double(measured[i].distance),
                  (measured[i].reach + rho4) * (1 + 0x1p-20) + 0x1p-19 * measured[i].scale)
            << "leaf-exact extra" << at << ": " << describe({extras[i]}) << " reach " << measured[i].reach;
    }
  EXPECT_TRUE(is_subset(plain[MINKQ_MODE_CAPSULE_EXACT], plain[MINKQ_MODE_CAPSULE_RAY]));
  EXPECT_TRUE(is_subset(plain[MINKQ_MODE_CAPSULE_RAY], plain[MINKQ_MODE_BOX]));
  if (kind != ref::Kind::EE) {
    EXPECT_TRUE(is_subset(plain[MINKQ_MODE_SPHERE], plain[MINKQ_MODE_BOX]));
    EXPECT_EQ(plain[MINKQ_MODE_CAPSULE_RAY], plain[MINKQ_MODE_BOX]) << "points: capsule_ray is the box test";
    EXPECT_EQ(plain[MINKQ_MODE_CAPSULE_EXACT], plain[MINKQ_MODE_SPHERE]) << "points: capsule_exact is the sphere test";
  }
  return truth;
}

// check_kind for every kind the scene answers (the union of its geometries' kinds).
inline void check_scene(minkq_scene* scene, const std::vector<ref::Geometry>& geometries, float r,
                        const std::string& what) {
  uint32_t kinds = 0;
  for (const ref::Geometry& g : geometries) kinds |= g.kinds;
  const uint32_t bits[] = {ref::kKindVT, ref::kKindEE, ref::kKindVV, ref::kKindEV};
  for (int k = 0; k < 4; ++k)
    if (kinds & bits[k]) check_kind(scene, geometries, kAllQueryKinds[k], r, what);
}

}  // namespace minkq::test
