// The checks the differential fuzzer runs on one decoded scene, shared with the regression
// tests (tests/test_fuzz_regressions.cpp): every mode through the C API, against
//   - the mode's definition applied to every primitive (brute force, minkq's own shape tests),
//   - an independent traversal computing the same definition (the Embree reference, fuzz only),
//   - the long-double contact oracle of oracle/ (zero false negatives, leaf-exact
//     extras within r + 2^-19 * S),
//   - the containment chain, the pair-buffer contract (canonical order, digest, no duplicates,
//     nothing written past the count) and refit == fresh build,
//   - float64 input: the sets of the rounded positions at r + 2 rho, the oracle on the doubles,
//   - a swept step (swept_checks.h), and static sets again after it,
//   - every further device (CUDA, where one exists) giving the same sets.
// Failures are collected in a Report, never thrown, so a caller can print the scene first.
//
// The parts: scene_types.h (scenes, reports, printing, set comparisons), scene_definitions.h
// (each mode's definition by brute force), scene_runs.h (the C API runs and the pair-buffer
// contract), scene_oracle.h (the oracle's bounds and its sampled swept contacts),
// swept_checks.h (a swept step's checks); this file holds the rest of the checks.
#pragma once

#include <algorithm>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "scene_definitions.h"
#include "scene_oracle.h"
#include "scene_runs.h"
#include "scene_types.h"
#include "swept_checks.h"

namespace minkq::fuzz {

// ---- The checks ---------------------------------------------------------------------------------

inline void check_chain(Report& report, const MeshSets& m, const std::string& tag) {
  // VT: true <= leaf_exact <= sphere <= box; capsule modes on points are box and sphere.
  expect_subset(report, m.vt[MINKQ_MODE_SPHERE][1], m.vt[MINKQ_MODE_SPHERE][0], tag + " VT leaf_exact <= sphere");
  expect_subset(report, m.vt[MINKQ_MODE_SPHERE][0], m.vt[MINKQ_MODE_BOX][0], tag + " VT sphere <= box");
  expect_subset(report, m.vt[MINKQ_MODE_BOX][1], m.vt[MINKQ_MODE_BOX][0], tag + " VT box+leaf <= box");
  expect_subset(report, m.vt[MINKQ_MODE_SPHERE][1], m.vt[MINKQ_MODE_BOX][1], tag + " VT sphere+leaf <= box+leaf");
  for (int leaf = 0; leaf < 2; ++leaf) {
    expect_equal(report, m.vt[MINKQ_MODE_CAPSULE_RAY][leaf], m.vt[MINKQ_MODE_BOX][leaf], tag + " VT capsule_ray == box");
    expect_equal(report, m.vt[MINKQ_MODE_CAPSULE_EXACT][leaf], m.vt[MINKQ_MODE_SPHERE][leaf],
                 tag + " VT capsule_exact == sphere");
  }
  // EE: true <= leaf_exact <= capsule_exact <= capsule_ray <= box.
  expect_subset(report, m.ee[MINKQ_MODE_CAPSULE_EXACT][1], m.ee[MINKQ_MODE_CAPSULE_EXACT][0],
                tag + " EE leaf_exact <= capsule_exact");
  expect_subset(report, m.ee[MINKQ_MODE_CAPSULE_EXACT][0], m.ee[MINKQ_MODE_CAPSULE_RAY][0],
                tag + " EE capsule_exact <= capsule_ray");
  expect_subset(report, m.ee[MINKQ_MODE_CAPSULE_RAY][0], m.ee[MINKQ_MODE_BOX][0], tag + " EE capsule_ray <= box");
  expect_subset(report, m.ee[MINKQ_MODE_CAPSULE_EXACT][1], m.ee[MINKQ_MODE_CAPSULE_RAY][1],
                tag + " EE exact+leaf <= ray+leaf");
  expect_subset(report, m.ee[MINKQ_MODE_CAPSULE_RAY][1], m.ee[MINKQ_MODE_BOX][1], tag + " EE ray+leaf <= box+leaf");
  for (int mode : {0, 2, 3})
    expect_subset(report, m.ee[mode][1], m.ee[mode][0], tag + " EE " + mode_name(mode) + "+leaf <= " + mode_name(mode));
}

inline void compare_sets(Report& report, const MeshSets& got, const MeshSets& want, const std::string& tag,
                         Stats* stats) {
  for (int mode = 0; mode < 4; ++mode)
    for (int leaf = 0; leaf < 2; ++leaf) {
      const std::string suffix = std::string(mode_name(mode)) + (leaf ? "+leaf_exact" : "");
      expect_equal(report, got.vt[mode][leaf], want.vt[mode][leaf], tag + " VT " + suffix);
      if (ee_mode(mode)) expect_equal(report, got.ee[mode][leaf], want.ee[mode][leaf], tag + " EE " + suffix);
      if (stats) stats->pairs += got.vt[mode][leaf].size() + got.ee[mode][leaf].size();
    }
}

// Every check of one set of positions of a mesh scene whose minkq handle is `scene`. For float64
// input the sets are those of the rounded positions at the widened radius (r + 2 rho), the
// oracle's contacts those of the doubles at r, and leaf-exact extras lie within the widened
// radius plus the float slack on the rounded positions.
inline MeshSets check_mesh_positions(minkq_scene* scene, const MeshScene& s, const Positions& x,
                                     const std::vector<int32_t>& edges, IndependentSets* independent, bool moved,
                                     Report& report, Stats& stats, const std::string& tag, minkq_result* result) {
  const std::vector<float>& xyz = x.xyz;
  const MeshGeometry g(xyz, s.tris, edges);
  const uint32_t filters = s.drop_incident ? kDropIncident : 0u;
  const float radius = scene_radius(s.r, rounding_rho(x));  // s.r for float input
  if (x.float64()) check_widened_radius(report, s.r, radius, x, tag + " float64");
  MeshSets got = minkq_mesh_sets(scene, g, s.r, s.variant, report, stats, tag, result);
  if (inject_fault() && !got.vt[MINKQ_MODE_SPHERE][1].empty()) got.vt[MINKQ_MODE_SPHERE][1].pop_back();

  // Traversal finds exactly the definition, computed by brute force...
  compare_sets(report, got, definition_sets(g, radius, filters), tag + " minkq vs definition", &stats);
  // ...and by the independent traversal.
  if (independent && independent->accepts(xyz, radius)) {
    compare_sets(report, got, independent->mesh_sets(g, radius, filters, moved), tag + " minkq vs Embree", nullptr);
    stats.independent += 14;
  }
  check_chain(report, got, tag);

  // Zero false negatives against the long-double oracle (on the double input, if any);
  // leaf-exact extras within the bound.
  reference::Mesh mesh;
  mesh.xyz = xyz;
  mesh.xyz64 = x.xyz64;
  mesh.tris = s.tris;
  mesh.edges = edges;
  // The oracle's grid-accelerated sets (its prefilter is conservative: padded double boxes),
  // checked against its all-pairs sets on one scene in eight and on every small scene.
  const Pairs vt_true = reference::vt_contacts(mesh, s.r, s.drop_incident);
  const Pairs ee_true = reference::ee_contacts(mesh, s.r, s.drop_incident);
  if ((s.variant >> 29) == 0 || g.ne() <= 24) {
    expect_equal(report, vt_true, reference::vt_contacts_brute(mesh, s.r, s.drop_incident), tag + " VT oracle grid vs brute");
    expect_equal(report, ee_true, reference::ee_contacts_brute(mesh, s.r, s.drop_incident), tag + " EE oracle grid vs brute");
  }
  stats.true_contacts += vt_true.size() + ee_true.size();
  for (int mode = 0; mode < 4; ++mode)
    for (int leaf = 0; leaf < 2; ++leaf) {
      const std::string suffix = std::string(mode_name(mode)) + (leaf ? "+leaf_exact" : "");
      expect_subset(report, vt_true, got.vt[mode][leaf], tag + " VT false negatives in " + suffix);
      if (!ee_mode(mode)) continue;
      expect_subset(report, ee_true, got.ee[mode][leaf], tag + " EE false negatives in " + suffix);
    }
  check_vt_extras(report, minus(got.vt[MINKQ_MODE_SPHERE][1], vt_true), xyz, s.tris, radius, tag + " VT");
  check_vt_extras(report, minus(got.vt[MINKQ_MODE_BOX][1], vt_true), xyz, s.tris, radius, tag + " VT box");
  check_ee_extras(report, minus(got.ee[MINKQ_MODE_CAPSULE_EXACT][1], ee_true), xyz, edges, radius, tag + " EE");
  check_ee_extras(report, minus(got.ee[MINKQ_MODE_BOX][1], ee_true), xyz, edges, radius, tag + " EE box");
  return got;
}

// The whole mesh-scene check on devices[0] (the CPU): the positions, the refit (if any), the
// swept step (if any) and back to static positions; then the same sets on every further device.
inline void check_mesh_scene(const std::vector<cxx::Device>& devices, const MeshScene& s,
                             IndependentSets* independent, Report& report, Stats& stats) {
  const uint32_t flags = MINKQ_SCENE_VT | MINKQ_SCENE_EE | (s.drop_incident ? uint32_t(MINKQ_SCENE_DROP_INCIDENT) : 0u) |
                         (s.float64() ? uint32_t(MINKQ_SCENE_FLOAT64) : 0u);
  const Positions start = s.start(), moved = s.refit(), x0 = s.step_start(), x1 = s.step_end();
  // A scene of the given positions on a device; empty (and reported) where creation fails.
  auto create = [&](const cxx::Device& device, const Positions& x) {
    minkq_scene_desc desc{};
    desc.flags = flags;
    desc.vertices = x.buffer();
    desc.triangles = {s.tris.empty() ? nullptr : s.tris.data(), 0, s.tris.size() / 3, MINKQ_MEMORY_HOST};
    desc.edges = {s.edges.empty() ? nullptr : s.edges.data(), 0, s.edges.size() / 2, MINKQ_MEMORY_HOST};
    minkq_scene* out = nullptr;
    const minkq_status status = minkq_scene_create(device.get(), &desc, &out);
    if (status != MINKQ_SUCCESS)
      report.fail(std::string("minkq_scene_create on ") + minkq_device_name(device.get()) + ": " + status_text(status));
    return cxx::Scene(out);
  };
  const cxx::Scene scene = create(devices[0], start);
  if (!scene) return;
  minkq_result* raw_result = nullptr;
  if (minkq_result_create(&raw_result) != MINKQ_SUCCESS) report.fail("minkq_result_create");
  const cxx::Result result(raw_result);

  // The edge numbering: given edges as they are, else every distinct triangle edge, sorted.
  std::vector<int32_t> edges(2 * minkq_scene_edge_count(scene.get()));
  if (minkq_scene_edges(scene.get(), edges.data(), edges.size() / 2) != MINKQ_SUCCESS) report.fail("minkq_scene_edges");
  if (edges != (s.edges.empty() ? reference::derive_edges(s.tris) : s.edges))
    report.fail("minkq_scene_edges: not the documented edge list");

  const MeshSets before =
      check_mesh_positions(scene.get(), s, start, edges, independent, false, report, stats, "", result.get());
  MeshSets after;
  const bool refit = !moved.empty();
  if (refit) {
    const minkq_status status = minkq_scene_refit(scene.get(), moved.buffer());
    if (status != MINKQ_SUCCESS) {
      report.fail("minkq_scene_refit: " + status_text(status));
    } else {
      after = check_mesh_positions(scene.get(), s, moved, edges, independent, true, report, stats, "[refit]",
                                   result.get());
      double growth = -1.0;
      if (minkq_scene_tree_growth(scene.get(), &growth) != MINKQ_SUCCESS || !(growth >= 0.0))
        report.fail("minkq_scene_tree_growth after a refit: " + std::to_string(growth));
      // A refitted tree keeps its old topology but must give the sets of a fresh build, and so
      // must a scene built at the old positions and rebuilt at the new (all are compared with
      // the definition above, so this runs on one refit in four for each).
      const uint32_t twin = (s.variant >> 27) % 4;
      const cxx::Scene fresh = twin < 2 ? create(devices[0], twin == 0 ? moved : start) : cxx::Scene();
      if (fresh) {
        const char* label = twin == 0 ? "[refit] vs fresh build" : "[refit] vs rebuild";
        if (twin == 1) {
          const minkq_status rebuilt = minkq_scene_rebuild(fresh.get(), moved.buffer());
          if (rebuilt != MINKQ_SUCCESS) report.fail("minkq_scene_rebuild: " + status_text(rebuilt));
          if (minkq_scene_tree_growth(fresh.get(), &growth) != MINKQ_SUCCESS || growth != 1.0)
            report.fail("minkq_scene_tree_growth after a rebuild: " + std::to_string(growth) + ", not 1");
        }
        Stats scratch;
        const MeshGeometry g(moved.xyz, s.tris, edges);
        compare_sets(report, after, minkq_mesh_sets(fresh.get(), g, s.r, ~s.variant, report, scratch, label, nullptr),
                     label, nullptr);
      }
      stats.refit_scenes++;
    }
  }
  // The swept step, on the scene as the refit left it (refit_swept keeps that tree's grouping;
  // rebuild_swept, on one step in two, builds afresh); a step of zero motion from the start
  // positions gives the static sets; then a plain refit to the start makes the scene static
  // again, with the static sets.
  SweptSets swept;
  const bool step = s.swept();
  const bool rebuild_step = ((s.variant >> 26) & 1) != 0;
  if (step) {
    swept = check_swept_step(scene.get(), s, x0, x1, edges, independent, rebuild_step, report, stats, "[swept]",
                             result.get());
    if (x0 == start && x1 == start) {
      compare_still_step(report, swept, before, "[swept]");
      stats.still_steps++;
    }
    const minkq_status status = minkq_scene_refit(scene.get(), start.buffer());
    if (status != MINKQ_SUCCESS) {
      report.fail("minkq_scene_refit after a swept step: " + status_text(status));
    } else {
      if (minkq_scene_is_swept(scene.get()) != 0) report.fail("minkq_scene_is_swept is not 0 after a plain refit");
      Stats scratch;
      compare_sets(report, minkq_mesh_sets(scene.get(), MeshGeometry(start.xyz, s.tris, edges), s.r, s.variant >> 1,
                                           report, scratch, "[after swept]", result.get()),
                   before, "[refit after swept] vs static", nullptr);
    }
    stats.swept_scenes++;
  }
  // Every further device gives exactly the CPU's sets (the backends are bit-identical).
  for (size_t d = 1; d < devices.size(); ++d) {
    const std::string name = minkq_device_name(devices[d].get());
    const cxx::Scene other = create(devices[d], start);
    if (!other) continue;
    Stats scratch;
    compare_sets(report, minkq_mesh_sets(other.get(), MeshGeometry(start.xyz, s.tris, edges), s.r, s.variant, report,
                                         scratch, name, nullptr),
                 before, name + " vs cpu", nullptr);
    if (refit && minkq_scene_refit(other.get(), moved.buffer()) == MINKQ_SUCCESS)
      compare_sets(report, minkq_mesh_sets(other.get(), MeshGeometry(moved.xyz, s.tris, edges), s.r, s.variant, report,
                                           scratch, name + " [refit]", nullptr),
                   after, name + " [refit] vs cpu", nullptr);
    if (step && sweep(other.get(), x0, x1, rebuild_step, report, name + " [swept]")) {
      MeshGeometry g(x0.xyz, s.tris, edges);
      g.set_end(x1.xyz);
      compare_swept_sets(report, minkq_swept_sets(other.get(), g, s.r, s.variant, report, scratch, name + " [swept]", nullptr),
                         swept, name + " [swept] vs cpu", nullptr);
    }
  }
  if (s.float64()) stats.float64_scenes++;
  stats.mesh_scenes++;
}

// User-box scenes: sets equal the definition (brute force and independent), the chain holds,
// every exact overlap is found, and sphere / capsule_exact extras stay within the node tests'
// stated bounds (predicates.h).
inline void check_box_positions(minkq_bvh* bvh, const BoxScene& s, const std::vector<float>& boxes,
                                IndependentSets* independent, bool moved, Report& report, Stats& stats,
                                const std::string& tag, BoxSets* out) {
  const BoxGeometry g(boxes, s.first, s.second);
  const BoxSets got = minkq_box_sets(bvh, s, s.variant, report, stats, tag, g.nb());
  const BoxSets want = definition_sets(g, s.shape, s.r);
  BoxSets other;
  const bool compare_independent = independent && independent->accepts(boxes, s.r) && independent->accepts(s.first, s.r) &&
                                   independent->accepts(s.second, s.r);
  if (compare_independent) {
    other = independent->box_sets(g, s.shape, s.r, moved);
    stats.independent++;
  }
  for (int mode = 0; mode < 4; ++mode) {
    if (!box_scene_mode(s.shape, mode)) continue;
    expect_equal(report, got.by_mode[mode], want.by_mode[mode], tag + " minkq vs definition " + mode_name(mode));
    if (compare_independent)
      expect_equal(report, got.by_mode[mode], other.by_mode[mode], tag + " minkq vs Embree " + mode_name(mode));
    stats.pairs += got.by_mode[mode].size();
  }
  // The chain, and the exact overlaps (long double) inside the finest set.
  const int finest = s.shape == MINKQ_SHAPE_BOX ? MINKQ_MODE_BOX
                                                : (s.shape == MINKQ_SHAPE_SPHERE ? MINKQ_MODE_SPHERE : MINKQ_MODE_CAPSULE_EXACT);
  if (s.shape == MINKQ_SHAPE_SPHERE) {
    expect_subset(report, got.by_mode[MINKQ_MODE_SPHERE], got.by_mode[MINKQ_MODE_BOX], tag + " sphere <= box");
    expect_equal(report, got.by_mode[MINKQ_MODE_CAPSULE_RAY], got.by_mode[MINKQ_MODE_BOX], tag + " capsule_ray == box");
    expect_equal(report, got.by_mode[MINKQ_MODE_CAPSULE_EXACT], got.by_mode[MINKQ_MODE_SPHERE],
                 tag + " capsule_exact == sphere");
  } else if (s.shape == MINKQ_SHAPE_CAPSULE) {
    expect_subset(report, got.by_mode[MINKQ_MODE_CAPSULE_EXACT], got.by_mode[MINKQ_MODE_CAPSULE_RAY],
                  tag + " capsule_exact <= capsule_ray");
    expect_subset(report, got.by_mode[MINKQ_MODE_CAPSULE_RAY], got.by_mode[MINKQ_MODE_BOX], tag + " capsule_ray <= box");
  }
  Pairs exact;
  const LD r = s.r;
  for (int32_t q = 0; q < g.nq(); ++q)
    for (int32_t b = 0; b < g.nb(); ++b) {
      const float* a = &s.first[3 * size_t(q)];
      const Box& box = g.boxes[b];
      bool hit;
      if (s.shape == MINKQ_SHAPE_SPHERE) {
        hit = point_box_distance_ld(a, box) <= r;
      } else if (s.shape == MINKQ_SHAPE_CAPSULE) {
        hit = segment_box_distance_ld(a, &s.second[3 * size_t(q)], box) <= r;
      } else {  // the box spanned by first and second, grown by r, against the box
        const float* c = &s.second[3 * size_t(q)];
        const float blo[3] = {box.lo.x, box.lo.y, box.lo.z}, bhi[3] = {box.hi.x, box.hi.y, box.hi.z};
        hit = true;
        for (int k = 0; k < 3; ++k)
          hit = hit && LD(std::min(a[k], c[k])) - r <= bhi[k] && blo[k] <= LD(std::max(a[k], c[k])) + r;
      }
      if (hit) exact.push_back({q, b});
    }
  stats.true_contacts += exact.size();
  expect_subset(report, exact, got.by_mode[finest], tag + std::string(" false negatives in ") + mode_name(finest));
  // Node tests accept nothing beyond their stated bounds: sphere r * (1 + 2^-17) (plus
  // underflow, < 1e-21 absolute); capsule_exact r + 2^-16 * (r + |d|_1) (2^-17 threshold plus
  // the 2^-18 distance error, each doubled for safety) plus the same underflow allowance.
  // These are rounding bounds: they hold where the tests' float squares are finite. Beyond
  // that (|x| or r >= 2^62) an overflowing square or difference makes a test accept ("unknown
  // means may overlap", predicates.h), which the containment checks above still cover.
  LD magnitude = std::fabs(LD(s.r));
  for (const std::vector<float>* list : {&boxes, &s.first, &s.second})
    for (float x : *list) magnitude = std::max(magnitude, std::fabs(LD(x)));
  if (s.shape != MINKQ_SHAPE_BOX && magnitude < std::ldexp(LD(1), 62))
    for (const auto& [q, b] : got.by_mode[finest]) {
      const float* a = &s.first[3 * size_t(q)];
      LD d, bound;
      if (s.shape == MINKQ_SHAPE_SPHERE) {
        d = point_box_distance_ld(a, g.boxes[b]);
        bound = r * (1 + std::ldexp(LD(1), -17)) + 1e-21L;
      } else {
        const float* c = &s.second[3 * size_t(q)];
        d = segment_box_distance_ld(a, c, g.boxes[b]);
        const LD length1 = std::fabs(LD(c[0]) - a[0]) + std::fabs(LD(c[1]) - a[1]) + std::fabs(LD(c[2]) - a[2]);
        bound = r + std::ldexp(LD(1), -16) * (r + length1) + 1e-21L;
      }
      if (!(d <= bound)) {
        char text[200];
        std::snprintf(text, sizeof text, " %s accepts (%d,%d) at distance %.9Lg beyond its bound %.9Lg", mode_name(finest),
                      q, b, d, bound);
        report.fail(tag + text);
        break;
      }
    }
  if (out) *out = got;
}

inline void check_box_scene(const std::vector<cxx::Device>& devices, const BoxScene& s, IndependentSets* independent,
                            Report& report, Stats& stats) {
  // A BVH of the scene's boxes on a device; empty (and reported) where creation fails.
  auto create = [&](const cxx::Device& device) {
    minkq_bvh* out = nullptr;
    const minkq_status status =
        minkq_bvh_create(device.get(), {s.boxes.data(), 0, s.boxes.size() / 6, MINKQ_MEMORY_HOST}, &out);
    if (status != MINKQ_SUCCESS) report.fail("minkq_bvh_create: " + status_text(status));
    return cxx::Bvh(out);
  };
  const cxx::Bvh bvh = create(devices[0]);
  if (!bvh) return;
  BoxSets before, after;
  check_box_positions(bvh.get(), s, s.boxes, independent, false, report, stats, "", &before);
  const bool refit = !s.moved.empty();
  if (refit) {
    // Every check of the moved boxes, after a refit or (one scene in four) a rebuild.
    const bool rebuild = (s.variant >> 29) % 4 == 0;
    const minkq_buffer moved{s.moved.data(), 0, s.moved.size() / 6, MINKQ_MEMORY_HOST};
    const minkq_status status = rebuild ? minkq_bvh_rebuild(bvh.get(), moved) : minkq_bvh_refit(bvh.get(), moved);
    double growth = -1.0;
    if (status != MINKQ_SUCCESS) {
      report.fail(std::string(rebuild ? "minkq_bvh_rebuild: " : "minkq_bvh_refit: ") + status_text(status));
    } else {
      check_box_positions(bvh.get(), s, s.moved, independent, true, report, stats, rebuild ? "[rebuild]" : "[refit]",
                          &after);
      if (minkq_bvh_tree_growth(bvh.get(), &growth) != MINKQ_SUCCESS || !(rebuild ? growth == 1.0 : growth >= 0.0))
        report.fail("minkq_bvh_tree_growth: " + std::to_string(growth));
    }
  }
  for (size_t d = 1; d < devices.size(); ++d) {
    const std::string name = minkq_device_name(devices[d].get());
    const cxx::Bvh other = create(devices[d]);
    if (!other) continue;
    Stats scratch;
    const BoxSets sets = minkq_box_sets(other.get(), s, s.variant, report, scratch, name, int32_t(s.boxes.size() / 6));
    for (int mode = 0; mode < 4; ++mode)
      expect_equal(report, sets.by_mode[mode], before.by_mode[mode], name + " vs cpu " + mode_name(mode));
    if (refit &&
        minkq_bvh_refit(other.get(), {s.moved.data(), 0, s.moved.size() / 6, MINKQ_MEMORY_HOST}) == MINKQ_SUCCESS) {
      const BoxSets moved = minkq_box_sets(other.get(), s, s.variant, report, scratch, name, int32_t(s.boxes.size() / 6));
      for (int mode = 0; mode < 4; ++mode)
        expect_equal(report, moved.by_mode[mode], after.by_mode[mode], name + " [refit] vs cpu " + mode_name(mode));
    }
  }
  stats.box_scenes++;
}

}  // namespace minkq::fuzz
