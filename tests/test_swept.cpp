// Swept queries (minkq_scene_refit_swept / rebuild_swept): every pair whose elements come within
// r at some t in [0, 1], vertices moving linearly from x0 to x1. Checked against
//   - the static oracle at many times t (every pair it finds at a sampled t must be reported:
//     a lower bound of the true set, exact wherever a sampled time hits the closest approach),
//   - the box mode's definition applied to every pair (each element's box over both positions,
//     per-axis gap <= r, the same float operations), which the box mode must equal exactly,
//   - the static queries at zero motion,
// at scales 1e-6 to 1e6, with one element still and the other moving far past it, and for
// float64 input; and the errors of what swept scenes refuse.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "capi_util.h"
#include "scene_definitions.h"
#include "swept_steps.h"
#include "minkq_reference.h"
#include "test_util.h"

namespace minkq {
namespace {

using reference::Mesh;
using test::Pairs;
using test::Step;
using test::sampled_contacts;

constexpr uint32_t kBothDrop = test::kSweptScene;
const minkq_mode kVtModes[] = {MINKQ_MODE_BOX, MINKQ_MODE_SPHERE, MINKQ_MODE_CAPSULE_RAY, MINKQ_MODE_CAPSULE_EXACT};

// A scene holding the step's swept positions (rebuilt for them, or refitted from x0).
test::Scene swept_scene(minkq_device* device, const Step& step, bool rebuild) {
  test::Scene scene(device, step.from, step.flags());
  const minkq_buffer x0 = test::vertices_of(step.from, step.flags()), x1 = test::vertices_of(step.to, step.flags());
  EXPECT_EQ(rebuild ? minkq_scene_rebuild_swept(scene.get(), x0, x1) : minkq_scene_refit_swept(scene.get(), x0, x1),
            MINKQ_SUCCESS)
      << minkq_last_error_message();
  EXPECT_EQ(minkq_scene_is_swept(scene.get()), 1);
  return scene;
}

// Every mode of a swept scene contains the sampled contacts; box mode equals its definition;
// the finer VT modes nest inside it.
void check_step(minkq_device* device, const Step& step, double r, const std::string& what) {
  SCOPED_TRACE(what);
  const auto [vt_truth, ee_truth] = sampled_contacts(step, r, 32);
  const float rf = float(r);
  for (bool rebuild : {false, true}) {
    test::Scene scene = swept_scene(device, step, rebuild);
    const Pairs vt_box = scene.query(MINKQ_QUERY_VT, MINKQ_MODE_BOX, rf);
    const Pairs ee_box = scene.query(MINKQ_QUERY_EE, MINKQ_MODE_BOX, rf);
    EXPECT_TRUE(test::is_subset(ee_truth, ee_box)) << "EE lost " << test::describe(test::difference(ee_truth, ee_box));
    if (!step.float64()) {  // float64 scenes widen r by 2 rho: more than the definition's r
      // The box mode's definition on every pair (elements boxed over both positions, per-axis
      // gap <= r in float), written plainly in testing/scene_definitions.h.
      const auto [vt_def, ee_def] = fuzz::plain_swept_box_sets(step.from.xyz, step.to.xyz, step.from.tris,
                                                               reference::derive_edges(step.from.tris), rf, true);
      EXPECT_EQ(vt_box, vt_def) << "VT box mode";
      EXPECT_EQ(ee_box, ee_def) << "EE box mode";
    }
    for (minkq_mode mode : kVtModes) {
      const Pairs got = scene.query(MINKQ_QUERY_VT, mode, rf);
      EXPECT_TRUE(test::is_subset(vt_truth, got)) << "VT mode " << mode << " lost "
                                                  << test::describe(test::difference(vt_truth, got));
      EXPECT_TRUE(test::is_subset(got, vt_box)) << "VT mode " << mode << " outside box mode";
    }
    EXPECT_EQ(scene.query(MINKQ_QUERY_VT, MINKQ_MODE_SPHERE, rf), scene.query(MINKQ_QUERY_VT, MINKQ_MODE_CAPSULE_EXACT, rf));
  }
}

// x1 = x0 moved by a smooth field of amplitude `amount` (in mean edge lengths).
Mesh moved(const Mesh& mesh, double amount, double phase) {
  Mesh m = mesh;
  const double h = reference::mean_edge_length(mesh);
  for (size_t v = 0; v < m.vertex_count(); ++v)
    for (int a = 0; a < 3; ++a)
      m.xyz[3 * v + a] = float(m.xyz[3 * v + a] + amount * h * std::sin(0.37 * double(v) + phase + 1.7 * a));
  return m;
}

TEST(Swept, every_contact_along_the_step_is_found_at_any_scale) {
  const test::Device cpu;
  for (double scale : {1e-6, 1.0, 1e6}) {
    Mesh sheet = reference::twisted_sheet(16, 2.0);
    reference::transform(sheet, scale, 0.5 * scale);
    for (double amount : {0.3, 3.0}) {
      const Step step{sheet, moved(sheet, amount, scale)};
      check_step(cpu.get(), step, 0.5 * reference::mean_edge_length(sheet),
                 "scale " + std::to_string(scale) + " motion " + std::to_string(amount) + " edges");
    }
  }
}

TEST(Swept, zero_motion_gives_the_static_pairs) {
  const test::Device cpu;
  const Mesh sheet = reference::twisted_sheet(20, 3.0);
  const float r = float(0.4 * reference::mean_edge_length(sheet));
  test::Scene fixed(cpu.get(), sheet, kBothDrop);
  test::Scene still = swept_scene(cpu.get(), Step{sheet, sheet}, true);
  for (minkq_mode mode : kVtModes) {
    const minkq_mode static_mode = mode == MINKQ_MODE_CAPSULE_EXACT ? MINKQ_MODE_SPHERE : mode;
    uint64_t a = 0, b = 0;
    EXPECT_EQ(still.query(MINKQ_QUERY_VT, mode, r, 0, &a), fixed.query(MINKQ_QUERY_VT, static_mode, r, 0, &b)) << mode;
    EXPECT_EQ(a, b);
  }
  EXPECT_EQ(still.query(MINKQ_QUERY_EE, MINKQ_MODE_BOX, r), fixed.query(MINKQ_QUERY_EE, MINKQ_MODE_BOX, r));
  // A plain refit makes the scene static again.
  ASSERT_EQ(minkq_scene_refit(still.get(), test::vertices_of(sheet, 0)), MINKQ_SUCCESS);
  EXPECT_EQ(minkq_scene_is_swept(still.get()), 0);
  EXPECT_EQ(still.query(MINKQ_QUERY_EE, MINKQ_MODE_CAPSULE_EXACT, r, MINKQ_QUERY_LEAF_EXACT),
            fixed.query(MINKQ_QUERY_EE, MINKQ_MODE_CAPSULE_EXACT, r, MINKQ_QUERY_LEAF_EXACT));
}

// A vertex and an edge that fly through a triangle and an edge which stay still, far past
// them (motions a hundred times the elements' size), apart at t = 0 and t = 1.
TEST(Swept, an_element_moving_far_past_a_still_one_is_found) {
  const test::Device cpu;
  for (double length : {1.0, 100.0, 1e4}) {
    Mesh from;
    from.xyz = {0, -1, -1, 0, 2, -1, 0, -1, 2,         // triangle 0 in the plane x = 0 (still)
                float(-length), 0.1f, 0.1f,             // vertex 3: crosses the triangle
                0, 0, -5, 0, 0, -4,                     // edge 4-5 along z, still
                float(-length), 0.5f, -4.5f, float(-length), -0.5f, -4.5f};  // edge 6-7 along y: sweeps through
    from.tris = {0, 1, 2};
    from.edges = reference::derive_edges(from.tris);
    Mesh to = from;
    to.xyz[9] = float(length);
    to.xyz[18] = to.xyz[21] = float(length);
    // Edges 4-5 and 6-7 are not triangle edges: a scene of the triangle's edges plus these.
    Mesh vt_from = from, vt_to = to;
    vt_from.edges = vt_to.edges = {0, 1, 0, 2, 1, 2, 4, 5, 6, 7};
    test::Scene scene(cpu.get(), vt_from, kBothDrop);
    // The API derives edges from triangles: pass them explicitly.
    minkq_scene_desc desc{};
    desc.flags = kBothDrop;
    desc.vertices = test::vertices_of(vt_from, 0);
    desc.triangles = cxx::host_buffer(vt_from.tris.data(), 1);
    desc.edges = cxx::host_buffer(vt_from.edges.data(), 5);
    cxx::Scene explicit_edges = test::new_scene(cpu.get(), desc);
    ASSERT_EQ(minkq_scene_rebuild_swept(explicit_edges.get(), test::vertices_of(vt_from, 0), test::vertices_of(vt_to, 0)),
              MINKQ_SUCCESS);
    const float r = 0.01f;
    for (minkq_mode mode : kVtModes) {
      const Pairs vt = test::Scene::query_pairs(explicit_edges.get(), MINKQ_QUERY_VT, mode, r);
      EXPECT_TRUE(std::count(vt.begin(), vt.end(), std::pair<int32_t, int32_t>{3, 0})) << "length " << length << " mode " << mode;
    }
    const Pairs ee = test::Scene::query_pairs(explicit_edges.get(), MINKQ_QUERY_EE, MINKQ_MODE_BOX, r);
    EXPECT_TRUE(std::count(ee.begin(), ee.end(), std::pair<int32_t, int32_t>{3, 4})) << "length " << length;
    // At either end alone they are far apart.
    EXPECT_TRUE(scene.query(MINKQ_QUERY_VT, MINKQ_MODE_BOX, r).empty());
  }
}

TEST(Swept, float64_steps_lose_no_contact) {
  const test::Device cpu;
  Mesh sheet = reference::twisted_sheet(16, 2.0);
  Step step{sheet, moved(sheet, 1.0, 0.3)};
  for (Mesh* m : {&step.from, &step.to}) {
    std::vector<double> xyz(m->xyz.size());
    for (size_t i = 0; i < xyz.size(); ++i) xyz[i] = double(m->xyz[i]) * 1e-3 + 7e3 + 1e-9 * double(i % 7);
    reference::set_float64(*m, std::move(xyz));
  }
  check_step(cpu.get(), step, 0.5 * reference::mean_edge_length(step.from), "float64 far from the origin");
}

TEST(Swept, what_swept_scenes_refuse_is_named) {
  const test::Device cpu;
  const Mesh sheet = reference::twisted_sheet(6, 1.0);
  test::Scene scene = swept_scene(cpu.get(), Step{sheet, moved(sheet, 1.0, 0.0)}, false);
  minkq_query_info info{};
  minkq_query_desc leaf{MINKQ_QUERY_VT, MINKQ_MODE_BOX, MINKQ_QUERY_LEAF_EXACT, 0.1f};
  EXPECT_EQ(minkq_scene_query(scene.get(), &leaf, nullptr, 0, MINKQ_MEMORY_HOST, &info), MINKQ_ERROR_UNSUPPORTED);
  EXPECT_NE(std::string(minkq_last_error_message()).find("LEAF_EXACT on swept positions"), std::string::npos);
  minkq_query_desc capsule{MINKQ_QUERY_EE, MINKQ_MODE_CAPSULE_RAY, 0, 0.1f};
  EXPECT_EQ(minkq_scene_query(scene.get(), &capsule, nullptr, 0, MINKQ_MEMORY_HOST, &info), MINKQ_ERROR_UNSUPPORTED);
  EXPECT_NE(std::string(minkq_last_error_message()).find("box mode only"), std::string::npos);
  const std::vector<float> fewer(sheet.xyz.begin(), sheet.xyz.end() - 3);
  EXPECT_EQ(minkq_scene_refit_swept(scene.get(), test::vertices_of(sheet, 0), cxx::host_buffer(fewer.data(), fewer.size() / 3)),
            MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(minkq_last_error_message()).find("refit_swept with"), std::string::npos);
  std::vector<float> bad = sheet.xyz;
  bad[7] = NAN;
  EXPECT_EQ(minkq_scene_rebuild_swept(scene.get(), test::vertices_of(sheet, 0), cxx::host_buffer(bad.data(), bad.size() / 3)),
            MINKQ_ERROR_NON_FINITE);
  EXPECT_NE(std::string(minkq_last_error_message()).find("x1 vertex 2 has a non-finite coordinate"), std::string::npos)
      << minkq_last_error_message();
  EXPECT_EQ(minkq_scene_is_swept(scene.get()), 1);  // kept
  EXPECT_EQ(minkq_scene_is_swept(nullptr), 0);
  EXPECT_EQ(minkq_scene_refit_swept(nullptr, test::vertices_of(sheet, 0), test::vertices_of(sheet, 0)),
            MINKQ_ERROR_INVALID_ARGUMENT);
}

}  // namespace
}  // namespace minkq
