// The C ABI's contract: bad input gets a specific status and a message naming the element,
// outputs are exact-count bounded (nothing written past the buffer), digests and canonical
// order are as documented, user-box BVHs answer every shape.
#include <gtest/gtest.h>
#include <xxhash.h>

#include <cmath>
#include <cstdlib>
#include <limits>
#include <string>

#include "capi_util.h"
#include "minkq/bvh.h"
#include "minkq/shapes.h"
#include "test_util.h"

namespace minkq {
namespace {

using test::host_buffer;

std::string message() { return minkq_last_error_message(); }

struct Fixture : ::testing::Test {
  test::Device device;
  std::vector<float> xyz = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 0.05f, 1, 0, 0.05f, 0, 1, 0.05f};
  std::vector<int32_t> tris = {0, 1, 2, 3, 4, 5};
  minkq_scene_desc desc() {
    minkq_scene_desc d{};
    d.flags = MINKQ_SCENE_VT | MINKQ_SCENE_EE | MINKQ_SCENE_DROP_INCIDENT;
    d.vertices = host_buffer(xyz.data(), xyz.size() / 3);
    d.triangles = host_buffer(tris.data(), tris.size() / 3);
    return d;
  }
  minkq_status create(const minkq_scene_desc& d) {
    minkq_scene* scene = nullptr;
    const minkq_status status = minkq_scene_create(device.get(), &d, &scene);
    if (status == MINKQ_SUCCESS) EXPECT_NE(scene, nullptr); else EXPECT_EQ(scene, nullptr);
    minkq_scene_release(scene);
    return status;
  }
};

TEST_F(Fixture, non_finite_coordinates_name_the_vertex) {
  xyz[3 * 4 + 1] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(create(desc()), MINKQ_ERROR_NON_FINITE);
  EXPECT_NE(message().find("vertex 4 has a non-finite coordinate"), std::string::npos) << message();
  xyz[3 * 4 + 1] = std::numeric_limits<float>::infinity();
  EXPECT_EQ(create(desc()), MINKQ_ERROR_NON_FINITE);
  EXPECT_NE(message().find("vertex 4"), std::string::npos);
}

TEST_F(Fixture, out_of_range_and_negative_indices_name_the_triangle) {
  tris[4] = 6;
  EXPECT_EQ(create(desc()), MINKQ_ERROR_INDEX_OUT_OF_RANGE);
  EXPECT_NE(message().find("triangle 1 references vertex 6 but the scene has 6 vertices"), std::string::npos) << message();
  tris[4] = -1;
  EXPECT_EQ(create(desc()), MINKQ_ERROR_INDEX_OUT_OF_RANGE);
  EXPECT_NE(message().find("vertex -1"), std::string::npos);
  tris[4] = 4;
  std::vector<int32_t> edges = {0, 1, 2, 9};
  minkq_scene_desc d = desc();
  d.edges = host_buffer(edges.data(), 2);
  EXPECT_EQ(create(d), MINKQ_ERROR_INDEX_OUT_OF_RANGE);
  EXPECT_NE(message().find("edge 1 references vertex 9"), std::string::npos) << message();
}

TEST_F(Fixture, null_pointers_strides_flags_and_sizes_are_rejected) {
  minkq_scene_desc d = desc();
  d.vertices.data = nullptr;
  EXPECT_EQ(create(d), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(message().find("vertices.data is NULL but vertices.count is 6"), std::string::npos) << message();
  d = desc();
  d.triangles.byte_stride = 8;
  EXPECT_EQ(create(d), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(message().find("triangles.byte_stride 8"), std::string::npos) << message();
  d = desc();
  d.flags = MINKQ_SCENE_DROP_INCIDENT;
  EXPECT_EQ(create(d), MINKQ_ERROR_INVALID_ARGUMENT);
  d = desc();
  d.flags |= 64;
  EXPECT_EQ(create(d), MINKQ_ERROR_INVALID_ARGUMENT);
  d = desc();
  d.vertices.count = size_t(1) << 40;
  EXPECT_EQ(create(d), MINKQ_ERROR_SIZE_OVERFLOW);
  d = desc();
  d.vertices.count = 1000;
  d.vertices.byte_stride = std::numeric_limits<size_t>::max() / 10;
  EXPECT_EQ(create(d), MINKQ_ERROR_SIZE_OVERFLOW);
  d = desc();
  d.vertices.memory = MINKQ_MEMORY_DEVICE;
  EXPECT_EQ(create(d), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(message().find("device memory"), std::string::npos);
  EXPECT_EQ(minkq_scene_create(device.get(), nullptr, nullptr), MINKQ_ERROR_INVALID_ARGUMENT);
  minkq_scene* scene = nullptr;
  EXPECT_EQ(minkq_scene_create(nullptr, &d, &scene), MINKQ_ERROR_INVALID_ARGUMENT);
}

// A tree over n elements links its nodes by (node << 1) | side in an int32 (bvh.h), so
// vertices, triangles, edges and boxes stop at kMaxTreePrimitives = 2^30 + 1. One more is
// refused with the count and the limit named, before the (much smaller) buffer is read: a
// check that ran after the read would read past it.
TEST_F(Fixture, counts_past_the_tree_limit_are_refused_before_reading) {
  static_assert(kMaxTreePrimitives == (int64_t(1) << 30) + 1, "the limit minkq.h documents");
  const size_t over = size_t(kMaxTreePrimitives) + 1;
  const std::string limit = "exceeds the limit of " + std::to_string(kMaxTreePrimitives);
  for (const char* field : {"vertices", "triangles", "edges"}) {
    std::vector<int32_t> edges = {0, 1, 1, 2};
    minkq_scene_desc d = desc();
    d.edges = host_buffer(edges.data(), 2);
    minkq_buffer& buffer = std::string(field) == "vertices" ? d.vertices
                           : std::string(field) == "triangles" ? d.triangles : d.edges;
    buffer.count = over;
    EXPECT_EQ(create(d), MINKQ_ERROR_SIZE_OVERFLOW) << field;
    EXPECT_NE(message().find(std::string(field) + ".count " + std::to_string(over) + " " + limit), std::string::npos)
        << message();
  }
  std::vector<float> boxes = {0, 0, 0, 1, 1, 1};
  minkq_bvh* bvh = nullptr;
  minkq_buffer box_buffer = host_buffer(boxes.data(), 1, 24);
  box_buffer.count = over;
  EXPECT_EQ(minkq_bvh_create(device.get(), box_buffer, &bvh), MINKQ_ERROR_SIZE_OVERFLOW);
  EXPECT_EQ(bvh, nullptr);
  EXPECT_NE(message().find("boxes.count " + std::to_string(over) + " " + limit), std::string::npos) << message();
  // Rebuilds keep the count their scene or bvh was created with, so they never reach a tree
  // past the limit: a larger count is refused before it is read too.
  box_buffer.count = 1;
  ASSERT_EQ(minkq_bvh_create(device.get(), box_buffer, &bvh), MINKQ_SUCCESS) << message();
  box_buffer.count = over;
  EXPECT_EQ(minkq_bvh_rebuild(bvh, box_buffer), MINKQ_ERROR_INVALID_ARGUMENT);
  minkq_bvh_release(bvh);
  test::Scene scene(device.get(), reference::Mesh{xyz, tris, {}}, MINKQ_SCENE_VT);
  minkq_buffer vertices = desc().vertices;
  vertices.count = over;
  EXPECT_EQ(minkq_scene_rebuild(scene.get(), vertices), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(message().find("rebuild with " + std::to_string(over) + " vertices"), std::string::npos) << message();
}

TEST_F(Fixture, bad_radius_mode_kind_and_flags_are_rejected) {
  test::Scene scene(device.get(), reference::Mesh{xyz, tris, {}}, MINKQ_SCENE_VT);
  minkq_query_info info{};
  auto run = [&](minkq_query_desc q) { return minkq_scene_query(scene.get(), &q, nullptr, 0, MINKQ_MEMORY_HOST, &info); };
  EXPECT_EQ(run({MINKQ_QUERY_VT, MINKQ_MODE_SPHERE, 0, -1.0f}), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(message().find("radius -1 is negative"), std::string::npos) << message();
  EXPECT_EQ(run({MINKQ_QUERY_VT, MINKQ_MODE_SPHERE, 0, std::nanf("")}), MINKQ_ERROR_NON_FINITE);
  EXPECT_EQ(run({MINKQ_QUERY_VT, MINKQ_MODE_SPHERE, 0, INFINITY}), MINKQ_ERROR_NON_FINITE);
  EXPECT_EQ(run({MINKQ_QUERY_VT, minkq_mode(7), 0, 1.0f}), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(run({minkq_query_kind(5), MINKQ_MODE_BOX, 0, 1.0f}), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(run({MINKQ_QUERY_VT, MINKQ_MODE_BOX, 1u << 9, 1.0f}), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(run({MINKQ_QUERY_EE, MINKQ_MODE_BOX, 0, 1.0f}), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(message().find("without MINKQ_SCENE_EE"), std::string::npos) << message();
  EXPECT_EQ(minkq_scene_edge_count(scene.get()), 0u);  // a VT-only scene derives no edges
  test::Scene both(device.get(), reference::Mesh{xyz, tris, {}}, MINKQ_SCENE_VT | MINKQ_SCENE_EE);
  minkq_query_desc sphere_ee{MINKQ_QUERY_EE, MINKQ_MODE_SPHERE, 0, 1.0f};
  EXPECT_EQ(minkq_scene_query(both.get(), &sphere_ee, nullptr, 0, MINKQ_MEMORY_HOST, &info), MINKQ_ERROR_INVALID_ARGUMENT);
  minkq_query_desc ok{MINKQ_QUERY_VT, MINKQ_MODE_BOX, 0, 1.0f};
  EXPECT_EQ(minkq_scene_query(both.get(), &ok, nullptr, 0, MINKQ_MEMORY_HOST, nullptr), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(minkq_scene_query(both.get(), &ok, nullptr, 5, MINKQ_MEMORY_HOST, &info), MINKQ_ERROR_INVALID_ARGUMENT);
}

TEST_F(Fixture, vt_ee_call_checks_each_query_and_buffer_by_name) {
  test::Scene vt_only(device.get(), reference::Mesh{xyz, tris, {}}, MINKQ_SCENE_VT);
  test::Scene both(device.get(), reference::Mesh{xyz, tris, {}}, MINKQ_SCENE_VT | MINKQ_SCENE_EE);
  const minkq_query_desc vt{MINKQ_QUERY_VT, MINKQ_MODE_BOX, 0, 1.0f}, ee{MINKQ_QUERY_EE, MINKQ_MODE_BOX, 0, 1.0f};
  std::vector<int32_t> a(64), b(64);
  minkq_query_info vt_info{}, ee_info{};
  auto run = [&](minkq_scene* scene, const minkq_query_desc* v, const minkq_query_desc* e, int32_t* vp, size_t vc,
                 int32_t* ep, size_t ec, minkq_query_info* vi, minkq_query_info* ei) {
    return minkq_scene_query_vt_ee(scene, v, e, vp, vc, ep, ec, MINKQ_MEMORY_HOST, vi, ei);
  };
  auto expect = [&](minkq_status status, minkq_status expected, const std::string& words) {
    EXPECT_EQ(status, expected) << words;
    EXPECT_NE(message().find(words), std::string::npos) << message();
  };
  expect(run(vt_only.get(), &vt, &ee, a.data(), 32, b.data(), 32, &vt_info, &ee_info), MINKQ_ERROR_INVALID_ARGUMENT,
         "EE query on a scene created without MINKQ_SCENE_EE");
  expect(run(nullptr, &vt, &ee, a.data(), 32, b.data(), 32, &vt_info, &ee_info), MINKQ_ERROR_INVALID_ARGUMENT,
         "scene is NULL");
  expect(run(both.get(), nullptr, &ee, a.data(), 32, b.data(), 32, &vt_info, &ee_info), MINKQ_ERROR_INVALID_ARGUMENT,
         "vt_query is NULL");
  expect(run(both.get(), &ee, &vt, a.data(), 32, b.data(), 32, &vt_info, &ee_info), MINKQ_ERROR_INVALID_ARGUMENT,
         "vt_query->kind is not MINKQ_QUERY_VT");
  expect(run(both.get(), &vt, &vt, a.data(), 32, b.data(), 32, &vt_info, &ee_info), MINKQ_ERROR_INVALID_ARGUMENT,
         "ee_query->kind is not MINKQ_QUERY_EE");
  const minkq_query_desc ee_sphere{MINKQ_QUERY_EE, MINKQ_MODE_SPHERE, 0, 1.0f};
  expect(run(both.get(), &vt, &ee_sphere, a.data(), 32, b.data(), 32, &vt_info, &ee_info),
         MINKQ_ERROR_INVALID_ARGUMENT, "sphere mode needs point queries");
  const minkq_query_desc ee_bad_radius{MINKQ_QUERY_EE, MINKQ_MODE_BOX, 0, -2.0f};
  expect(run(both.get(), &vt, &ee_bad_radius, a.data(), 32, b.data(), 32, &vt_info, &ee_info),
         MINKQ_ERROR_INVALID_ARGUMENT, "radius -2 is negative");
  const minkq_query_desc vt_bad_flags{MINKQ_QUERY_VT, MINKQ_MODE_BOX, 1u << 9, 1.0f};
  expect(run(both.get(), &vt_bad_flags, &ee, a.data(), 32, b.data(), 32, &vt_info, &ee_info),
         MINKQ_ERROR_INVALID_ARGUMENT, "vt_query->flags has unknown bits");
  expect(run(both.get(), &vt, &ee, nullptr, 3, b.data(), 32, &vt_info, &ee_info), MINKQ_ERROR_INVALID_ARGUMENT,
         "vt_pairs is NULL but vt_capacity is 3");
  expect(run(both.get(), &vt, &ee, a.data(), 32, nullptr, 4, &vt_info, &ee_info), MINKQ_ERROR_INVALID_ARGUMENT,
         "ee_pairs is NULL but ee_capacity is 4");
  expect(run(both.get(), &vt, &ee, a.data(), 32, b.data(), 32, nullptr, &ee_info), MINKQ_ERROR_INVALID_ARGUMENT,
         "vt_info is NULL");
  expect(run(both.get(), &vt, &ee, a.data(), 32, b.data(), 32, &vt_info, nullptr), MINKQ_ERROR_INVALID_ARGUMENT,
         "ee_info is NULL");
  expect(run(both.get(), &vt, &ee, a.data(), 32, b.data(), 32, &vt_info, &vt_info), MINKQ_ERROR_INVALID_ARGUMENT,
         "vt_info and ee_info are the same");
  expect(run(both.get(), &vt, &ee, a.data(), 32, b.data(), SIZE_MAX, &vt_info, &ee_info), MINKQ_ERROR_SIZE_OVERFLOW,
         "ee_capacity");
  expect(minkq_scene_query_vt_ee(both.get(), &vt, &ee, a.data(), 32, b.data(), 32, MINKQ_MEMORY_DEVICE, &vt_info,
                                 &ee_info),
         MINKQ_ERROR_INVALID_ARGUMENT, "vt_pairs is in device memory but the device is cpu");
  expect(minkq_scene_query_vt_ee_result(both.get(), &vt, &ee, nullptr, nullptr), MINKQ_ERROR_INVALID_ARGUMENT,
         "vt_result is NULL");
  EXPECT_EQ(run(both.get(), &vt, &ee, a.data(), 32, b.data(), 32, &vt_info, &ee_info), MINKQ_SUCCESS) << message();
  EXPECT_GT(vt_info.count, 0u);
  EXPECT_GT(ee_info.count, 0u);
}

// The backend's store holds the scene's only copy of its topology: counts and edges come back
// from it, on the CPU and on a CUDA device where one exists.
TEST_F(Fixture, scene_edges_come_back_derived_in_lexicographic_order_or_as_given) {
  std::vector<std::string> specs = {"cpu"};
  if (minkq_cuda_device_count() > 0) specs.push_back("cuda");
  const std::vector<int32_t> derived = {0, 1, 0, 2, 1, 2, 3, 4, 3, 5, 4, 5};
  const std::vector<int32_t> given = {2, 0, 5, 4, 1, 3};
  for (const std::string& spec : specs) {
    test::Device dev(spec.c_str());
    for (const bool give : {false, true})
      for (const uint32_t flags : {uint32_t(MINKQ_SCENE_EE), uint32_t(MINKQ_SCENE_VT), uint32_t(MINKQ_SCENE_VT | MINKQ_SCENE_EE)}) {
        minkq_scene_desc d = desc();
        d.flags = flags;
        if (give) d.edges = host_buffer(given.data(), given.size() / 2);
        minkq_scene* scene = nullptr;
        ASSERT_EQ(minkq_scene_create(dev.get(), &d, &scene), MINKQ_SUCCESS) << message();
        const std::vector<int32_t> expected = give ? given : (flags & MINKQ_SCENE_EE) ? derived : std::vector<int32_t>{};
        EXPECT_EQ(minkq_scene_triangle_count(scene), 2u);
        ASSERT_EQ(minkq_scene_edge_count(scene), expected.size() / 2);
        std::vector<int32_t> edges(expected.size() + 2, -5);
        EXPECT_EQ(minkq_scene_edges(scene, edges.data(), expected.size() / 2), MINKQ_SUCCESS) << message();
        EXPECT_EQ(std::vector<int32_t>(edges.begin(), edges.end() - 2), expected) << spec << " flags " << flags;
        EXPECT_EQ(edges[expected.size()], -5);  // nothing past the edges
        if (!expected.empty()) {
          EXPECT_EQ(minkq_scene_edges(scene, edges.data(), expected.size() / 2 - 1), MINKQ_ERROR_CAPACITY);
          EXPECT_NE(message().find("the scene has " + std::to_string(expected.size() / 2) + " edges"), std::string::npos)
              << message();
        }
        minkq_scene_release(scene);
      }
  }
}

// A scene with an edge tree keeps its edges only in the tree's leaf order, and a rebuild
// reorders that; minkq_scene_edges gives them back by id all the same, derived or given (here in
// a shuffled order), and the EE pairs of a rebuilt scene are a new scene's at those positions.
TEST_F(Fixture, scene_edges_keep_their_numbering_over_refits_and_rebuilds) {
  std::vector<std::string> specs = {"cpu"};
  if (minkq_cuda_device_count() > 0) specs.push_back("cuda");
  const reference::Mesh flat = reference::twisted_sheet(30, 0.0);
  std::vector<int32_t> given = reference::derive_edges(flat.tris);
  test::Random rng(test::fresh_seed());
  for (int e = int(given.size() / 2) - 1; e > 0; --e) {  // a shuffle of the edges and of each one's ends
    const int f = rng.integer(0, e);
    std::swap(given[2 * e], given[2 * f]);
    std::swap(given[2 * e + 1], given[2 * f + 1]);
    if (rng.integer(0, 1)) std::swap(given[2 * e], given[2 * e + 1]);
  }
  for (const std::string& spec : specs) {
    test::Device dev(spec.c_str());
    for (const bool give : {false, true})
      for (const uint32_t flags : {uint32_t(MINKQ_SCENE_EE), uint32_t(MINKQ_SCENE_VT | MINKQ_SCENE_EE)}) {
        minkq_scene_desc d{};
        d.flags = flags;
        d.vertices = host_buffer(flat.xyz.data(), flat.vertex_count());
        d.triangles = host_buffer(flat.tris.data(), flat.triangle_count());
        if (give) d.edges = host_buffer(given.data(), given.size() / 2);
        cxx::Scene scene = test::new_scene(dev.get(), d);
        ASSERT_TRUE(scene);
        const std::vector<int32_t> created = test::Scene::edges_of(scene.get());
        EXPECT_EQ(created, give ? given : reference::derive_edges(flat.tris));  // the library's numbering
        const std::string what = spec + (give ? " given" : " derived") + " flags " + std::to_string(flags);
        for (double turns : {3.0, -2.0}) {
          const reference::Mesh wrung = reference::twisted_sheet(30, turns);
          const minkq_buffer moved = host_buffer(wrung.xyz.data(), wrung.vertex_count());
          ASSERT_EQ(minkq_scene_refit(scene.get(), moved), MINKQ_SUCCESS) << message();
          EXPECT_EQ(test::Scene::edges_of(scene.get()), created) << what << " after a refit to " << turns << " turns";
          ASSERT_EQ(minkq_scene_rebuild(scene.get(), moved), MINKQ_SUCCESS) << message();
          EXPECT_EQ(test::Scene::edges_of(scene.get()), created) << what << " after a rebuild at " << turns << " turns";
          d.vertices = moved;
          cxx::Scene fresh = test::new_scene(dev.get(), d);
          ASSERT_TRUE(fresh);
          const float r = float(0.5 * reference::mean_edge_length(wrung));
          uint64_t rebuilt_digest = 0, made_digest = 0;
          const test::Pairs rebuilt =
              test::Scene::query_pairs(scene.get(), MINKQ_QUERY_EE, MINKQ_MODE_BOX, r, 0, &rebuilt_digest);
          const test::Pairs made = test::Scene::query_pairs(fresh.get(), MINKQ_QUERY_EE, MINKQ_MODE_BOX, r, 0, &made_digest);
          EXPECT_FALSE(made.empty()) << what;
          EXPECT_EQ(rebuilt, made) << what << " EE pairs after a rebuild at " << turns << " turns";
          EXPECT_EQ(rebuilt_digest, made_digest) << what;
        }
      }
  }
}

TEST_F(Fixture, capacity_reports_the_exact_count_and_writes_nothing_past_the_buffer) {
  test::Scene scene(device.get(), reference::Mesh{xyz, tris, {}}, MINKQ_SCENE_VT | MINKQ_SCENE_EE);
  const test::Pairs all = scene.query(MINKQ_QUERY_EE, MINKQ_MODE_BOX, 0.1f);
  ASSERT_GT(all.size(), 3u);
  minkq_query_desc q{MINKQ_QUERY_EE, MINKQ_MODE_BOX, MINKQ_QUERY_CANONICAL, 0.1f};
  for (size_t capacity : {size_t(0), size_t(1), all.size() - 1}) {
    std::vector<int32_t> buffer(2 * capacity + 16, -77);
    minkq_query_info info{};
    EXPECT_EQ(minkq_scene_query(scene.get(), &q, buffer.data(), capacity, MINKQ_MEMORY_HOST, &info), MINKQ_ERROR_CAPACITY);
    EXPECT_EQ(info.count, all.size());
    EXPECT_NE(message().find(std::to_string(all.size()) + " pairs found"), std::string::npos) << message();
    for (size_t i = 2 * capacity; i < buffer.size(); ++i) ASSERT_EQ(buffer[i], -77) << "written past the buffer";
  }
  std::vector<int32_t> exact(2 * all.size());
  minkq_query_info info{};
  EXPECT_EQ(minkq_scene_query(scene.get(), &q, exact.data(), all.size(), MINKQ_MEMORY_HOST, &info), MINKQ_SUCCESS);
  EXPECT_EQ(info.count, all.size());
}

TEST_F(Fixture, digest_is_xxh64_of_the_canonical_little_endian_pairs) {
  test::Scene scene(device.get(), reference::random_soup(300, 7, 1.0), MINKQ_SCENE_VT | MINKQ_SCENE_EE);
  uint64_t digest = 0;
  const test::Pairs pairs = scene.query(MINKQ_QUERY_EE, MINKQ_MODE_CAPSULE_RAY, 0.05f, 0, &digest);
  ASSERT_FALSE(pairs.empty());
  EXPECT_TRUE(std::is_sorted(pairs.begin(), pairs.end()));
  std::vector<int32_t> flat;
  for (const auto& [a, b] : pairs) { flat.push_back(a); flat.push_back(b); }
  EXPECT_EQ(digest, XXH64(flat.data(), flat.size() * 4, 0));
  // Without CANONICAL the same set comes back (in the backend's deterministic order).
  minkq_query_desc q{MINKQ_QUERY_EE, MINKQ_MODE_CAPSULE_RAY, 0, 0.05f};
  std::vector<int32_t> raw(2 * pairs.size());
  minkq_query_info info{};
  ASSERT_EQ(minkq_scene_query(scene.get(), &q, raw.data(), pairs.size(), MINKQ_MEMORY_HOST, &info), MINKQ_SUCCESS);
  test::Pairs unordered;
  for (size_t i = 0; i < pairs.size(); ++i) unordered.push_back({raw[2 * i], raw[2 * i + 1]});
  std::sort(unordered.begin(), unordered.end());
  EXPECT_EQ(unordered, pairs);
}

TEST_F(Fixture, failed_refit_keeps_the_previous_positions) {
  test::Scene scene(device.get(), reference::Mesh{xyz, tris, {}}, MINKQ_SCENE_VT | MINKQ_SCENE_EE);
  const test::Pairs before = scene.query(MINKQ_QUERY_VT, MINKQ_MODE_SPHERE, 0.1f);
  std::vector<float> moved = xyz;
  moved[5] = std::numeric_limits<float>::infinity();
  EXPECT_EQ(minkq_scene_refit(scene.get(), host_buffer(moved.data(), 6)), MINKQ_ERROR_NON_FINITE);
  EXPECT_NE(message().find("vertex 1"), std::string::npos) << message();
  EXPECT_EQ(minkq_scene_refit(scene.get(), host_buffer(moved.data(), 5)), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(message().find("refit with 5 vertices but the scene has 6"), std::string::npos) << message();
  EXPECT_EQ(scene.query(MINKQ_QUERY_VT, MINKQ_MODE_SPHERE, 0.1f), before);
}

// The backends scan large inputs in parallel blocks: the vertex named is still the first bad
// one, whichever block finds one first, for creation, blocking and stream-ordered refits, in
// float and double and through a stride.
TEST(CapiLarge, non_finite_coordinates_of_many_vertices_name_the_first) {
  test::Device device;
  const reference::Mesh mesh = reference::twisted_sheet(300, 1.0);
  const int64_t n = int64_t(mesh.vertex_count());
  ASSERT_GT(n, 80000);
  for (const bool float64 : {false, true}) {
    for (const size_t stride_floats : {size_t(3), size_t(5)}) {
      SCOPED_TRACE(std::string(float64 ? "float64" : "float32") + ", stride " + std::to_string(stride_floats));
      std::vector<double> xyz(size_t(n) * stride_floats, 0.0);
      for (int64_t v = 0; v < n; ++v)
        for (int k = 0; k < 3; ++k) xyz[size_t(v) * stride_floats + size_t(k)] = mesh.xyz[size_t(3 * v + k)];
      std::vector<float> xyz_f(xyz.begin(), xyz.end());
      auto buffer = [&]() {
        minkq_buffer b{};
        b.data = float64 ? static_cast<void*>(xyz.data()) : static_cast<void*>(xyz_f.data());
        b.byte_stride = stride_floats * (float64 ? sizeof(double) : sizeof(float));
        b.count = size_t(n);
        b.memory = MINKQ_MEMORY_HOST;
        return b;
      };
      auto spoil = [&](int64_t v, int k, double value) {
        xyz[size_t(v) * stride_floats + size_t(k)] = value;
        xyz_f[size_t(v) * stride_floats + size_t(k)] = float(value);
      };
      minkq_scene_desc d{};
      d.flags = MINKQ_SCENE_VT | MINKQ_SCENE_EE | (float64 ? uint32_t(MINKQ_SCENE_FLOAT64) : 0u);
      d.vertices = buffer();
      d.triangles = host_buffer(mesh.tris.data(), mesh.triangle_count());
      minkq_scene* raw = nullptr;
      ASSERT_EQ(minkq_scene_create(device.get(), &d, &raw), MINKQ_SUCCESS) << message();
      const cxx::Scene scene(raw);
      ASSERT_EQ(minkq_scene_reserve(raw, MINKQ_RESERVE_REFIT, 0), MINKQ_SUCCESS) << message();
      spoil(n - 1, 2, std::numeric_limits<double>::quiet_NaN());
      spoil(70001, 0, std::numeric_limits<double>::infinity());
      spoil(40000, 1, std::numeric_limits<double>::quiet_NaN());
      spoil(40001, 1, -std::numeric_limits<double>::infinity());
      EXPECT_EQ(minkq_scene_refit(raw, buffer()), MINKQ_ERROR_NON_FINITE);
      EXPECT_NE(message().find("vertex 40000 "), std::string::npos) << message();
      EXPECT_EQ(minkq_scene_rebuild(raw, buffer()), MINKQ_ERROR_NON_FINITE);
      EXPECT_NE(message().find("vertex 40000 "), std::string::npos) << message();
      ASSERT_EQ(minkq_scene_refit_async(raw, buffer(), nullptr), MINKQ_SUCCESS) << message();
      EXPECT_EQ(minkq_scene_async_status(raw, nullptr), MINKQ_ERROR_NON_FINITE);
      EXPECT_NE(message().find("vertex 40000 "), std::string::npos) << message();
      d.vertices = buffer();
      minkq_scene* bad = nullptr;
      EXPECT_EQ(minkq_scene_create(device.get(), &d, &bad), MINKQ_ERROR_NON_FINITE);
      EXPECT_EQ(bad, nullptr);
      EXPECT_NE(message().find("vertex 40000 "), std::string::npos) << message();
    }
  }
}

TEST_F(Fixture, failed_rebuild_keeps_the_previous_positions_and_growth_checks_its_arguments) {
  test::Scene scene(device.get(), reference::Mesh{xyz, tris, {}}, MINKQ_SCENE_VT | MINKQ_SCENE_EE);
  const test::Pairs before = scene.query(MINKQ_QUERY_EE, MINKQ_MODE_BOX, 0.1f);
  std::vector<float> moved = xyz;
  moved[7] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(minkq_scene_rebuild(scene.get(), host_buffer(moved.data(), 6)), MINKQ_ERROR_NON_FINITE);
  EXPECT_NE(message().find("vertex 2 has a non-finite coordinate"), std::string::npos) << message();
  EXPECT_EQ(minkq_scene_rebuild(scene.get(), host_buffer(moved.data(), 5)), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(message().find("rebuild with 5 vertices but the scene has 6"), std::string::npos) << message();
  EXPECT_EQ(minkq_scene_rebuild(nullptr, host_buffer(xyz.data(), 6)), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(message().find("scene is NULL"), std::string::npos) << message();
  EXPECT_EQ(minkq_scene_refit(nullptr, host_buffer(xyz.data(), 6)), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(message().find("scene is NULL"), std::string::npos) << message();
  EXPECT_EQ(minkq_scene_rebuild(scene.get(), host_buffer(nullptr, 6)), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(scene.query(MINKQ_QUERY_EE, MINKQ_MODE_BOX, 0.1f), before);
  double growth = 0.0;
  EXPECT_EQ(minkq_scene_tree_growth(scene.get(), nullptr), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(message().find("out_growth is NULL"), std::string::npos) << message();
  EXPECT_EQ(minkq_scene_tree_growth(nullptr, &growth), MINKQ_ERROR_INVALID_ARGUMENT);
  ASSERT_EQ(minkq_scene_tree_growth(scene.get(), &growth), MINKQ_SUCCESS);
  EXPECT_EQ(growth, 1.0);
}

TEST(Devices, specs_versions_and_missing_cuda) {
  minkq_device* device = nullptr;
  EXPECT_EQ(minkq_device_create("gpu", &device), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(message().find("unknown device spec \"gpu\""), std::string::npos);
  EXPECT_EQ(minkq_device_create("cuda:x", &device), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(minkq_device_create(nullptr, &device), MINKQ_ERROR_INVALID_ARGUMENT);
  ASSERT_EQ(minkq_device_create("auto", &device), MINKQ_SUCCESS);
  EXPECT_EQ(minkq_device_backend(device), minkq_cuda_device_count() > 0 ? MINKQ_BACKEND_CUDA : MINKQ_BACKEND_CPU);
  minkq_device_release(device);
  if (minkq_cuda_device_count() == 0) {
    EXPECT_EQ(minkq_device_create("cuda", &device), MINKQ_ERROR_UNSUPPORTED);
    EXPECT_FALSE(message().empty());
    EXPECT_EQ(device, nullptr);
  }
  EXPECT_EQ(minkq_device_create("cuda:999", &device), MINKQ_ERROR_UNSUPPORTED);
  EXPECT_EQ(minkq_abi_version(), uint32_t(MINKQ_ABI_VERSION));
  EXPECT_EQ(minkq_version(), uint32_t(MINKQ_VERSION_MAJOR * 10000 + MINKQ_VERSION_MINOR * 100 + MINKQ_VERSION_PATCH));
  EXPECT_STREQ(minkq_status_name(MINKQ_ERROR_CAPACITY), "MINKQ_ERROR_CAPACITY");
}

// A CPU device names its instruction-set level: MINKQ_CPU_ISA's when set (tests/CMakeLists.txt
// runs the C API suites at each level), and a word that is no level fails device creation
// with a message naming the variable, the device left null.
TEST(Devices, cpu_name_says_its_level_and_bad_levels_are_refused) {
  const char* asked = std::getenv("MINKQ_CPU_ISA");
  const std::string level = asked ? asked : "";
  minkq_device* device = nullptr;
  ASSERT_EQ(minkq_device_create("cpu", &device), MINKQ_SUCCESS) << message();
  const std::string name = minkq_device_name(device);
  minkq_device_release(device);
  if (!level.empty()) {
    EXPECT_EQ(name.substr(name.size() - level.size() - 3), ", " + level + ")") << name;
  } else {
    const bool known = name.find(", sse2)") != std::string::npos || name.find(", avx2)") != std::string::npos ||
                       name.find(", avx512)") != std::string::npos;
    EXPECT_TRUE(known) << name;
  }
  ASSERT_EQ(setenv("MINKQ_CPU_ISA", "sse3", 1), 0);
  device = nullptr;
  EXPECT_EQ(minkq_device_create("cpu", &device), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(message().find("MINKQ_CPU_ISA=sse3: expected one of sse2, avx2, avx512"), std::string::npos) << message();
  EXPECT_EQ(device, nullptr);
  if (asked) setenv("MINKQ_CPU_ISA", asked, 1); else unsetenv("MINKQ_CPU_ISA");
}

// A BVH over user boxes answers sphere, capsule and box queries; each set equals the node test
// applied to every box (the definition), and contains every exact overlap.
TEST(UserBvh, every_shape_matches_its_definition) {
  test::Random rng(test::fresh_seed());
  test::Device device;
  std::vector<Box> boxes(800);
  for (Box& b : boxes) b = rng.box(rng.vec3(0, 10), 0.3f);
  minkq_bvh* bvh = nullptr;
  ASSERT_EQ(minkq_bvh_create(device.get(), host_buffer(boxes.data(), boxes.size()), &bvh), MINKQ_SUCCESS);
  std::vector<Vec3> a(300), b(300);
  for (size_t i = 0; i < a.size(); ++i) { a[i] = rng.vec3(0, 10); b[i] = a[i] + rng.vec3(-1, 1); }
  const float r = 0.2f;
  auto run = [&](minkq_shape shape, minkq_mode mode) {
    minkq_bvh_query_desc q{shape, mode, MINKQ_QUERY_CANONICAL, shape == MINKQ_SHAPE_BOX ? 0.0f : r,
                           host_buffer(a.data(), a.size()),
                           shape == MINKQ_SHAPE_SPHERE ? host_buffer(nullptr, 0) : host_buffer(b.data(), b.size())};
    minkq_query_info info{};
    std::vector<int32_t> out(2 * 200000);
    EXPECT_EQ(minkq_bvh_query(bvh, &q, out.data(), 200000, MINKQ_MEMORY_HOST, &info), MINKQ_SUCCESS) << message();
    test::Pairs pairs;
    for (size_t i = 0; i < info.count; ++i) pairs.push_back({out[2 * i], out[2 * i + 1]});
    return pairs;
  };
  auto definition = [&](auto shape_type, bool segments, float radius) {
    using Shape = decltype(shape_type);
    test::Pairs pairs;
    for (int32_t q = 0; q < int32_t(a.size()); ++q) {
      const Shape shape = Shape::from({a[q], segments ? b[q] : a[q], radius});
      for (int32_t p = 0; p < int32_t(boxes.size()); ++p)
        if (shape.overlaps(boxes[p])) pairs.push_back({q, p});
    }
    return pairs;
  };
  EXPECT_EQ(run(MINKQ_SHAPE_SPHERE, MINKQ_MODE_BOX), definition(BoxShape{}, false, r));
  EXPECT_EQ(run(MINKQ_SHAPE_SPHERE, MINKQ_MODE_SPHERE), definition(SphereShape{}, false, r));
  EXPECT_EQ(run(MINKQ_SHAPE_CAPSULE, MINKQ_MODE_BOX), definition(BoxShape{}, true, r));
  EXPECT_EQ(run(MINKQ_SHAPE_CAPSULE, MINKQ_MODE_CAPSULE_RAY), definition(CapsuleRayShape{}, true, r));
  EXPECT_EQ(run(MINKQ_SHAPE_CAPSULE, MINKQ_MODE_CAPSULE_EXACT), definition(CapsuleExactShape{}, true, r));
  EXPECT_EQ(run(MINKQ_SHAPE_BOX, MINKQ_MODE_BOX), definition(BoxShape{}, true, 0.0f));
  // Refit with moved boxes matches a fresh definition.
  for (Box& box : boxes) { const Vec3 shift = rng.vec3(-0.5f, 0.5f); box = {box.lo + shift, box.hi + shift}; }
  ASSERT_EQ(minkq_bvh_refit(bvh, host_buffer(boxes.data(), boxes.size())), MINKQ_SUCCESS);
  EXPECT_EQ(run(MINKQ_SHAPE_CAPSULE, MINKQ_MODE_CAPSULE_EXACT), definition(CapsuleExactShape{}, true, r));
  // Rebuild: the same pairs from a fresh tree, whose growth starts again at 1.
  double growth = 0.0;
  ASSERT_EQ(minkq_bvh_tree_growth(bvh, &growth), MINKQ_SUCCESS);
  EXPECT_GT(growth, 0.0);
  ASSERT_EQ(minkq_bvh_rebuild(bvh, host_buffer(boxes.data(), boxes.size())), MINKQ_SUCCESS) << message();
  ASSERT_EQ(minkq_bvh_tree_growth(bvh, &growth), MINKQ_SUCCESS);
  EXPECT_EQ(growth, 1.0);
  EXPECT_EQ(run(MINKQ_SHAPE_CAPSULE, MINKQ_MODE_CAPSULE_EXACT), definition(CapsuleExactShape{}, true, r));
  EXPECT_EQ(run(MINKQ_SHAPE_BOX, MINKQ_MODE_BOX), definition(BoxShape{}, true, 0.0f));
  // Bad input.
  boxes[3].lo.x = boxes[3].hi.x + 1;
  EXPECT_EQ(minkq_bvh_refit(bvh, host_buffer(boxes.data(), boxes.size())), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(message().find("box 3 has lo > hi"), std::string::npos);
  EXPECT_EQ(minkq_bvh_rebuild(bvh, host_buffer(boxes.data(), boxes.size())), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(message().find("box 3 has lo > hi"), std::string::npos);
  EXPECT_EQ(minkq_bvh_rebuild(bvh, host_buffer(boxes.data(), boxes.size() - 1)), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(message().find("rebuild with 799 boxes but the bvh has 800"), std::string::npos) << message();
  EXPECT_EQ(minkq_bvh_tree_growth(bvh, nullptr), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(minkq_bvh_tree_growth(nullptr, &growth), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(message().find("bvh is NULL"), std::string::npos);
  EXPECT_EQ(minkq_bvh_refit(nullptr, host_buffer(boxes.data(), boxes.size())), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(minkq_bvh_rebuild(nullptr, host_buffer(boxes.data(), boxes.size())), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(message().find("bvh is NULL"), std::string::npos);
  minkq_bvh_query_desc bad{MINKQ_SHAPE_CAPSULE, MINKQ_MODE_SPHERE, 0, r, host_buffer(a.data(), a.size()),
                           host_buffer(b.data(), b.size())};
  minkq_query_info info{};
  EXPECT_EQ(minkq_bvh_query(bvh, &bad, nullptr, 0, MINKQ_MEMORY_HOST, &info), MINKQ_ERROR_INVALID_ARGUMENT);
  bad.mode = MINKQ_MODE_BOX;
  bad.flags = MINKQ_QUERY_LEAF_EXACT;
  EXPECT_EQ(minkq_bvh_query(bvh, &bad, nullptr, 0, MINKQ_MEMORY_HOST, &info), MINKQ_ERROR_INVALID_ARGUMENT);
  bad.flags = 0;
  bad.second.count = 5;
  EXPECT_EQ(minkq_bvh_query(bvh, &bad, nullptr, 0, MINKQ_MEMORY_HOST, &info), MINKQ_ERROR_INVALID_ARGUMENT);
  minkq_bvh_release(bvh);
}

}  // namespace
}  // namespace minkq
