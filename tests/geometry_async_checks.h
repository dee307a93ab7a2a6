// The stream-ordered calls on scenes of many geometries (minkq_async.h),
// checked on any device as async_checks.h checks one-mesh scenes: test_geometries_async.cpp
// runs them on the CPU, test_cuda_geometries.cpp on a GPU (and captures them into a graph).
// Each check drives a scene by the asynchronous calls beside a CPU twin driven by the blocking
// ones over the same positions, and compares their pairs.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "async_checks.h"
#include "minkq_reference.h"
#include "test_util.h"

namespace minkq::test {

// A mixed scene of float geometries: a cloth with thickness (world 0), a static body below it
// with thickness, the cloth's copy in world 1, a static floor in every world, and rods on the
// cloth's edges (group 2, which the body's mask leaves out). Three geometries move: the two
// cloths and the rods, one after another in a whole-scene buffer.
struct AsyncGeometries {
  using Mesh = reference::Mesh;
  Mesh cloth = reference::twisted_sheet(16, 0.5), body = reference::grid_sheet(21), floor = reference::grid_sheet(7);
  Mesh rods;
  std::vector<float> cloth_thickness, body_thickness;
  std::vector<minkq_geometry_desc> descs;
  static constexpr uint32_t kMoving[] = {0, 2, 4};

  AsyncGeometries(const AsyncGeometries&) = delete;  // descs point into the meshes
  AsyncGeometries& operator=(const AsyncGeometries&) = delete;
  explicit AsyncGeometries(Random& rng) {
    reference::transform(body, 1.2, -0.1);
    reference::transform(floor, 2.0, -0.5);
    rods = cloth;
    rods.edges = reference::derive_edges(rods.tris);
    rods.tris.clear();
    const double edge = reference::mean_edge_length(cloth);
    for (size_t v = 0; v < cloth.vertex_count(); ++v) cloth_thickness.push_back(float(edge * rng.uniform(0.0f, 0.3f)));
    for (size_t v = 0; v < body.vertex_count(); ++v) body_thickness.push_back(float(edge * rng.uniform(0.0f, 0.5f)));
    const uint32_t all = MINKQ_SCENE_VT | MINKQ_SCENE_EE | MINKQ_SCENE_VV | MINKQ_SCENE_EV;
    const uint32_t self = MINKQ_GEOMETRY_SELF | MINKQ_GEOMETRY_DROP_INCIDENT;
    add(cloth, all, self, 0, &cloth_thickness);
    add(body, all, MINKQ_GEOMETRY_STATIC, 0, &body_thickness);
    add(cloth, all, self, 1, nullptr);
    add(floor, MINKQ_SCENE_VT | MINKQ_SCENE_EE, MINKQ_GEOMETRY_STATIC, -1, nullptr);
    add(rods, MINKQ_SCENE_EE | MINKQ_SCENE_VV | MINKQ_SCENE_EV, self, 0, nullptr).group = 2;
    descs[1].mask = ~2u;
  }
  minkq_geometry_desc& add(const Mesh& mesh, uint32_t kinds, uint32_t flags, int32_t world,
                           const std::vector<float>* thickness) {
    minkq_geometry_desc d;
    minkq_geometry_desc_init(&d);
    d.kinds = kinds;
    d.flags = flags;
    d.world = world;
    d.vertices = host_buffer(mesh.xyz.data(), mesh.vertex_count());
    d.triangles = host_buffer(mesh.tris.data(), mesh.triangle_count());
    d.edges = host_buffer(mesh.edges.data(), mesh.edge_count());
    if (thickness) d.thickness = host_buffer(thickness->data(), thickness->size());
    descs.push_back(d);
    return descs.back();
  }
  cxx::Scene create(minkq_device* device) const {
    return created<cxx::Scene>(
        [&](minkq_scene** out) { return minkq_scene_create_geometries(device, descs.data(), descs.size(), out); });
  }
  float radius() const { return float(0.5 * reference::mean_edge_length(cloth)); }
  // The moving geometries' positions at a step: each cloth (and the rods) moved differently.
  std::vector<float> moved(int step) const {
    std::vector<float> all;
    for (int k = 0; k < 3; ++k) {
      Mesh m = k == 2 ? rods : cloth;
      reference::transform(m, 1.0 + 0.01 * step, 0.004 * step * (k + 1));
      for (size_t v = 0; v < m.vertex_count(); ++v) m.xyz[3 * v + 2] += 0.02f * float(std::sin(0.2 * double(v) + step + k));
      all.insert(all.end(), m.xyz.begin(), m.xyz.end());
    }
    return all;
  }
  size_t moving_vertices() const { return 3 * cloth.vertex_count(); }
};

// The two scenes: `scene` on the device under test, driven by the asynchronous calls, and its
// blocking twin on the CPU.
struct AsyncGeometryScenes {
  AsyncMemory& memory;
  AsyncGeometries geometries;
  cxx::Scene scene, twin;
  AsyncGeometryScenes(AsyncMemory& memory, minkq_device* device, minkq_device* cpu, Random& rng)
      : memory(memory), geometries(rng), scene(geometries.create(device)), twin(geometries.create(cpu)) {}

  // A whole-scene move of both: stream-ordered on `scene`, blocking on the twin; x1: swept.
  void move(const std::vector<float>& x0, const std::vector<float>* x1, bool rebuild) {
    const size_t n = x0.size() / 3;
    const minkq_buffer a{memory.copy_of(x0), 0, n, memory.kind()};
    const minkq_buffer ha = host_buffer(x0.data(), n);
    minkq_status async_status, blocking_status;
    if (x1) {
      const minkq_buffer b{memory.copy_of(*x1), 0, n, memory.kind()};
      const minkq_buffer hb = host_buffer(x1->data(), n);
      async_status = rebuild ? minkq_scene_rebuild_swept_async(scene.get(), a, b, memory.stream())
                             : minkq_scene_refit_swept_async(scene.get(), a, b, memory.stream());
      blocking_status = rebuild ? minkq_scene_rebuild_swept(twin.get(), ha, hb) : minkq_scene_refit_swept(twin.get(), ha, hb);
    } else {
      async_status = rebuild ? minkq_scene_rebuild_async(scene.get(), a, memory.stream())
                             : minkq_scene_refit_async(scene.get(), a, memory.stream());
      blocking_status = rebuild ? minkq_scene_rebuild(twin.get(), ha) : minkq_scene_refit(twin.get(), ha);
    }
    ASSERT_EQ(async_status, MINKQ_SUCCESS) << minkq_last_error_message();
    ASSERT_EQ(blocking_status, MINKQ_SUCCESS) << minkq_last_error_message();
  }

  // Every kind's stream-ordered queries (a coarse and a fine mode, leaf-exact where the scene is
  // not swept; buffers that hold all the pairs and one pair short; VT and EE in one call) equal
  // the twin's blocking ones.
  void expect_queries_match(const std::string& label) {
    SCOPED_TRACE(label);
    const float r = geometries.radius();
    const bool swept = minkq_scene_is_swept(twin.get()) == 1;
    struct Case {
      minkq_query_kind kind;
      minkq_mode mode;
      uint32_t flags;
    };
    std::vector<Case> cases;
    for (minkq_query_kind kind : {MINKQ_QUERY_VT, MINKQ_QUERY_EE, MINKQ_QUERY_VV, MINKQ_QUERY_EV}) {
      cases.push_back({kind, MINKQ_MODE_BOX, uint32_t(MINKQ_QUERY_CANONICAL | (swept ? 0 : MINKQ_QUERY_LEAF_EXACT))});
      if (!swept || kind != MINKQ_QUERY_EE)
        cases.push_back({kind, kind == MINKQ_QUERY_EE ? MINKQ_MODE_CAPSULE_EXACT : MINKQ_MODE_SPHERE, 0u});
    }
    for (const Case& c : cases) {
      const std::string what = "kind " + std::to_string(c.kind) + " mode " + std::to_string(c.mode) + " flags " +
                               std::to_string(c.flags);
      const Pairs expected = Scene::query_pairs(twin.get(), c.kind, c.mode, r, c.flags & MINKQ_QUERY_LEAF_EXACT);
      ASSERT_GT(expected.size(), 0u) << what;
      const minkq_query_desc desc{c.kind, c.mode, c.flags, r};
      for (size_t capacity : {expected.size(), expected.size() - 1}) {
        int32_t* pairs = memory.copy_of(std::vector<int32_t>(2 * capacity + 2, AsyncScene::kGuard));
        uint64_t* count = memory.copy_of(std::vector<uint64_t>{7});
        ASSERT_EQ(minkq_scene_query_async(scene.get(), &desc, pairs, capacity, count, memory.stream()), MINKQ_SUCCESS)
            << what << ": " << minkq_last_error_message();
        const uint64_t n = memory.read_back(count, 1)[0];
        const std::vector<int32_t> raw = memory.read_back(pairs, 2 * capacity + 2);
        EXPECT_EQ(n, expected.size()) << what << " capacity " << capacity;
        EXPECT_EQ(raw[2 * capacity], AsyncScene::kGuard) << what << ": written past a buffer of " << capacity;
        if (capacity < expected.size()) {
          EXPECT_TRUE(is_subset(sorted(pairs_of(raw, capacity)), expected)) << what << " capacity " << capacity;
        } else if (c.flags & MINKQ_QUERY_CANONICAL) {
          EXPECT_EQ(pairs_of(raw, n), expected) << what;
        } else {
          EXPECT_EQ(sorted(pairs_of(raw, n)), expected) << what;
        }
      }
    }
    const uint32_t leaf = swept ? 0u : uint32_t(MINKQ_QUERY_LEAF_EXACT);
    const minkq_query_desc vt{MINKQ_QUERY_VT, MINKQ_MODE_BOX, leaf | MINKQ_QUERY_CANONICAL, r};
    const minkq_query_desc ee{MINKQ_QUERY_EE, MINKQ_MODE_BOX, leaf | MINKQ_QUERY_CANONICAL, r};
    const Pairs vt_expected = Scene::query_pairs(twin.get(), MINKQ_QUERY_VT, MINKQ_MODE_BOX, r, leaf);
    const Pairs ee_expected = Scene::query_pairs(twin.get(), MINKQ_QUERY_EE, MINKQ_MODE_BOX, r, leaf);
    int32_t* vt_pairs = memory.copy_of(std::vector<int32_t>(2 * vt_expected.size(), 0));
    int32_t* ee_pairs = memory.copy_of(std::vector<int32_t>(2 * ee_expected.size(), 0));
    uint64_t* counts = memory.copy_of(std::vector<uint64_t>{7, 7});
    ASSERT_EQ(minkq_scene_query_vt_ee_async(scene.get(), &vt, &ee, vt_pairs, vt_expected.size(), counts, ee_pairs,
                                            ee_expected.size(), counts + 1, memory.stream()),
              MINKQ_SUCCESS)
        << minkq_last_error_message();
    const std::vector<uint64_t> count = memory.read_back(counts, 2);
    ASSERT_EQ(count[0], vt_expected.size());
    ASSERT_EQ(count[1], ee_expected.size());
    EXPECT_EQ(pairs_of(memory.read_back(vt_pairs, 2 * count[0]), count[0]), vt_expected) << "VT of vt_ee";
    EXPECT_EQ(pairs_of(memory.read_back(ee_pairs, 2 * count[1]), count[1]), ee_expected) << "EE of vt_ee";
  }
};

// Whole-scene refits, rebuilds and their swept forms, stream-ordered, give the blocking calls'
// pairs in every kind; so do queries after a blocking move of one geometry (an arrangement of
// swept and resting geometries no reservation foresaw: the call writes its table first).
inline void check_geometry_async_matches_blocking(AsyncMemory& memory, minkq_device* device, minkq_device* cpu) {
  Random rng(fresh_seed());
  AsyncGeometryScenes s(memory, device, cpu, rng);
  ASSERT_EQ(minkq_scene_reserve(s.scene.get(), MINKQ_RESERVE_REBUILD | MINKQ_RESERVE_SWEPT, 1 << 16), MINKQ_SUCCESS)
      << minkq_last_error_message();
  s.expect_queries_match("as created");
  std::vector<float> previous = s.geometries.moved(0);
  for (int step = 1; step <= 5; ++step) {
    const std::vector<float> next = s.geometries.moved(step);
    const bool swept = step == 3 || step == 4, rebuild = step == 2 || step == 4;
    s.move(swept ? previous : next, swept ? &next : nullptr, rebuild);
    if (::testing::Test::HasFatalFailure()) return;
    s.expect_queries_match("step " + std::to_string(step) + (rebuild ? " rebuilt" : " refit") + (swept ? " swept" : ""));
    previous = next;
  }
  memory.wait();
  const AsyncGeometries& g = s.geometries;
  const std::vector<float> later = g.moved(6);
  const minkq_buffer x0 = host_buffer(previous.data(), g.cloth.vertex_count());
  const minkq_buffer x1 = host_buffer(later.data(), g.cloth.vertex_count());
  for (minkq_scene* scene : {s.scene.get(), s.twin.get()})
    ASSERT_EQ(minkq_scene_geometry_refit_swept(scene, 0, x0, x1), MINKQ_SUCCESS) << minkq_last_error_message();
  s.expect_queries_match("geometry 0 swept alone");
  EXPECT_EQ(minkq_scene_async_status(s.scene.get(), memory.stream()), MINKQ_SUCCESS) << minkq_last_error_message();
}

// A non-finite coordinate in one moving geometry's part of a stream-ordered refit: that
// geometry keeps its positions while the others take theirs, and minkq_scene_async_status
// names the buffer's vertex and the geometry once.
inline void check_geometry_async_non_finite(AsyncMemory& memory, minkq_device* device, minkq_device* cpu) {
  Random rng(fresh_seed());
  AsyncGeometryScenes s(memory, device, cpu, rng);
  ASSERT_EQ(minkq_scene_reserve(s.scene.get(), MINKQ_RESERVE_REFIT, 1 << 16), MINKQ_SUCCESS)
      << minkq_last_error_message();
  const AsyncGeometries& g = s.geometries;
  const size_t n = g.cloth.vertex_count();
  std::vector<float> next = g.moved(1);
  const size_t bad = 2 * n + 5;  // the rods' (geometry 4's) vertex 5
  next[3 * bad + 1] = NAN;
  const minkq_buffer all{memory.copy_of(next), 0, next.size() / 3, memory.kind()};
  ASSERT_EQ(minkq_scene_refit_async(s.scene.get(), all, memory.stream()), MINKQ_SUCCESS) << minkq_last_error_message();
  for (uint32_t k = 0; k < 2; ++k)  // the twin: the two cloths moved, the rods kept
    ASSERT_EQ(minkq_scene_geometry_refit(s.twin.get(), AsyncGeometries::kMoving[k], host_buffer(next.data() + 3 * k * n, n)),
              MINKQ_SUCCESS)
        << minkq_last_error_message();
  EXPECT_EQ(minkq_scene_async_status(s.scene.get(), memory.stream()), MINKQ_ERROR_NON_FINITE);
  const std::string message = minkq_last_error_message();
  EXPECT_NE(message.find("minkq_scene_refit_async: vertex " + std::to_string(bad) + " "), std::string::npos) << message;
  EXPECT_NE(message.find("geometry 4 (its vertex 5) kept its positions"), std::string::npos) << message;
  EXPECT_EQ(minkq_scene_async_status(s.scene.get(), memory.stream()), MINKQ_SUCCESS) << "reported once";
  s.expect_queries_match("after a refit with a non-finite rod vertex");
}

// What the stream-ordered calls refuse on scenes of many geometries, at once: moves without
// the reservation, of the wrong vertex count, or of moving geometries that mix precisions.
inline void check_geometry_async_refusals(AsyncMemory& memory, minkq_device* device, minkq_device* cpu) {
  Random rng(fresh_seed());
  AsyncGeometryScenes s(memory, device, cpu, rng);
  const std::vector<float> next = s.geometries.moved(1);
  const minkq_buffer all{memory.copy_of(next), 0, next.size() / 3, memory.kind()};
  EXPECT_EQ(minkq_scene_refit_async(s.scene.get(), all, memory.stream()), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(minkq_last_error_message()).find("needs scratch reserved first"), std::string::npos)
      << minkq_last_error_message();
  ASSERT_EQ(minkq_scene_reserve(s.scene.get(), MINKQ_RESERVE_REFIT, 0), MINKQ_SUCCESS) << minkq_last_error_message();
  const minkq_buffer short_by_one{all.data, 0, all.count - 1, memory.kind()};
  EXPECT_EQ(minkq_scene_refit_async(s.scene.get(), short_by_one, memory.stream()), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(minkq_last_error_message()).find("moving geometries have " + std::to_string(all.count)),
            std::string::npos)
      << minkq_last_error_message();

  AsyncGeometries mixed(rng);  // the rods in double: two precisions among the moving geometries
  std::vector<double> rods64(mixed.rods.xyz.begin(), mixed.rods.xyz.end());
  mixed.descs[4].vertices = host_buffer(rods64.data(), rods64.size() / 3);
  mixed.descs[4].flags |= MINKQ_GEOMETRY_FLOAT64;
  cxx::Scene scene = mixed.create(device);
  ASSERT_EQ(minkq_scene_reserve(scene.get(), MINKQ_RESERVE_REFIT, 0), MINKQ_SUCCESS) << minkq_last_error_message();
  EXPECT_EQ(minkq_scene_refit_async(scene.get(), all, memory.stream()), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(minkq_last_error_message()).find("mix float32 and float64"), std::string::npos)
      << minkq_last_error_message();
}

}  // namespace minkq::test
