// Scenes of many geometries on CUDA against the CPU through the C API: self and cross pairs,
// groups and masks, worlds, thickness, a float64 geometry, static and moving geometries, one
// geometry refit, rebuilt and swept: the same pairs, digests and work counts on both backends in
// every mode. The stream-ordered calls refuse such scenes on both. Skips (saying why) where no
// CUDA device is usable.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "cuda_checks.h"

namespace minkq {
namespace {

using namespace cuda_test;

// A scene of the meshes below, each with its role: a cloth, a static body below it with thickness,
// the cloth's copies in two more worlds at the same place, a world -1 floor, a float64 rod set of
// the cloth's edges in a group the body's mask leaves out.
struct MixedScene {
  Mesh cloth = reference::twisted_sheet(24, 0.5), body = reference::grid_sheet(31), floor = reference::grid_sheet(9);
  Mesh rods;
  std::vector<float> cloth_thickness, body_thickness;
  std::vector<minkq_geometry_desc> descs;

  explicit MixedScene(test::Random& rng) {
    reference::transform(body, 1.2, -0.1);
    reference::transform(floor, 2.0, -0.5);
    rods = cloth;
    rods.edges = reference::derive_edges(rods.tris);
    rods.tris.clear();
    std::vector<double> xyz64(rods.xyz.begin(), rods.xyz.end());
    for (double& x : xyz64) x += 1e-9 * rng.uniform(-1.0f, 1.0f);
    reference::set_float64(rods, xyz64);
    const double edge = reference::mean_edge_length(cloth);
    for (size_t v = 0; v < cloth.vertex_count(); ++v) cloth_thickness.push_back(float(edge * rng.uniform(0.0f, 0.3f)));
    for (size_t v = 0; v < body.vertex_count(); ++v) body_thickness.push_back(float(edge * rng.uniform(0.0f, 0.5f)));
    auto add = [&](const Mesh& mesh, uint32_t kinds, uint32_t flags, int32_t world, const std::vector<float>* thickness) {
      minkq_geometry_desc d;
      minkq_geometry_desc_init(&d);
      d.kinds = kinds;
      d.flags = flags;
      d.world = world;
      if (flags & MINKQ_GEOMETRY_FLOAT64) d.vertices = host_buffer(mesh.xyz64.data(), mesh.vertex_count());
      else d.vertices = host_buffer(mesh.xyz.data(), mesh.vertex_count());
      d.triangles = host_buffer(mesh.tris.data(), mesh.triangle_count());
      d.edges = host_buffer(mesh.edges.data(), mesh.edge_count());
      if (thickness) d.thickness = host_buffer(thickness->data(), thickness->size());
      descs.push_back(d);
      return descs.size() - 1;
    };
    const uint32_t all = MINKQ_SCENE_VT | MINKQ_SCENE_EE | MINKQ_SCENE_VV | MINKQ_SCENE_EV;
    const uint32_t self = MINKQ_GEOMETRY_SELF | MINKQ_GEOMETRY_DROP_INCIDENT;
    add(cloth, all, self, 0, &cloth_thickness);
    add(body, all, MINKQ_GEOMETRY_STATIC, 0, &body_thickness);
    for (int32_t world : {1, 2}) add(cloth, all, self, world, nullptr);
    add(floor, MINKQ_SCENE_VT | MINKQ_SCENE_EE, MINKQ_GEOMETRY_STATIC, -1, nullptr);
    const size_t r = add(rods, MINKQ_SCENE_EE | MINKQ_SCENE_VV | MINKQ_SCENE_EV, MINKQ_GEOMETRY_FLOAT64, 0, nullptr);
    descs[r].group = 2;
    descs[1].mask = ~2u;
  }
  cxx::Scene create(minkq_device* device) const {
    return test::created<cxx::Scene>(
        [&](minkq_scene** out) { return minkq_scene_create_geometries(device, descs.data(), descs.size(), out); });
  }
};

void compare_kinds(minkq_scene* cpu, minkq_scene* cuda, float r, bool swept, const std::string& label) {
  for (minkq_query_kind kind : {MINKQ_QUERY_VT, MINKQ_QUERY_EE, MINKQ_QUERY_VV, MINKQ_QUERY_EV})
    for (minkq_mode mode : {MINKQ_MODE_BOX, MINKQ_MODE_SPHERE, MINKQ_MODE_CAPSULE_RAY, MINKQ_MODE_CAPSULE_EXACT})
      for (uint32_t leaf : {0u, uint32_t(MINKQ_QUERY_LEAF_EXACT)}) {
        if ((kind == MINKQ_QUERY_EE && mode == MINKQ_MODE_SPHERE) || (swept && (leaf || (kind == MINKQ_QUERY_EE && mode != MINKQ_MODE_BOX)))) continue;
        const std::string what = label + " kind " + std::to_string(kind) + " mode " + std::to_string(mode) +
                                 (leaf ? " leaf_exact" : "");
        expect_same(scene_query(cpu, kind, mode, r, leaf | MINKQ_QUERY_DIGEST | MINKQ_QUERY_STATS),
                    scene_query(cuda, kind, mode, r, leaf | MINKQ_QUERY_DIGEST | MINKQ_QUERY_STATS), what);
      }
}

TEST_F(Cuda, scenes_of_many_geometries_match_cpu_over_moves) {
  test::Device cpu("cpu"), cuda("cuda");
  test::Random rng(seed);
  MixedScene mixed(rng);
  cxx::Scene a = mixed.create(cpu.get()), b = mixed.create(cuda.get());
  ASSERT_TRUE(a && b);
  const float r = float(0.5 * reference::mean_edge_length(mixed.cloth));
  compare_kinds(a.get(), b.get(), r, false, "created");
  Mesh moved = mixed.cloth;
  reference::transform(moved, 1.01, 0.02);
  for (minkq_scene* scene : {a.get(), b.get()}) {
    ASSERT_EQ(minkq_scene_geometry_refit(scene, 0, host_buffer(moved.xyz.data(), moved.vertex_count())), MINKQ_SUCCESS)
        << minkq_last_error_message();
    ASSERT_EQ(minkq_scene_geometry_rebuild(scene, 3, host_buffer(moved.xyz.data(), moved.vertex_count())), MINKQ_SUCCESS)
        << minkq_last_error_message();
  }
  compare_kinds(a.get(), b.get(), r, false, "one geometry refit, one rebuilt");
  for (minkq_scene* scene : {a.get(), b.get()})
    ASSERT_EQ(minkq_scene_geometry_refit_swept(scene, 2, host_buffer(mixed.cloth.xyz.data(), mixed.cloth.vertex_count()),
                                               host_buffer(moved.xyz.data(), moved.vertex_count())),
              MINKQ_SUCCESS)
        << minkq_last_error_message();
  compare_kinds(a.get(), b.get(), r, true, "one geometry swept");
  for (minkq_scene* scene : {a.get(), b.get()}) {
    ASSERT_EQ(minkq_scene_reserve(scene, MINKQ_RESERVE_REFIT, 0), MINKQ_ERROR_UNSUPPORTED);
    EXPECT_NE(std::string(minkq_last_error_message()).find("geometries"), std::string::npos) << minkq_last_error_message();
  }
}

}  // namespace
}  // namespace minkq
