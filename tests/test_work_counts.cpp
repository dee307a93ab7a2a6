// Work counters (MINKQ_QUERY_STATS): exact on scenes where every box overlaps every other,
// monotone from the box mode to the finer modes, unchanged by output options, and off by
// default. EE meets each unordered pair once.
#include <gtest/gtest.h>

#include "capi_util.h"
#include "minkq/traversal.h"
#include "test_util.h"

namespace minkq {
namespace {

constexpr uint32_t kBoth = MINKQ_SCENE_VT | MINKQ_SCENE_EE;

bool operator==(const minkq_query_stats& a, const minkq_query_stats& b) {
  return a.nodes_visited == b.nodes_visited && a.node_tests == b.node_tests &&
         a.primitive_tests == b.primitive_tests && a.candidates == b.candidates;
}

bool no_more_work(const minkq_query_stats& finer, const minkq_query_stats& coarser) {
  return finer.nodes_visited <= coarser.nodes_visited && finer.node_tests <= coarser.node_tests &&
         finer.primitive_tests <= coarser.primitive_tests && finer.candidates <= coarser.candidates;
}

TEST(WorkCounts, a_cluster_within_r_of_everything_visits_every_node_and_meets_each_pair_once) {
  const uint64_t seed = test::fresh_seed();
  const reference::Mesh mesh = reference::random_soup(30, seed, 0.01);  // 90 vertices, 90 edges
  test::Device device;
  test::Scene scene(device.get(), mesh, kBoth);
  const uint64_t nv = mesh.xyz.size() / 3, nt = mesh.tris.size() / 3, ne = minkq_scene_edge_count(scene.get());
  const float r = 4.0f;  // the soup lies in the unit cube: every box is within r of every other
  const minkq_query_stats vt = test::work_of(scene.get(), MINKQ_QUERY_VT, MINKQ_MODE_BOX, r);
  // Every query reads every node record (fewer than a binary tree's nt - 1: leaf ranges) and
  // tests every box: two per node, plus each leaf box of ranges holding more than one.
  EXPECT_EQ(vt.nodes_visited % nv, 0u);
  EXPECT_LT(vt.nodes_visited, nv * (nt - 1));
  EXPECT_GE(vt.node_tests, 2 * vt.nodes_visited);
  EXPECT_LE(vt.node_tests, 2 * vt.nodes_visited + nv * nt);
  EXPECT_EQ(vt.primitive_tests, nv * nt);
  EXPECT_EQ(vt.candidates, nv * nt);
  for (minkq_mode mode : {MINKQ_MODE_BOX, MINKQ_MODE_CAPSULE_RAY, MINKQ_MODE_CAPSULE_EXACT}) {
    const minkq_query_stats ee = test::work_of(scene.get(), MINKQ_QUERY_EE, mode, r);
    EXPECT_EQ(ee.primitive_tests, ne * (ne - 1) / 2) << "each unordered pair is met once";
    EXPECT_EQ(ee.candidates, ne * (ne - 1) / 2);
    EXPECT_LT(ee.nodes_visited, (ne - 1) * (ne - 1)) << "queries skip the leaves before them";
  }
}

TEST(WorkCounts, finer_modes_never_do_more_work_than_coarser_ones) {
  const reference::Mesh mesh = reference::twisted_sheet(40, 3.0);
  const float r = float(0.25 * reference::mean_edge_length(mesh));
  test::Device device;
  test::Scene scene(device.get(), mesh, kBoth | MINKQ_SCENE_DROP_INCIDENT);
  const auto vt = [&](minkq_mode mode, uint32_t flags = 0) {
    return test::work_of(scene.get(), MINKQ_QUERY_VT, mode, r, flags);
  };
  const auto ee = [&](minkq_mode mode, uint32_t flags = 0) {
    return test::work_of(scene.get(), MINKQ_QUERY_EE, mode, r, flags);
  };
  EXPECT_TRUE(no_more_work(vt(MINKQ_MODE_SPHERE), vt(MINKQ_MODE_BOX)));
  EXPECT_TRUE(no_more_work(ee(MINKQ_MODE_CAPSULE_RAY), ee(MINKQ_MODE_BOX)));
  EXPECT_TRUE(no_more_work(ee(MINKQ_MODE_CAPSULE_EXACT), ee(MINKQ_MODE_CAPSULE_RAY)));
  // The leaf filter changes only what is emitted.
  const minkq_query_stats plain = ee(MINKQ_MODE_CAPSULE_EXACT), exact = ee(MINKQ_MODE_CAPSULE_EXACT, MINKQ_QUERY_LEAF_EXACT);
  EXPECT_EQ(plain.nodes_visited, exact.nodes_visited);
  EXPECT_EQ(plain.primitive_tests, exact.primitive_tests);
  EXPECT_LE(exact.candidates, plain.candidates);
  EXPECT_GT(exact.candidates, 0u);
  // Every visited node tests one or two children (plus the leaf boxes of the ranges it
  // reaches, at most kLeafSize each); primitives come from passed tests.
  for (const minkq_query_stats& s : {vt(MINKQ_MODE_SPHERE), ee(MINKQ_MODE_BOX)}) {
    EXPECT_GE(s.node_tests, s.nodes_visited);
    EXPECT_LE(s.node_tests, (2 + 2 * kLeafSize) * s.nodes_visited);
    EXPECT_GE(s.primitive_tests, s.candidates);
  }
}

TEST(WorkCounts, are_zero_without_the_flag_and_do_not_depend_on_output_options) {
  const reference::Mesh mesh = reference::twisted_sheet(24, 3.0);
  const float r = float(0.5 * reference::mean_edge_length(mesh));
  test::Device device;
  test::Scene scene(device.get(), mesh, kBoth);
  minkq_query_desc desc{MINKQ_QUERY_EE, MINKQ_MODE_CAPSULE_EXACT, 0, r};
  minkq_query_info info{};
  ASSERT_EQ(minkq_scene_query(scene.get(), &desc, nullptr, 0, MINKQ_MEMORY_HOST, &info), MINKQ_ERROR_CAPACITY);
  EXPECT_TRUE(info.stats == minkq_query_stats{});
  const uint64_t count = info.count;
  ASSERT_GT(count, 0u);

  // Counted also when the buffer is too small, and the same with canonical order and digest.
  desc.flags = MINKQ_QUERY_STATS;
  ASSERT_EQ(minkq_scene_query(scene.get(), &desc, nullptr, 0, MINKQ_MEMORY_HOST, &info), MINKQ_ERROR_CAPACITY);
  const minkq_query_stats first = info.stats;
  EXPECT_EQ(first.candidates, count);
  EXPECT_GT(first.nodes_visited, 0u);
  std::vector<int32_t> pairs(2 * count);
  for (uint32_t extra : {0u, uint32_t(MINKQ_QUERY_CANONICAL), uint32_t(MINKQ_QUERY_DIGEST)}) {
    desc.flags = MINKQ_QUERY_STATS | extra;
    ASSERT_EQ(minkq_scene_query(scene.get(), &desc, pairs.data(), count, MINKQ_MEMORY_HOST, &info), MINKQ_SUCCESS);
    EXPECT_TRUE(info.stats == first) << "flags " << desc.flags;
  }
  EXPECT_TRUE(test::work_of(scene.get(), MINKQ_QUERY_EE, MINKQ_MODE_CAPSULE_EXACT, r) == first);
}

TEST(WorkCounts, bvh_queries_count_too) {
  const std::vector<float> boxes = {0, 0, 0, 1, 1, 1, 2, 0, 0, 3, 1, 1, 5, 5, 5, 6, 6, 6};
  const std::vector<float> centres = {0.5f, 0.5f, 0.5f, 2.5f, 0.5f, 0.5f};
  test::Device device;
  minkq_bvh* bvh = nullptr;
  ASSERT_EQ(minkq_bvh_create(device.get(), test::host_buffer(boxes.data(), 3), &bvh), MINKQ_SUCCESS);
  minkq_bvh_query_desc desc{};
  desc.shape = MINKQ_SHAPE_SPHERE;
  desc.mode = MINKQ_MODE_SPHERE;
  desc.flags = MINKQ_QUERY_STATS;
  desc.radius = 0.1f;
  desc.first = test::host_buffer(centres.data(), 2);
  int32_t pairs[8];
  minkq_query_info info{};
  ASSERT_EQ(minkq_bvh_query(bvh, &desc, pairs, 4, MINKQ_MEMORY_HOST, &info), MINKQ_SUCCESS);
  EXPECT_EQ(info.count, 2u);
  EXPECT_EQ(info.stats.candidates, 2u);
  EXPECT_GE(info.stats.nodes_visited, 2u);  // each query reads at least the root
  minkq_bvh_release(bvh);
}

}  // namespace
}  // namespace minkq
