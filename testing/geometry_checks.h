// The checks of a scene of many geometries (minkq_scene_create_geometries) against the oracle's
// contacts in the global numbering (reference::geometry_contacts), shared by the tests (through
// tests/geometry_scenes.h) and the differential fuzzer (through geometry_scene_checks.h): the
// C descriptions of the oracle's reference::Geometry list, and every mode of a kind, with and
// without LEAF_EXACT, checked against the oracle and the rules of minkq.h.
#pragma once

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "minkq.h"
#include "minkq.hpp"
#include "minkq_reference.h"
#include "scene_runs.h"

namespace minkq::fuzz {

namespace ref = reference;

// The oracle's bit values are the C API's.
static_assert(ref::kKindVT == MINKQ_SCENE_VT && ref::kKindEE == MINKQ_SCENE_EE && ref::kKindVV == MINKQ_SCENE_VV &&
              ref::kKindEV == MINKQ_SCENE_EV);
static_assert(ref::kSelf == MINKQ_GEOMETRY_SELF && ref::kDropIncident == MINKQ_GEOMETRY_DROP_INCIDENT &&
              ref::kFloat64 == MINKQ_GEOMETRY_FLOAT64 && ref::kStatic == MINKQ_GEOMETRY_STATIC);

inline constexpr uint32_t kAllGeometryKinds = ref::kKindVT | ref::kKindEE | ref::kKindVV | ref::kKindEV;
inline const ref::Kind kAllQueryKinds[] = {ref::Kind::VT, ref::Kind::EE, ref::Kind::VV, ref::Kind::EV};
inline constexpr uint32_t kKindBits[] = {ref::kKindVT, ref::kKindEE, ref::kKindVV, ref::kKindEV};

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
// The union of the geometries' kinds: the kinds the scene answers.
inline uint32_t scene_kinds(const std::vector<ref::Geometry>& geometries) {
  uint32_t kinds = 0;
  for (const ref::Geometry& g : geometries) kinds |= g.kinds;
  return kinds;
}

// A geometry's vertices as the scene reads them: its double input with FLOAT64, else floats.
inline minkq_buffer geometry_vertices(const ref::Geometry& g) {
  if (g.flags & MINKQ_GEOMETRY_FLOAT64) return cxx::host_buffer(g.mesh.xyz64.data(), g.mesh.xyz64.size() / 3);
  return cxx::host_buffer(g.mesh.xyz.data(), g.mesh.xyz.size() / 3);
}

// The C descriptions of the geometries, with the float thickness they point to. Edges are
// passed when the mesh holds them (the oracle's rule: given edges are kept), else derived.
struct GeometryDescriptions {
  std::vector<minkq_geometry_desc> descs;
  std::vector<std::vector<float>> thickness;

  explicit GeometryDescriptions(const std::vector<ref::Geometry>& geometries) : thickness(geometries.size()) {
    for (size_t i = 0; i < geometries.size(); ++i) {
      const ref::Geometry& g = geometries[i];
      minkq_geometry_desc d;
      minkq_geometry_desc_init(&d);
      d.kinds = g.kinds, d.flags = g.flags, d.world = g.world, d.group = g.group, d.mask = g.mask;
      d.vertices = geometry_vertices(g);
      d.triangles = cxx::host_buffer(g.mesh.tris.data(), g.mesh.tris.size() / 3);
      d.edges = cxx::host_buffer(g.mesh.edges.data(), g.mesh.edges.size() / 2);
      thickness[i].assign(g.thickness.begin(), g.thickness.end());
      d.thickness = cxx::host_buffer(thickness[i].data(), thickness[i].size());
      descs.push_back(d);
    }
  }
  minkq_status create(minkq_device* device, minkq_scene** out) const {
    return minkq_scene_create_geometries(device, descs.data(), descs.size(), out);
  }
};

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

// The global counts of a kind's first and second elements (vertices, triangles or edges).
inline std::pair<int32_t, int32_t> side_counts(const std::vector<ref::Geometry>& geometries, ref::Kind kind) {
  const int first = kind == ref::Kind::EE ? 2 : 0;
  const int second = kind == ref::Kind::VT ? 1 : kind == ref::Kind::VV ? 0 : 2;
  auto total = [&](int element) {
    const auto [start, count] = ref::geometry_range(geometries, geometries.size() - 1, element);
    return int32_t(start + count);
  };
  return {total(first), total(second)};
}

// One query of a geometry scene, its output checked (scene_runs.h's checked_pairs: range,
// duplicates, canonical order, digest, the ways of passing buffers by `variant`), sorted.
inline Pairs geometry_pairs(minkq_scene* scene, const std::vector<ref::Geometry>& geometries, ref::Kind kind,
                            minkq_mode mode, float r, uint32_t flags, uint32_t variant, Report& report,
                            const std::string& what, minkq_result* result) {
  auto call = [&](uint32_t f, int32_t* out, size_t capacity, minkq_query_info* info, minkq_result* res) {
    const minkq_query_desc desc{query_kind(kind), mode, f, r};
    return res ? minkq_scene_query_result(scene, &desc, res)
               : minkq_scene_query(scene, &desc, out, capacity, MINKQ_MEMORY_HOST, info);
  };
  const auto [queries, prims] = side_counts(geometries, kind);
  return checked_pairs(call, flags, variant, queries, prims, false, report, what, result);
}

inline std::string query_name(ref::Kind kind, minkq_mode mode, uint32_t flags) {
  const char* modes[] = {"box", "sphere", "capsule_ray", "capsule_exact"};
  return std::string(kind_name(kind)) + " " + modes[int(mode) & 3] + (flags & MINKQ_QUERY_LEAF_EXACT ? "+leaf_exact" : "");
}

// The sets of one kind: plain[mode] and leaf[mode] (LEAF_EXACT), modes_of(kind) filled.
struct KindSets {
  Pairs plain[4], leaf[4];
};

// The pairs of every mode of `kind`, with and without LEAF_EXACT, against the oracle: no
// contact lost, no pair the rules exclude (worlds, groups, masks, SELF, incident, each pair
// once), finer modes inside coarser ones (points: capsule_ray is box, capsule_exact sphere),
// leaf-exact pairs inside their mode's, and leaf-exact extras within their reach
// r + t(a) + t(b) plus the slack of minkq_scene_query. For double input that reach is grown by
// 2 rho on the rounded positions, which lie up to rho from the double ones at each end of the
// pair: within 4 rho more on the double input that the oracle measures. Returns the oracle's
// contacts; `sets` (when given) receives the sets.
inline Pairs check_geometry_kind(minkq_scene* scene, const std::vector<ref::Geometry>& geometries, ref::Kind kind,
                                 float r, uint32_t variant, Report& report, const std::string& what,
                                 KindSets* sets = nullptr) {
  const Pairs truth = ref::geometry_contacts(geometries, kind, double(r));
  const double rho4 = 4 * rounding_rho(geometries);
  const cxx::Result result = [] {
    minkq_result* raw = nullptr;
    minkq_result_create(&raw);
    return cxx::Result(raw);
  }();
  KindSets own;
  KindSets& s = sets ? *sets : own;
  int index = 0;
  for (uint32_t flags : {0u, uint32_t(MINKQ_QUERY_LEAF_EXACT)})
    for (minkq_mode mode : modes_of(kind)) {
      const std::string at = what + " " + query_name(kind, mode, flags) + " r=" + fmt_g(r);
      Pairs got = geometry_pairs(scene, geometries, kind, mode, r, flags, (variant >> (2 * index)) ^ uint32_t(index * 5),
                                 report, at, result.get());
      ++index;
      if (inject_fault() && kind == ref::Kind::VT && flags && !truth.empty()) {
        const auto it = std::find(got.begin(), got.end(), truth.front());  // the harness's self-test
        if (it != got.end()) got.erase(it);
      }
      expect_subset(report, truth, got, at + ": oracle contacts lost");
      const Pairs excluded = ref::not_allowed(geometries, kind, got);
      if (!excluded.empty()) report.fail(at + ": pairs the rules exclude: " + show(excluded));
      if (!flags) {
        s.plain[mode] = std::move(got);
        continue;
      }
      expect_subset(report, got, s.plain[mode], at + ": leaf-exact pairs outside the mode's");
      const Pairs extras = minus(got, truth);
      const auto measured = ref::measure_pairs(geometries, kind, extras, double(r));
      for (size_t i = 0; i < extras.size(); ++i)
        if (!(double(measured[i].distance) <=
              (measured[i].reach + rho4) * (1 + 0x1p-20) + 0x1p-19 * measured[i].scale))
          report.fail(at + ": leaf-exact extra " + show({extras[i]}) + " at distance " +
                      fmt_g(double(measured[i].distance)) + " beyond reach " + fmt_g(measured[i].reach));
      s.leaf[mode] = std::move(got);
    }
  const std::string at = what + " " + kind_name(kind) + " r=" + fmt_g(r);
  expect_subset(report, s.plain[MINKQ_MODE_CAPSULE_EXACT], s.plain[MINKQ_MODE_CAPSULE_RAY], at + ": capsule_exact in capsule_ray");
  expect_subset(report, s.plain[MINKQ_MODE_CAPSULE_RAY], s.plain[MINKQ_MODE_BOX], at + ": capsule_ray in box");
  if (kind != ref::Kind::EE) {
    expect_subset(report, s.plain[MINKQ_MODE_SPHERE], s.plain[MINKQ_MODE_BOX], at + ": sphere in box");
    expect_equal(report, s.plain[MINKQ_MODE_CAPSULE_RAY], s.plain[MINKQ_MODE_BOX], at + ": points: capsule_ray is box");
    expect_equal(report, s.plain[MINKQ_MODE_CAPSULE_EXACT], s.plain[MINKQ_MODE_SPHERE],
                 at + ": points: capsule_exact is sphere");
  }
  return truth;
}

// check_geometry_kind for every kind the scene answers; `sets` (when given) receives each
// kind's sets, indexed by ref::Kind. Returns the number of the oracle's contacts.
inline size_t check_geometry_scene(minkq_scene* scene, const std::vector<ref::Geometry>& geometries, float r,
                                 uint32_t variant, Report& report, const std::string& what,
                                 KindSets (*sets)[4] = nullptr) {
  const uint32_t kinds = scene_kinds(geometries);
  size_t contacts = 0;
  for (int k = 0; k < 4; ++k)
    if (kinds & kKindBits[k])
      contacts += check_geometry_kind(scene, geometries, kAllQueryKinds[k], r, variant + uint32_t(k), report, what,
                                      sets ? &(*sets)[k] : nullptr)
                      .size();
  return contacts;
}

}  // namespace minkq::fuzz
