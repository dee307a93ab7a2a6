// The checks of a swept step (minkq_scene_refit_swept / minkq_scene_rebuild_swept, capi/minkq.h
// "Swept positions") on a mesh scene, shared by the differential fuzzer and the regression tests:
//   - every mode's set (VT box, sphere, capsule_ray, capsule_exact; EE box) equals its definition
//     (the mode's segment shape of the vertex's path against the triangles' swept boxes; the
//     edges' swept boxes), by brute force and by the independent traversal; box mode also equals
//     the swept boxes' per-axis gap written out plainly (PlainSweptBoxes);
//   - the chain: VT capsule_exact <= capsule_ray <= box, sphere == capsule_exact;
//   - zero false negatives against the static oracle at sampled times (sampled_contacts);
//   - what swept scenes refuse answers MINKQ_ERROR_UNSUPPORTED;
//   - float64 steps: rho the larger of both position sets', the radius widened by 2 rho.
// The comparison of a step of zero motion with the static sets, and of every further device with
// the CPU, is check_mesh_scene's (scene_checks.h).
#pragma once

#include <algorithm>
#include <cmath>
#include <iterator>
#include <string>
#include <vector>

#include "scene_definitions.h"
#include "scene_oracle.h"
#include "scene_runs.h"
#include "scene_types.h"

namespace minkq::fuzz {

// Times at which the static oracle samples a swept step: t = k / kSweptSamples, k = 0..16
// (dyadic, so float positions between are mostly exact in double).
constexpr int kSweptSamples = 16;

// Moves `scene` through the step x0 -> x1 (rebuilding its trees for it, or refitting them); false
// (and reported) where the call fails.
inline bool sweep(minkq_scene* scene, const Positions& x0, const Positions& x1, bool rebuild, Report& report,
                  const std::string& tag) {
  const minkq_status status = rebuild ? minkq_scene_rebuild_swept(scene, x0.buffer(), x1.buffer())
                                      : minkq_scene_refit_swept(scene, x0.buffer(), x1.buffer());
  if (status != MINKQ_SUCCESS) {
    report.fail(tag + (rebuild ? " minkq_scene_rebuild_swept: " : " minkq_scene_refit_swept: ") + status_text(status));
    return false;
  }
  if (minkq_scene_is_swept(scene) != 1) report.fail(tag + " minkq_scene_is_swept is not 1 after a swept step");
  return true;
}

inline void compare_swept_sets(Report& report, const SweptSets& got, const SweptSets& want, const std::string& tag,
                               Stats* stats) {
  for (int mode = 0; mode < 4; ++mode) {
    expect_equal(report, got.vt[mode], want.vt[mode], tag + " VT " + mode_name(mode));
    if (stats) stats->pairs += got.vt[mode].size();
  }
  expect_equal(report, got.ee_box, want.ee_box, tag + " EE box");
  if (stats) stats->pairs += got.ee_box.size();
}

// Every check of the swept step x0 -> x1 on `scene` (a scene of the same mesh, at any
// positions); returns the step's sets (empty where the step failed).
inline SweptSets check_swept_step(minkq_scene* scene, const MeshScene& s, const Positions& x0, const Positions& x1,
                                  const std::vector<int32_t>& edges, IndependentSets* independent, bool rebuild,
                                  Report& report, Stats& stats, const std::string& tag, minkq_result* result) {
  if (!sweep(scene, x0, x1, rebuild, report, tag)) return {};
  MeshGeometry g(x0.xyz, s.tris, edges);
  g.set_end(x1.xyz);
  const uint32_t filters = s.drop_incident ? kDropIncident : 0u;
  // The radius the scene queries with: r, or for float64 input r + 2 rho over both positions.
  const float radius = scene_radius(s.r, std::max(rounding_rho(x0), rounding_rho(x1)));
  if (x0.float64()) {
    Positions both = x0;
    both.xyz.insert(both.xyz.end(), x1.xyz.begin(), x1.xyz.end());
    both.xyz64.insert(both.xyz64.end(), x1.xyz64.begin(), x1.xyz64.end());
    check_widened_radius(report, s.r, radius, both, tag + " swept float64");
  }
  const SweptSets got = minkq_swept_sets(scene, g, s.r, s.variant, report, stats, tag + " swept", result);
  check_swept_refusals(scene, s.r, report, tag);

  // The traversal finds exactly the definition (brute force, the core's shapes), the plain
  // box-gap definition, and the independent traversal's sets.
  compare_swept_sets(report, got, swept_definition_sets(g, radius, filters), tag + " swept minkq vs definition", &stats);
  const auto [vt_box, ee_box] = plain_swept_box_sets(x0.xyz, x1.xyz, s.tris, edges, radius, s.drop_incident);
  expect_equal(report, got.vt[MINKQ_MODE_BOX], vt_box, tag + " swept VT box vs the swept boxes' gaps");
  expect_equal(report, got.ee_box, ee_box, tag + " swept EE box vs the swept boxes' gaps");
  if (independent && independent->accepts(x0.xyz, radius) && independent->accepts(x1.xyz, radius)) {
    compare_swept_sets(report, got, independent->swept_sets(g, radius, filters, true), tag + " swept minkq vs Embree",
                       nullptr);
    stats.independent += 5;
  }
  // The chain.
  expect_subset(report, got.vt[MINKQ_MODE_CAPSULE_EXACT], got.vt[MINKQ_MODE_CAPSULE_RAY],
                tag + " swept VT capsule_exact <= capsule_ray");
  expect_subset(report, got.vt[MINKQ_MODE_CAPSULE_RAY], got.vt[MINKQ_MODE_BOX], tag + " swept VT capsule_ray <= box");
  expect_equal(report, got.vt[MINKQ_MODE_SPHERE], got.vt[MINKQ_MODE_CAPSULE_EXACT],
               tag + " swept VT sphere == capsule_exact");

  // Zero false negatives: every pair the static oracle finds at a sampled time (within r of the
  // double input, the float64 one or the floats' exact values) is in every mode's set.
  const SampledContacts truth = sampled_contacts(x0, x1, s.tris, edges, s.r, s.drop_incident, kSweptSamples);
  stats.sampled_contacts += truth.vt.size() + truth.ee.size();
  for (int mode = 0; mode < 4; ++mode)
    expect_subset(report, truth.vt, got.vt[mode], tag + " swept VT false negatives (sampled times) in " + mode_name(mode));
  expect_subset(report, truth.ee, got.ee_box, tag + " swept EE false negatives (sampled times) in box");
  return got;
}

// A step of zero motion from the positions the static sets were taken at gives the static
// sets exactly (minkq.h): VT box and capsule_ray the static box mode's (capsule_ray is the box
// test for points), sphere and capsule_exact the static sphere mode's (a still vertex takes the
// point tests; fuzz/RESULTS.md, bug 7), EE box the static EE box.
inline void compare_still_step(Report& report, const SweptSets& swept, const MeshSets& fixed, const std::string& tag) {
  expect_equal(report, swept.vt[MINKQ_MODE_BOX], fixed.vt[MINKQ_MODE_BOX][0], tag + " still step VT box vs static");
  expect_equal(report, swept.vt[MINKQ_MODE_CAPSULE_RAY], fixed.vt[MINKQ_MODE_BOX][0],
               tag + " still step VT capsule_ray vs static box");
  expect_equal(report, swept.vt[MINKQ_MODE_SPHERE], fixed.vt[MINKQ_MODE_SPHERE][0],
               tag + " still step VT sphere vs static sphere");
  expect_equal(report, swept.vt[MINKQ_MODE_CAPSULE_EXACT], fixed.vt[MINKQ_MODE_SPHERE][0],
               tag + " still step VT capsule_exact vs static sphere");
  expect_equal(report, swept.ee_box, fixed.ee[MINKQ_MODE_BOX][0], tag + " still step EE box vs static");
}

}  // namespace minkq::fuzz
