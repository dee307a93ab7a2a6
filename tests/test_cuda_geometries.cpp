// Scenes of many geometries on CUDA against the CPU through the C API: self and cross pairs,
// groups and masks, worlds, thickness, a float64 geometry, static and moving geometries, one
// geometry refit, rebuilt and swept: the same pairs, digests and work counts on both backends in
// every mode; their stream-ordered calls (geometry_async_checks.h, run on the CPU by
// test_geometries_async.cpp) against the blocking ones, and captured into a CUDA graph. Skips
// (saying why) where no CUDA device is usable.
#include <gtest/gtest.h>

#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "cuda_async_memory.h"
#include "cuda_checks.h"
#include "geometry_async_checks.h"

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
}

#if defined(MINKQ_TEST_HAVE_CUDART)
class CudaGeometriesAsync : public CudaAsync {};

TEST_F(CudaGeometriesAsync, queries_match_the_blocking_calls_over_every_move) {
  test::check_geometry_async_matches_blocking(memory(), cuda->get(), cpu->get());
}

TEST_F(CudaGeometriesAsync, a_non_finite_vertex_keeps_its_geometry_and_is_reported_once) {
  test::check_geometry_async_non_finite(memory(), cuda->get(), cpu->get());
}

TEST_F(CudaGeometriesAsync, moves_without_reservation_or_of_mixed_precision_are_refused) {
  test::check_geometry_async_refusals(memory(), cuda->get(), cpu->get());
}

// A simulator's captured step over a scene of many geometries: the moving geometries' refit (or
// rebuild) + VT and EE + VV recorded once into a CUDA graph, replayed over new positions written
// into the same device buffer; every replay gives the CPU twin's blocking pairs.
TEST_F(CudaGeometriesAsync, captured_step_replays_over_moving_geometries) {
  if (const char* blocking = std::getenv("CUDA_LAUNCH_BLOCKING"); blocking && std::string(blocking) == "1")
    GTEST_SKIP() << "CUDA_LAUNCH_BLOCKING=1: stream capture is not tested with blocking launches";
  test::Random rng(seed);
  for (bool rebuild : {false, true}) {
    SCOPED_TRACE(rebuild ? "rebuild" : "refit");
    test::AsyncGeometryScenes s(memory(), cuda->get(), cpu->get(), rng);
    const size_t capacity = 1 << 16;
    ASSERT_EQ(minkq_scene_reserve(s.scene.get(), MINKQ_RESERVE_REBUILD, capacity), MINKQ_SUCCESS)
        << minkq_last_error_message();
    const float r = s.geometries.radius();
    const std::vector<float> start = s.geometries.moved(0);
    float* positions = memory().copy_of(start);
    int32_t* pairs = static_cast<int32_t*>(memory().allocate(3 * 2 * capacity * sizeof(int32_t)));
    uint64_t* counts = static_cast<uint64_t*>(memory().allocate(3 * sizeof(uint64_t)));
    const minkq_buffer vertices{positions, 0, start.size() / 3, MINKQ_MEMORY_DEVICE};
    const uint32_t flags = MINKQ_QUERY_LEAF_EXACT | MINKQ_QUERY_CANONICAL;
    const minkq_query_desc vt{MINKQ_QUERY_VT, MINKQ_MODE_BOX, flags, r}, ee{MINKQ_QUERY_EE, MINKQ_MODE_BOX, flags, r};
    const minkq_query_desc vv{MINKQ_QUERY_VV, MINKQ_MODE_SPHERE, flags, r};
    cudaStream_t stream = static_cast<cudaStream_t>(memory().stream());
    const CapturedGraph graph(stream, [&](auto check) {
      check(rebuild ? minkq_scene_rebuild_async(s.scene.get(), vertices, stream)
                    : minkq_scene_refit_async(s.scene.get(), vertices, stream));
      check(minkq_scene_query_vt_ee_async(s.scene.get(), &vt, &ee, pairs, capacity, counts, pairs + 2 * capacity,
                                          capacity, counts + 1, stream));
      check(minkq_scene_query_async(s.scene.get(), &vv, pairs + 4 * capacity, capacity, counts + 2, stream));
    });
    ASSERT_TRUE(graph.ok());
    for (int step = 1; step <= 4; ++step) {
      const std::vector<float> next = s.geometries.moved(step);
      memory().write(positions, next.data(), next.size() * sizeof(float));
      ASSERT_EQ(graph.launch(), cudaSuccess);
      const std::vector<uint64_t> count = memory().read_back(counts, 3);
      const minkq_buffer host = host_buffer(next.data(), next.size() / 3);
      ASSERT_EQ(rebuild ? minkq_scene_rebuild(s.twin.get(), host) : minkq_scene_refit(s.twin.get(), host), MINKQ_SUCCESS);
      const minkq_query_desc* descs[] = {&vt, &ee, &vv};
      for (int k = 0; k < 3; ++k) {
        const test::Pairs expected = test::Scene::query_pairs(s.twin.get(), descs[k]->kind, descs[k]->mode, r,
                                                              MINKQ_QUERY_LEAF_EXACT);
        ASSERT_EQ(count[size_t(k)], expected.size()) << "replay " << step << " query " << k;
        EXPECT_EQ(test::pairs_of(memory().read_back(pairs + 2 * capacity * size_t(k), 2 * count[size_t(k)]), count[size_t(k)]),
                  expected)
            << "replay " << step << " query " << k;
      }
    }
    EXPECT_EQ(minkq_scene_async_status(s.scene.get(), stream), MINKQ_SUCCESS) << minkq_last_error_message();
  }
}
#endif  // MINKQ_TEST_HAVE_CUDART

}  // namespace
}  // namespace minkq
