// The CUDA backend against the CPU backend through the C API: the same trees and the same
// per-element code, so every query must give the identical canonical pair list (and digest)
// in every mode, after refits and rebuilds, with small output buffers, and for user-box BVHs.
// Inputs from device memory, float64, swept and codimensional scenes: test_cuda_inputs.cpp;
// the stream-ordered calls: test_cuda_async.cpp. Skips (saying why) where no CUDA device is
// usable.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "cuda_checks.h"
#include "tree_counts.h"

namespace minkq {
namespace {

using namespace cuda_test;

TEST_F(Cuda, device_is_named_and_missing_ordinals_are_unsupported) {
  test::Device cuda("cuda");
  ASSERT_NE(cuda.get(), nullptr);
  EXPECT_EQ(minkq_device_backend(cuda.get()), MINKQ_BACKEND_CUDA);
  EXPECT_EQ(std::string(minkq_device_name(cuda.get())).rfind("cuda:0 (", 0), 0u) << minkq_device_name(cuda.get());
  minkq_device* missing = nullptr;
  const std::string spec = "cuda:" + std::to_string(minkq_cuda_device_count());
  EXPECT_EQ(minkq_device_create(spec.c_str(), &missing), MINKQ_ERROR_UNSUPPORTED);
  EXPECT_EQ(missing, nullptr);
  EXPECT_FALSE(std::string(minkq_last_error_message()).empty());
}

TEST_F(Cuda, every_mode_matches_cpu_with_and_without_leaf_test) {
  test::Device cpu("cpu"), cuda("cuda");
  for (const auto& [name, mesh] : Scenes(seed).meshes)
    for (bool drop : {false, true}) {
      const uint32_t flags = kBoth | (drop ? uint32_t(MINKQ_SCENE_DROP_INCIDENT) : 0u);
      cxx::Scene a = make_scene(cpu.get(), mesh, flags), b = make_scene(cuda.get(), mesh, flags);
      ASSERT_TRUE(a && b);
      const double edge = reference::mean_edge_length(mesh);
      for (double factor : {0.1, 1.0})
        compare_all_modes(a.get(), b.get(), float(factor * edge), name + (drop ? " drop_incident" : ""));
    }
}

TEST_F(Cuda, refit_matches_cpu_after_moving_vertices) {
  test::Device cpu("cpu"), cuda("cuda");
  test::Random rng(seed);
  for (const auto& [name, mesh] : Scenes(seed).meshes) {
    cxx::Scene a = make_scene(cpu.get(), mesh, kBoth), b = make_scene(cuda.get(), mesh, kBoth);
    ASSERT_TRUE(a && b);
    const float r = float(0.5 * reference::mean_edge_length(mesh));
    for (int step = 0; step < 3; ++step) {
      // Moved vertices, passed with a 16-byte stride (padding float) to exercise the gather.
      std::vector<float> moved(4 * mesh.vertex_count());
      for (size_t v = 0; v < mesh.vertex_count(); ++v) {
        const float angle = 0.2f * float(step + 1) * mesh.xyz[3 * v];
        const float y = mesh.xyz[3 * v + 1], z = mesh.xyz[3 * v + 2];
        moved[4 * v] = mesh.xyz[3 * v] + rng.uniform(-0.01f, 0.01f);
        moved[4 * v + 1] = std::cos(angle) * y - std::sin(angle) * z;
        moved[4 * v + 2] = std::sin(angle) * y + std::cos(angle) * z;
        moved[4 * v + 3] = std::numeric_limits<float>::quiet_NaN();  // never read
      }
      const minkq_buffer buffer = host_buffer(moved.data(), mesh.vertex_count(), 4 * sizeof(float));
      ASSERT_EQ(minkq_scene_refit(a.get(), buffer), MINKQ_SUCCESS) << minkq_last_error_message();
      ASSERT_EQ(minkq_scene_refit(b.get(), buffer), MINKQ_SUCCESS) << minkq_last_error_message();
      compare_all_modes(a.get(), b.get(), r, name + " refit " + std::to_string(step));
    }
  }
}

// A rebuild on either backend builds the same tree (same pairs, same work counts through
// compare_all_modes), and tree growth agrees up to the rounding of the device's sum.
TEST_F(Cuda, rebuild_and_tree_growth_match_cpu) {
  test::Device cpu("cpu"), cuda("cuda");
  const Mesh flat = reference::twisted_sheet(40, 0.0), wrung = reference::twisted_sheet(40, 3.0);
  cxx::Scene a = make_scene(cpu.get(), flat, kBoth), b = make_scene(cuda.get(), flat, kBoth);
  ASSERT_TRUE(a && b);
  const float r = float(0.5 * reference::mean_edge_length(wrung));
  const minkq_buffer moved = host_buffer(wrung.xyz.data(), wrung.vertex_count());
  auto growth_of = [](minkq_scene* scene) {
    double g = -1.0;
    EXPECT_EQ(minkq_scene_tree_growth(scene, &g), MINKQ_SUCCESS) << minkq_last_error_message();
    return g;
  };
  ASSERT_EQ(minkq_scene_refit(a.get(), moved), MINKQ_SUCCESS) << minkq_last_error_message();
  ASSERT_EQ(minkq_scene_refit(b.get(), moved), MINKQ_SUCCESS) << minkq_last_error_message();
  EXPECT_NEAR(growth_of(b.get()), growth_of(a.get()), 1e-12 * growth_of(a.get()));
  EXPECT_GT(growth_of(b.get()), 1.5);
  ASSERT_EQ(minkq_scene_rebuild(a.get(), moved), MINKQ_SUCCESS) << minkq_last_error_message();
  ASSERT_EQ(minkq_scene_rebuild(b.get(), moved), MINKQ_SUCCESS) << minkq_last_error_message();
  EXPECT_EQ(growth_of(a.get()), 1.0);
  EXPECT_EQ(growth_of(b.get()), 1.0);
  compare_all_modes(a.get(), b.get(), r, "wrung sheet after rebuild");
}

// Issue 56: an unreserved CUDA tree holds node_room (build.h) of the nodes its build keeps, and
// a blocking rebuild that keeps more grows it. tree_counts.h's caterpillar keeps nearly
// n - leaf size nodes where the same triangles on a line keep a few: rebuilds line ->
// caterpillar -> line -> caterpillar give the CPU's pairs in every mode, and a tree growth of
// exactly 1 (the area reduction covers every node the grown room holds), as do user-box BVHs
// built and rebuilt over the same triangles' boxes.
TEST_F(Cuda, rebuilds_that_keep_more_nodes_grow_the_room_and_match_cpu) {
  test::Device cpu("cpu"), cuda("cuda");
  const Mesh line = test::caterpillar_mesh(false), caterpillar = test::caterpillar_mesh(true);
  const int32_t n = int32_t(line.triangle_count());
  ASSERT_GT(test::tree_counts(caterpillar).triangles, node_room(test::tree_counts(line).triangles, n));
  cxx::Scene a = make_scene(cpu.get(), line, kBoth), b = make_scene(cuda.get(), line, kBoth);
  ASSERT_TRUE(a && b);
  const float r = 0.5f;
  auto growth_of = [](minkq_scene* scene) {
    double g = -1.0;
    EXPECT_EQ(minkq_scene_tree_growth(scene, &g), MINKQ_SUCCESS) << minkq_last_error_message();
    return g;
  };
  int step = 0;
  for (const Mesh* next : {&caterpillar, &line, &caterpillar}) {
    const std::string what = "rebuild " + std::to_string(step++);
    const minkq_buffer moved = host_buffer(next->xyz.data(), next->vertex_count());
    ASSERT_EQ(minkq_scene_rebuild(a.get(), moved), MINKQ_SUCCESS) << minkq_last_error_message();
    ASSERT_EQ(minkq_scene_rebuild(b.get(), moved), MINKQ_SUCCESS) << minkq_last_error_message();
    EXPECT_EQ(growth_of(b.get()), 1.0) << what;
    compare_all_modes(a.get(), b.get(), r, what);
  }
  const std::vector<Box> spread = test::primitive_boxes(line, line.tris, 3);
  const std::vector<Box> chained = test::primitive_boxes(caterpillar, caterpillar.tris, 3);
  cxx::Bvh cpu_bvh = make_bvh(cpu.get(), spread), cuda_bvh = make_bvh(cuda.get(), spread);
  ASSERT_TRUE(cpu_bvh && cuda_bvh);
  std::vector<Vec3> points;
  for (const Box& box : chained) points.push_back(box.lo);
  const minkq_buffer boxes = host_buffer(chained.data(), chained.size());
  ASSERT_EQ(minkq_bvh_rebuild(cpu_bvh.get(), boxes), MINKQ_SUCCESS) << minkq_last_error_message();
  ASSERT_EQ(minkq_bvh_rebuild(cuda_bvh.get(), boxes), MINKQ_SUCCESS) << minkq_last_error_message();
  for (minkq_mode mode : {MINKQ_MODE_BOX, MINKQ_MODE_SPHERE})
    expect_same(bvh_query(cpu_bvh.get(), MINKQ_SHAPE_SPHERE, mode, r, points, {}),
                bvh_query(cuda_bvh.get(), MINKQ_SHAPE_SPHERE, mode, r, points, {}), "bvh after rebuild");
}

// A scene with an edge tree keeps its edges only in the tree's leaf order; minkq_scene_edges
// scatters them back to their ids (and a rebuild does before it builds): the same list as the
// CPU's, in the numbering EE pairs use, after each of two rebuilds that change the leaf order.
TEST_F(Cuda, scene_edges_keep_their_numbering_over_rebuilds) {
  test::Device cpu("cpu"), cuda("cuda");
  const Mesh flat = reference::twisted_sheet(40, 0.0);
  for (uint32_t flags : {kBoth, uint32_t(MINKQ_SCENE_EE), uint32_t(MINKQ_SCENE_VT)}) {
    cxx::Scene a = make_scene(cpu.get(), flat, flags), b = make_scene(cuda.get(), flat, flags);
    ASSERT_TRUE(a && b);
    const std::vector<int32_t> created = test::Scene::edges_of(a.get());
    const std::string what = "flags " + std::to_string(flags);
    expect_same_pairs(created, test::Scene::edges_of(b.get()), what + " at creation");
    for (double turns : {3.0, -2.0}) {
      const Mesh wrung = reference::twisted_sheet(40, turns);
      const minkq_buffer moved = host_buffer(wrung.xyz.data(), wrung.vertex_count());
      ASSERT_EQ(minkq_scene_rebuild(a.get(), moved), MINKQ_SUCCESS) << minkq_last_error_message();
      ASSERT_EQ(minkq_scene_rebuild(b.get(), moved), MINKQ_SUCCESS) << minkq_last_error_message();
      const std::string at = what + " after rebuild at " + std::to_string(turns) + " turns";
      expect_same_pairs(created, test::Scene::edges_of(b.get()), at);
      if (flags & MINKQ_SCENE_EE) {
        const uint32_t q = MINKQ_QUERY_CANONICAL | MINKQ_QUERY_DIGEST;
        const float r = float(0.5 * reference::mean_edge_length(wrung));
        expect_same(scene_query(a.get(), MINKQ_QUERY_EE, MINKQ_MODE_BOX, r, q),
                    scene_query(b.get(), MINKQ_QUERY_EE, MINKQ_MODE_BOX, r, q), at + " EE box");
      }
    }
  }
}

TEST_F(Cuda, capacity_returns_the_exact_count_and_writes_nothing_past_the_buffer) {
  test::Device cpu("cpu"), cuda("cuda");
  const Mesh mesh = reference::random_soup(3000, seed, 0.08);
  cxx::Scene a = make_scene(cpu.get(), mesh, kBoth), b = make_scene(cuda.get(), mesh, kBoth);
  ASSERT_TRUE(a && b);
  const minkq_query_desc desc{MINKQ_QUERY_EE, MINKQ_MODE_BOX, MINKQ_QUERY_CANONICAL | MINKQ_QUERY_DIGEST,
                              float(reference::mean_edge_length(mesh))};
  const Outcome expected = scene_query(a.get(), desc.kind, desc.mode, desc.radius, desc.flags);
  ASSERT_GT(expected.count, 2u);
  minkq_query_info info{};
  EXPECT_EQ(minkq_scene_query(b.get(), &desc, nullptr, 0, MINKQ_MEMORY_HOST, &info), MINKQ_ERROR_CAPACITY);
  EXPECT_EQ(info.count, expected.count);

  const size_t capacity = size_t(expected.count) - 1, guard = 64;
  const int32_t sentinel = -7;
  std::vector<int32_t> buffer(2 * (capacity + guard), sentinel);
  EXPECT_EQ(minkq_scene_query(b.get(), &desc, buffer.data(), capacity, MINKQ_MEMORY_HOST, &info), MINKQ_ERROR_CAPACITY);
  EXPECT_EQ(info.count, expected.count);
  for (size_t i = 2 * capacity; i < buffer.size(); ++i) ASSERT_EQ(buffer[i], sentinel) << "written past capacity at " << i;

  // Exactly enough room, more than enough, and far more (the canonical sort covers the count,
  // not the capacity: sort_size.h): all pairs, nothing past the count.
  for (size_t room : {size_t(expected.count), size_t(expected.count) + guard, 100 * size_t(expected.count)}) {
    std::vector<int32_t> out(2 * (room + guard), sentinel);
    ASSERT_EQ(minkq_scene_query(b.get(), &desc, out.data(), room, MINKQ_MEMORY_HOST, &info), MINKQ_SUCCESS)
        << minkq_last_error_message();
    EXPECT_EQ(info.count, expected.count);
    EXPECT_EQ(info.digest, expected.digest);
    for (size_t i = 2 * expected.count; i < out.size(); ++i) ASSERT_EQ(out[i], sentinel) << "written past count at " << i;
    out.resize(2 * expected.count);
    expect_same_pairs(expected.pairs, out, "room " + std::to_string(room));
  }
}

TEST_F(Cuda, user_box_queries_match_cpu_for_every_shape_and_after_refit) {
  test::Device cpu("cpu"), cuda("cuda");
  test::Random rng(seed);
  auto random_boxes = [&](int n, float scale) {
    std::vector<Box> boxes(static_cast<size_t>(n));
    for (Box& b : boxes) b = rng.box(rng.vec3(0.0f, 1.0f), scale);
    return boxes;
  };
  std::vector<Box> boxes = random_boxes(4000, 0.02f);
  cxx::Bvh a = make_bvh(cpu.get(), boxes), b = make_bvh(cuda.get(), boxes);
  ASSERT_TRUE(a && b);
  const int nq = 3000;
  std::vector<Vec3> p0(nq), p1(nq), lo(nq), hi(nq);
  for (int i = 0; i < nq; ++i) {
    p0[i] = rng.vec3(0.0f, 1.0f);
    p1[i] = p0[i] + rng.vec3(-0.05f, 0.05f);
    const Box q = rng.box(p0[i], 0.03f);
    lo[i] = q.lo;
    hi[i] = q.hi;
  }
  for (int round = 0; round < 2; ++round) {
    const std::string tag = round ? " after refit" : "";
    for (float r : {0.0f, 0.01f, 0.04f}) {
      const std::string at = " r=" + std::to_string(r) + tag;
      for (minkq_mode mode : {MINKQ_MODE_BOX, MINKQ_MODE_SPHERE})
        expect_same(bvh_query(a.get(), MINKQ_SHAPE_SPHERE, mode, r, p0, {}),
                    bvh_query(b.get(), MINKQ_SHAPE_SPHERE, mode, r, p0, {}), "spheres mode " + std::to_string(mode) + at);
      for (minkq_mode mode : {MINKQ_MODE_BOX, MINKQ_MODE_CAPSULE_RAY, MINKQ_MODE_CAPSULE_EXACT})
        expect_same(bvh_query(a.get(), MINKQ_SHAPE_CAPSULE, mode, r, p0, p1),
                    bvh_query(b.get(), MINKQ_SHAPE_CAPSULE, mode, r, p0, p1), "capsules mode " + std::to_string(mode) + at);
    }
    expect_same(bvh_query(a.get(), MINKQ_SHAPE_BOX, MINKQ_MODE_BOX, 0.0f, lo, hi),
                bvh_query(b.get(), MINKQ_SHAPE_BOX, MINKQ_MODE_BOX, 0.0f, lo, hi), "boxes" + tag);
    boxes = random_boxes(int(boxes.size()), 0.03f);
    ASSERT_EQ(minkq_bvh_refit(a.get(), host_buffer(boxes.data(), boxes.size())), MINKQ_SUCCESS);
    ASSERT_EQ(minkq_bvh_refit(b.get(), host_buffer(boxes.data(), boxes.size())), MINKQ_SUCCESS)
        << minkq_last_error_message();
  }
}

TEST_F(Cuda, single_box_and_tiny_scenes_match_cpu) {
  test::Device cpu("cpu"), cuda("cuda");
  for (int n : {1, 2, 3}) {
    std::vector<Box> boxes;
    for (int i = 0; i < n; ++i) boxes.push_back({{float(i), 0, 0}, {float(i) + 0.5f, 1, 1}});
    cxx::Bvh a = make_bvh(cpu.get(), boxes), b = make_bvh(cuda.get(), boxes);
    ASSERT_TRUE(a && b);
    const std::vector<Vec3> centres = {{0.25f, 0.5f, 0.5f}, {1.7f, 0.5f, 0.5f}, {9, 9, 9}};
    expect_same(bvh_query(a.get(), MINKQ_SHAPE_SPHERE, MINKQ_MODE_SPHERE, 0.3f, centres, {}),
                bvh_query(b.get(), MINKQ_SHAPE_SPHERE, MINKQ_MODE_SPHERE, 0.3f, centres, {}),
                std::to_string(n) + " boxes");
  }
}


// Count-only queries (MINKQ_QUERY_COUNT, and the capacity-0 call that sizes a buffer) count
// through the leaf filter's count-only path (PairCounter) on the device: for every kind, mode
// and filter (incident pairs dropped or kept, leaf test or not) the CPU's count and work, and
// the number of pairs the CUDA backend emits for the same query.
TEST_F(Cuda, count_only_queries_equal_cpu_counts_and_emitted_pairs_for_every_filter) {
  test::Device cpu("cpu"), cuda("cuda");
  Mesh codim = reference::twisted_sheet(40, 3.0);
  codim.tris.clear();  // explicit edges, no triangles
  const Mesh soup = reference::random_soup(3000, seed, 0.08);
  for (bool drop : {false, true}) {
    const uint32_t dropped = drop ? uint32_t(MINKQ_SCENE_DROP_INCIDENT) : 0u;
    struct Case {
      const Mesh& mesh;
      uint32_t flags;
      std::vector<ModeCase> modes;
    };
    const Case cases[] = {{soup, kBoth | dropped, std::vector<ModeCase>(std::begin(kModes), std::end(kModes))},
                          {codim, MINKQ_SCENE_VV | MINKQ_SCENE_EV | dropped,
                           std::vector<ModeCase>(std::begin(kCodimModes), std::end(kCodimModes))}};
    for (const Case& c : cases) {
      cxx::Scene a = make_scene(cpu.get(), c.mesh, c.flags), b = make_scene(cuda.get(), c.mesh, c.flags);
      ASSERT_TRUE(a && b);
      const float r = float(reference::mean_edge_length(c.mesh));
      for (const ModeCase& m : c.modes)
        for (uint32_t leaf : {0u, uint32_t(MINKQ_QUERY_LEAF_EXACT)}) {
          const std::string what = std::string(m.name) + (leaf ? " leaf_exact" : "") + (drop ? " drop_incident" : "");
          const minkq_query_desc desc{m.kind, m.mode, leaf | MINKQ_QUERY_COUNT | MINKQ_QUERY_STATS, r};
          minkq_query_info on_cpu{}, on_cuda{};
          ASSERT_EQ(minkq_scene_query(a.get(), &desc, nullptr, 0, MINKQ_MEMORY_HOST, &on_cpu), MINKQ_SUCCESS) << what;
          ASSERT_EQ(minkq_scene_query(b.get(), &desc, nullptr, 0, MINKQ_MEMORY_HOST, &on_cuda), MINKQ_SUCCESS)
              << what << ": " << minkq_last_error_message();
          EXPECT_EQ(on_cuda.count, on_cpu.count) << what;
          EXPECT_EQ(on_cuda.stats.primitive_tests, on_cpu.stats.primitive_tests) << what;
          EXPECT_EQ(on_cuda.stats.candidates, on_cpu.stats.candidates) << what;
          const Outcome emitted = scene_query(b.get(), m.kind, m.mode, r, leaf);  // sized by a capacity-0 call
          EXPECT_EQ(emitted.count, on_cpu.count) << what << " (emitted)";
          EXPECT_EQ(emitted.pairs.size(), 2 * on_cpu.count) << what << " (emitted)";
        }
    }
  }
}

}  // namespace
}  // namespace minkq
