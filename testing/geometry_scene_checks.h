// A scene of many geometries as the differential fuzzer decodes it (fuzz/geometry_decoder.h)
// and every check of it: each kind and mode against the oracle (geometry_checks.h), the
// geometry ranges, one step that moves it (whole scene or one geometry; refit, rebuild or swept;
// refusals of static geometries and of mixed precision), and its first geometry alone as a
// minkq_scene_create scene, which must give the same pairs.
#pragma once

#include <string>
#include <vector>

#include "geometry_checks.h"

namespace minkq::fuzz {

// The step a geometry scene takes after its first checks.
enum class GeometryStep { kNone, kRefit, kRebuild, kSwept, kSweptRebuild };

struct GeometryScene {
  std::vector<ref::Geometry> geometries;
  float r = 0.0f;
  uint32_t variant = 0;  // how the pair buffers are passed (scene_runs.h's checked_pairs)
  GeometryStep step = GeometryStep::kNone;
  int32_t moving = -1;  // the geometry the step moves, or -1: every geometry that is not static
  // The positions after the step (the end of a swept step), one per geometry, of each
  // geometry's precision (xyz64 for FLOAT64, else xyz); only moving ones differ.
  std::vector<ref::Mesh> moved;
  std::string label;
};

struct GeometryStats {
  uint64_t scenes = 0, steps = 0, swept = 0, refused = 0, one_mesh = 0, contacts = 0, sampled = 0;
};

inline std::string describe(const GeometryScene& s) {
  static const char* steps[] = {"kNone", "kRefit", "kRebuild", "kSwept", "kSweptRebuild"};
  std::string out = "// " + s.label + "\nfuzz::GeometryScene s;\ns.r = " + hex_float(s.r) + ";\ns.variant = " +
                    std::to_string(s.variant) + ";\ns.step = fuzz::GeometryStep::" + steps[int(s.step)] +
                    ";\ns.moving = " + std::to_string(s.moving) + ";\n";
  auto mesh = [&](const std::string& name, const ref::Mesh& m) {
    out += name + ".xyz = " + float_list(m.xyz) + ";\n";
    if (!m.xyz64.empty()) out += "reference::set_float64(" + name + ", " + double_list(m.xyz64) + ");\n";
  };
  for (size_t i = 0; i < s.geometries.size(); ++i) {
    const ref::Geometry& g = s.geometries[i];
    const std::string n = "s.geometries[" + std::to_string(i) + "]";
    out += "s.geometries.emplace_back();\n";
    mesh(n + ".mesh", g.mesh);
    out += n + ".mesh.tris = " + int_list(g.mesh.tris) + ";\n" + n + ".mesh.edges = " + int_list(g.mesh.edges) +
           ";\n";
    out += n + ".kinds = " + std::to_string(g.kinds) + ", " + n + ".flags = " + std::to_string(g.flags) + ", " + n +
           ".world = " + std::to_string(g.world) + ", " + n + ".group = " + std::to_string(g.group) + "u, " + n +
           ".mask = " + std::to_string(g.mask) + "u;\n";
    if (!g.thickness.empty()) out += n + ".thickness = " + double_list(g.thickness) + ";\n";
  }
  for (size_t i = 0; i < s.moved.size(); ++i) {
    const ref::Mesh& m = s.geometries[i].mesh;
    if (s.moved[i].xyz == m.xyz && s.moved[i].xyz64 == m.xyz64) {  // unmoved: the geometry's own
      out += "s.moved.push_back(s.geometries[" + std::to_string(i) + "].mesh);\n";
      continue;
    }
    out += "s.moved.emplace_back();\n";
    mesh("s.moved[" + std::to_string(i) + "]", s.moved[i]);
  }
  return out;
}

// The geometries with the positions of `moved` (topology, thickness and rules kept).
inline std::vector<ref::Geometry> with_positions(std::vector<ref::Geometry> geometries,
                                                 const std::vector<ref::Mesh>& moved) {
  for (size_t i = 0; i < geometries.size(); ++i) {
    geometries[i].mesh.xyz = moved[i].xyz;
    geometries[i].mesh.xyz64 = moved[i].xyz64;
  }
  return geometries;
}

// Whether the step moves geometry i.
inline bool step_moves(const GeometryScene& s, size_t i) {
  return s.moving < 0 ? !(s.geometries[i].flags & MINKQ_GEOMETRY_STATIC) : size_t(s.moving) == i;
}

// The vertex buffer of a step from geometries `at`: geometry `moving`'s, or every moving
// geometry's one after another (doubles when the first is FLOAT64); `storage` holds them.
// Sets `mixed` when the moving geometries are of both precisions (the whole-scene calls refuse).
inline minkq_buffer step_buffer(const GeometryScene& s, const std::vector<ref::Geometry>& at,
                                std::vector<float>& floats, std::vector<double>& doubles, bool& mixed) {
  mixed = false;
  if (s.moving >= 0) return geometry_vertices(at[size_t(s.moving)]);
  int precision = -1;
  for (size_t i = 0; i < at.size(); ++i) {
    if (!step_moves(s, i)) continue;
    const int p = (at[i].flags & MINKQ_GEOMETRY_FLOAT64) ? 1 : 0;
    if (precision >= 0 && p != precision) mixed = true;
    if (precision < 0) precision = p;
    const ref::Mesh& m = at[i].mesh;
    if (p) doubles.insert(doubles.end(), m.xyz64.begin(), m.xyz64.end());
    else doubles.insert(doubles.end(), m.xyz.begin(), m.xyz.end());
    floats.insert(floats.end(), m.xyz.begin(), m.xyz.end());
  }
  if (precision == 1) return cxx::host_buffer(doubles.data(), doubles.size() / 3);
  return cxx::host_buffer(floats.data(), floats.size() / 3);
}

// The oracle's contacts at times k/16 of a swept step (k = 0..16, positions between in double
// where they are exact; a time with an inexact position is skipped), merged.
inline Pairs sampled_contacts(const GeometryScene& s, ref::Kind kind) {
  Pairs sampled;
  for (int k = 0; k <= 16; ++k) {
    std::vector<ref::Geometry> at = s.geometries;
    bool exact = true;
    for (size_t i = 0; i < at.size() && exact; ++i) {
      if (!step_moves(s, i)) continue;
      const ref::Mesh& from = s.geometries[i].mesh;
      const std::vector<double> a = from.xyz64.empty() ? std::vector<double>(from.xyz.begin(), from.xyz.end()) : from.xyz64;
      const std::vector<double> b = s.moved[i].xyz64.empty()
                                        ? std::vector<double>(s.moved[i].xyz.begin(), s.moved[i].xyz.end())
                                        : s.moved[i].xyz64;
      std::vector<double> xyz(a.size());
      for (size_t j = 0; j < xyz.size(); ++j) {
        xyz[j] = a[j] + (k / 16.0) * (b[j] - a[j]);
        const long double e = (long double)a[j] + (long double)(k / 16.0) * ((long double)b[j] - (long double)a[j]);
        exact = exact && (long double)xyz[j] == e && std::isfinite(xyz[j]);
      }
      ref::set_float64(at[i].mesh, std::move(xyz));
    }
    if (!exact) continue;
    const Pairs found = ref::geometry_contacts(at, kind, double(s.r));
    Pairs merged;
    std::set_union(sampled.begin(), sampled.end(), found.begin(), found.end(), std::back_inserter(merged));
    sampled = std::move(merged);
  }
  return sampled;
}

// The swept step's checks: each kind's swept modes (EE: box) hold the sampled contacts and no
// pair the rules exclude; LEAF_EXACT and the EE segment modes answer UNSUPPORTED; a step of
// no motion gives the static sets (sphere for capsule_exact, box for capsule_ray).
inline void check_swept_geometry_step(minkq_scene* scene, const GeometryScene& s, const KindSets (&before)[4],
                                      bool still, Report& report, GeometryStats& stats) {
  if (minkq_scene_is_swept(scene) != 1) report.fail("swept step: minkq_scene_is_swept is not 1");
  const uint32_t kinds = scene_kinds(s.geometries);
  for (int k = 0; k < 4; ++k) {
    if (!(kinds & kKindBits[k])) continue;
    const ref::Kind kind = kAllQueryKinds[k];
    const Pairs sampled = still ? Pairs{} : sampled_contacts(s, kind);
    stats.sampled += sampled.size();
    for (minkq_mode mode : modes_of(kind)) {
      const std::string at = "swept " + query_name(kind, mode, 0);
      const minkq_query_desc desc{query_kind(kind), mode, MINKQ_QUERY_LEAF_EXACT, s.r};
      minkq_query_info info{};
      if (kind == ref::Kind::EE && mode != MINKQ_MODE_BOX) {
        const minkq_query_desc plain{query_kind(kind), mode, 0, s.r};
        if (minkq_scene_query(scene, &plain, nullptr, 0, MINKQ_MEMORY_HOST, &info) != MINKQ_ERROR_UNSUPPORTED)
          report.fail(at + ": not UNSUPPORTED");
        continue;
      }
      if (minkq_scene_query(scene, &desc, nullptr, 0, MINKQ_MEMORY_HOST, &info) != MINKQ_ERROR_UNSUPPORTED)
        report.fail(at + "+leaf_exact: not UNSUPPORTED");
      const Pairs got = geometry_pairs(scene, s.geometries, kind, mode, s.r, 0, s.variant + uint32_t(k), report, at,
                                       nullptr);
      expect_subset(report, sampled, got, at + ": oracle contacts at sampled times lost");
      const Pairs excluded = ref::not_allowed(s.geometries, kind, got);
      if (!excluded.empty()) report.fail(at + ": pairs the rules exclude: " + show(excluded));
      if (still) {
        const minkq_mode same = kind == ref::Kind::EE                ? mode
                                : mode == MINKQ_MODE_CAPSULE_EXACT ? MINKQ_MODE_SPHERE
                                : mode == MINKQ_MODE_CAPSULE_RAY   ? MINKQ_MODE_BOX
                                                                   : mode;
        expect_equal(report, got, before[k].plain[same], at + ": no motion vs the static sets");
      }
    }
  }
}

// Runs the step's call on `scene` from positions `from` to `to` (to only, for a plain step).
inline minkq_status run_geometry_step(minkq_scene* scene, const GeometryScene& s, const std::vector<ref::Geometry>& from,
                                      const std::vector<ref::Geometry>& to, bool& mixed) {
  std::vector<float> f0, f1;
  std::vector<double> d0, d1;
  const minkq_buffer x1 = step_buffer(s, to, f1, d1, mixed);
  const bool swept = s.step == GeometryStep::kSwept || s.step == GeometryStep::kSweptRebuild;
  const minkq_buffer x0 = swept ? step_buffer(s, from, f0, d0, mixed) : x1;
  const uint32_t g = uint32_t(s.moving);
  switch (s.step) {
    case GeometryStep::kNone: return MINKQ_SUCCESS;
    case GeometryStep::kRefit:
      return s.moving < 0 ? minkq_scene_refit(scene, x1) : minkq_scene_geometry_refit(scene, g, x1);
    case GeometryStep::kRebuild:
      return s.moving < 0 ? minkq_scene_rebuild(scene, x1) : minkq_scene_geometry_rebuild(scene, g, x1);
    case GeometryStep::kSwept:
      return s.moving < 0 ? minkq_scene_refit_swept(scene, x0, x1) : minkq_scene_geometry_refit_swept(scene, g, x0, x1);
    case GeometryStep::kSweptRebuild:
      return s.moving < 0 ? minkq_scene_rebuild_swept(scene, x0, x1)
                          : minkq_scene_geometry_rebuild_swept(scene, g, x0, x1);
  }
  return MINKQ_SUCCESS;
}

// The first geometry alone (thickness dropped, SELF on), through minkq_scene_create_geometries
// and through minkq_scene_create: the same pairs in every mode, with and without LEAF_EXACT.
inline void check_one_mesh_equality(minkq_device* device, const GeometryScene& s, Report& report, GeometryStats& stats) {
  ref::Geometry g = s.geometries[0];
  g.thickness.clear();
  g.flags |= MINKQ_GEOMETRY_SELF;
  g.world = 0, g.group = 1, g.mask = ~0u;
  const std::vector<ref::Geometry> one = {g};
  minkq_scene_desc desc{};
  desc.flags = g.kinds | (g.flags & MINKQ_GEOMETRY_DROP_INCIDENT ? uint32_t(MINKQ_SCENE_DROP_INCIDENT) : 0u) |
               (g.flags & MINKQ_GEOMETRY_FLOAT64 ? uint32_t(MINKQ_SCENE_FLOAT64) : 0u);
  desc.vertices = geometry_vertices(g);
  desc.triangles = cxx::host_buffer(g.mesh.tris.data(), g.mesh.tris.size() / 3);
  desc.edges = cxx::host_buffer(g.mesh.edges.data(), g.mesh.edges.size() / 2);
  minkq_scene *a = nullptr, *b = nullptr;
  const minkq_status sa = GeometryDescriptions(one).create(device, &a);
  const cxx::Scene geometry_scene(a);
  const minkq_status sb = minkq_scene_create(device, &desc, &b);
  const cxx::Scene mesh_scene(b);
  if (sa != MINKQ_SUCCESS || sb != MINKQ_SUCCESS) {
    report.fail("one geometry vs one mesh: creation " + std::string(minkq_status_name(sa)) + " / " +
                minkq_status_name(sb) + " (" + minkq_last_error_message() + ")");
    return;
  }
  stats.one_mesh++;
  for (int k = 0; k < 4; ++k) {
    if (!(g.kinds & kKindBits[k])) continue;
    for (uint32_t flags : {0u, uint32_t(MINKQ_QUERY_LEAF_EXACT)})
      for (minkq_mode mode : modes_of(kAllQueryKinds[k])) {
        const std::string at = "one geometry vs one mesh " + query_name(kAllQueryKinds[k], mode, flags);
        const Pairs x = geometry_pairs(a, one, kAllQueryKinds[k], mode, s.r, flags, 3, report, at, nullptr);
        const Pairs y = geometry_pairs(b, one, kAllQueryKinds[k], mode, s.r, flags, 3, report, at, nullptr);
        expect_equal(report, x, y, at);
      }
  }
}

// Every check of a geometry scene on one device.
inline void check_geometry_fuzz_scene(minkq_device* device, const GeometryScene& s, Report& report,
                                      GeometryStats& stats) {
  minkq_scene* raw = nullptr;
  const minkq_status created = GeometryDescriptions(s.geometries).create(device, &raw);
  const cxx::Scene scene(raw);
  if (created != MINKQ_SUCCESS) {
    report.fail("minkq_scene_create_geometries: " + status_text(created));
    return;
  }
  stats.scenes++;
  if (minkq_scene_geometry_count(raw) != s.geometries.size()) report.fail("minkq_scene_geometry_count");
  for (size_t i = 0; i < s.geometries.size(); ++i)
    for (int e = 0; e < 3; ++e) {
      size_t first = 0, count = 0;
      const minkq_status st = minkq_scene_geometry_range(raw, uint32_t(i), minkq_element(e), &first, &count);
      if (st != MINKQ_SUCCESS || std::make_pair(first, count) != ref::geometry_range(s.geometries, i, e))
        report.fail("minkq_scene_geometry_range(" + std::to_string(i) + ", " + std::to_string(e) + ") differs from the oracle's");
    }
  KindSets before[4];
  stats.contacts += check_geometry_scene(raw, s.geometries, s.r, s.variant, report, "static", &before);
  check_one_mesh_equality(device, s, report, stats);
  if (s.step == GeometryStep::kNone || !report.ok()) return;

  const std::vector<ref::Geometry> after = with_positions(s.geometries, s.moved);
  bool mixed = false;
  const minkq_status st = run_geometry_step(raw, s, s.geometries, after, mixed);
  bool any_moving = false;
  for (size_t i = 0; i < s.geometries.size(); ++i) any_moving = any_moving || step_moves(s, i);
  const bool refused = (s.moving >= 0 && (s.geometries[size_t(s.moving)].flags & MINKQ_GEOMETRY_STATIC)) || mixed;
  if (refused || !any_moving) {
    if (refused && st != MINKQ_ERROR_INVALID_ARGUMENT)
      report.fail(std::string("step on a static geometry or of mixed precision: ") + minkq_status_name(st) +
                  ", not INVALID_ARGUMENT");
    if (st == MINKQ_SUCCESS) return;  // no moving geometry: nothing to compare
    stats.refused++;
    KindSets again[4];  // the scene keeps its positions and trees
    check_geometry_scene(raw, s.geometries, s.r, s.variant, report, "after a refused step", &again);
    for (int k = 0; k < 4; ++k)
      for (int m = 0; m < 4; ++m) expect_equal(report, again[k].plain[m], before[k].plain[m], "after a refused step");
    return;
  }
  if (st != MINKQ_SUCCESS) {
    report.fail("step: " + status_text(st));
    return;
  }
  stats.steps++;
  if (s.step == GeometryStep::kRefit || s.step == GeometryStep::kRebuild) {
    if (minkq_scene_is_swept(raw) != 0) report.fail("plain step: minkq_scene_is_swept is not 0");
    stats.contacts += check_geometry_scene(raw, after, s.r, s.variant >> 3, report, "after the step");
    return;
  }
  stats.swept++;
  bool still = true;
  for (size_t i = 0; i < after.size(); ++i)
    still = still && after[i].mesh.xyz == s.geometries[i].mesh.xyz && after[i].mesh.xyz64 == s.geometries[i].mesh.xyz64;
  check_swept_geometry_step(raw, s, before, still, report, stats);
  // A plain refit back to the start ends the swept step: the static sets again.
  GeometryScene back = s;
  back.step = GeometryStep::kRefit;
  const minkq_status sb = run_geometry_step(raw, back, s.geometries, s.geometries, mixed);
  if (sb != MINKQ_SUCCESS) {
    report.fail("refit back after the swept step: " + status_text(sb));
    return;
  }
  if (minkq_scene_is_swept(raw) != 0) report.fail("refit back: minkq_scene_is_swept is not 0");
  KindSets again[4];
  check_geometry_scene(raw, s.geometries, s.r, s.variant >> 5, report, "refit back", &again);
  for (int k = 0; k < 4; ++k)
    for (int m = 0; m < 4; ++m) expect_equal(report, again[k].plain[m], before[k].plain[m], "refit back vs the first build");
}

}  // namespace minkq::fuzz
