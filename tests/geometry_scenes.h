// Test-side helpers for scenes of many geometries (minkq_scene_create_geometries): scenes built
// from the oracle's reference::Geometry list, and the checks of testing/geometry_checks.h
// (every mode's pairs against the oracle's contacts in the global numbering) as test failures.
#pragma once

#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

#include "capi_util.h"
#include "geometry_checks.h"
#include "minkq.h"
#include "minkq_reference.h"

namespace minkq::test {

namespace ref = reference;

// The shared part lives in testing/geometry_checks.h (the differential fuzzer runs it too).
using fuzz::GeometryDescriptions;
using fuzz::geometry_vertices;
using fuzz::kAllQueryKinds;
using fuzz::kind_name;
using fuzz::modes_of;
using fuzz::query_kind;
using fuzz::rounding_rho;
inline constexpr uint32_t kAllKinds = fuzz::kAllGeometryKinds;

inline ref::Geometry make_geometry(ref::Mesh mesh, uint32_t kinds, uint32_t flags, int32_t world = 0) {
  ref::Geometry g;
  g.mesh = std::move(mesh);
  g.kinds = kinds;
  g.flags = flags;
  g.world = world;
  return g;
}

// Thickness is given to the scene as floats: the oracle takes the same values.
inline void set_thickness(ref::Geometry& g, const std::vector<float>& t) { g.thickness.assign(t.begin(), t.end()); }

inline cxx::Scene new_geometry_scene(minkq_device* device, const std::vector<ref::Geometry>& geometries) {
  const GeometryDescriptions d(geometries);
  return created<cxx::Scene>([&](minkq_scene** out) { return d.create(device, out); });
}

// Every mode of `kind`, with and without LEAF_EXACT, against the oracle and the rules
// (fuzz::check_geometry_kind); returns the oracle's contacts.
inline Pairs check_kind(minkq_scene* scene, const std::vector<ref::Geometry>& geometries, ref::Kind kind, float r,
                        const std::string& what) {
  fuzz::Report report;
  const Pairs truth = fuzz::check_geometry_kind(scene, geometries, kind, r, 1, report, what);
  EXPECT_TRUE(report.ok()) << report.text();
  return truth;
}

// check_kind for every kind the scene answers (the union of its geometries' kinds).
inline void check_scene(minkq_scene* scene, const std::vector<ref::Geometry>& geometries, float r,
                        const std::string& what) {
  fuzz::Report report;
  fuzz::check_geometry_scene(scene, geometries, r, 1, report, what);
  EXPECT_TRUE(report.ok()) << report.text();
}

}  // namespace minkq::test
