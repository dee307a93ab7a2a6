// MINKQ_QUERY_COUNT: the exact count of every query, blocking, fused, stream-ordered, into a
// result and on a user-box BVH, with nothing written; refused with CANONICAL or DIGEST.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "capi_util.h"
#include "test_util.h"

namespace minkq {
namespace {

using test::host_buffer;

std::string message() { return minkq_last_error_message(); }

constexpr int32_t kSentinel = -77;

// A count-only query: its status, count and stats, with a buffer of sentinels that must stay.
struct Counted {
  minkq_status status;
  minkq_query_info info;
};
Counted count_only(minkq_scene* scene, minkq_query_kind kind, minkq_mode mode, float r, uint32_t flags,
                   std::vector<int32_t>* untouched) {
  const minkq_query_desc q{kind, mode, flags | MINKQ_QUERY_COUNT, r};
  Counted c{};
  int32_t* pairs = untouched ? untouched->data() : nullptr;
  const size_t capacity = untouched ? untouched->size() / 2 : 0;
  c.status = minkq_scene_query(scene, &q, pairs, capacity, MINKQ_MEMORY_HOST, &c.info);
  return c;
}

struct CountTest : ::testing::Test {
  test::Device device;
  test::Scene scene{device.get(), reference::random_soup(400, test::fresh_seed(), 1.0),
                    MINKQ_SCENE_VT | MINKQ_SCENE_EE | MINKQ_SCENE_VV | MINKQ_SCENE_EV | MINKQ_SCENE_DROP_INCIDENT};
};

TEST_F(CountTest, every_kind_and_mode_counts_the_pairs_it_would_write_and_writes_none) {
  const float r = 0.03f;
  for (const minkq_query_kind kind : {MINKQ_QUERY_VT, MINKQ_QUERY_EE, MINKQ_QUERY_VV, MINKQ_QUERY_EV})
    for (const minkq_mode mode : {MINKQ_MODE_BOX, MINKQ_MODE_SPHERE, MINKQ_MODE_CAPSULE_RAY, MINKQ_MODE_CAPSULE_EXACT})
      for (const uint32_t leaf : {0u, uint32_t(MINKQ_QUERY_LEAF_EXACT)}) {
        if (kind == MINKQ_QUERY_EE && mode == MINKQ_MODE_SPHERE) continue;
        const test::Pairs pairs = scene.query(kind, mode, r, leaf);
        // NULL pairs, and a small buffer that must keep its sentinels (capacity is ignored).
        const Counted null_out = count_only(scene.get(), kind, mode, r, leaf, nullptr);
        std::vector<int32_t> small(8, kSentinel);
        const Counted small_out = count_only(scene.get(), kind, mode, r, leaf | MINKQ_QUERY_STATS, &small);
        const std::string what = "kind " + std::to_string(kind) + " mode " + std::to_string(mode) + " leaf " +
                                 std::to_string(leaf);
        ASSERT_EQ(null_out.status, MINKQ_SUCCESS) << what << ": " << message();
        ASSERT_EQ(small_out.status, MINKQ_SUCCESS) << what << ": " << message();
        EXPECT_EQ(null_out.info.count, pairs.size()) << what;
        EXPECT_EQ(small_out.info.count, pairs.size()) << what;
        EXPECT_EQ(small_out.info.stats.candidates, pairs.size()) << what;
        EXPECT_EQ(small_out.info.digest, 0u) << what;
        for (int32_t v : small) ASSERT_EQ(v, kSentinel) << what << ": a count-only query wrote a pair";
        // The same work as the query that stores its pairs.
        const minkq_query_stats stored = test::work_of(scene.get(), kind, mode, r, leaf);
        EXPECT_EQ(small_out.info.stats.nodes_visited, stored.nodes_visited) << what;
        EXPECT_EQ(small_out.info.stats.primitive_tests, stored.primitive_tests) << what;
      }
  ASSERT_GT(scene.query(MINKQ_QUERY_EE, MINKQ_MODE_BOX, r).size(), 100u);  // the soup has pairs to count
}

TEST_F(CountTest, a_count_only_query_with_canonical_or_digest_is_refused_by_name) {
  for (const uint32_t flags : {uint32_t(MINKQ_QUERY_CANONICAL), uint32_t(MINKQ_QUERY_DIGEST)}) {
    const Counted c = count_only(scene.get(), MINKQ_QUERY_VT, MINKQ_MODE_BOX, 0.03f, flags, nullptr);
    EXPECT_EQ(c.status, MINKQ_ERROR_INVALID_ARGUMENT);
    EXPECT_NE(message().find("query->flags asks for MINKQ_QUERY_COUNT with CANONICAL or DIGEST"), std::string::npos)
        << message();
  }
  // Other argument checks still apply: a count-only EE sphere query, a negative radius.
  EXPECT_EQ(count_only(scene.get(), MINKQ_QUERY_EE, MINKQ_MODE_SPHERE, 0.03f, 0, nullptr).status,
            MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(count_only(scene.get(), MINKQ_QUERY_VT, MINKQ_MODE_BOX, -1.0f, 0, nullptr).status,
            MINKQ_ERROR_INVALID_ARGUMENT);
}

TEST_F(CountTest, fused_async_and_result_calls_count_alike) {
  const float r = 0.03f;
  const uint64_t vt = scene.query(MINKQ_QUERY_VT, MINKQ_MODE_SPHERE, r).size();
  const test::Pairs ee = scene.query(MINKQ_QUERY_EE, MINKQ_MODE_BOX, r);
  const minkq_query_desc vt_count{MINKQ_QUERY_VT, MINKQ_MODE_SPHERE, MINKQ_QUERY_COUNT, r};
  const minkq_query_desc ee_pairs{MINKQ_QUERY_EE, MINKQ_MODE_BOX, MINKQ_QUERY_CANONICAL, r};
  // Fused: VT counted, EE written.
  std::vector<int32_t> ee_out(2 * ee.size());
  minkq_query_info vt_info{}, ee_info{};
  ASSERT_EQ(minkq_scene_query_vt_ee(scene.get(), &vt_count, &ee_pairs, nullptr, 0, ee_out.data(), ee.size(),
                                    MINKQ_MEMORY_HOST, &vt_info, &ee_info),
            MINKQ_SUCCESS)
      << message();
  EXPECT_EQ(vt_info.count, vt);
  EXPECT_EQ(ee_info.count, ee.size());
  for (size_t i = 0; i < ee.size(); ++i) EXPECT_EQ((std::pair<int32_t, int32_t>{ee_out[2 * i], ee_out[2 * i + 1]}), ee[i]);
  // Stream-ordered (run at once on the CPU): the count only, no reservation needed.
  uint64_t count = 0;
  std::vector<int32_t> untouched(8, kSentinel);
  ASSERT_EQ(minkq_scene_query_async(scene.get(), &vt_count, untouched.data(), 4, &count, nullptr), MINKQ_SUCCESS)
      << message();
  EXPECT_EQ(count, vt);
  for (int32_t v : untouched) EXPECT_EQ(v, kSentinel);
  // Into a result: the count, and no pairs, also where the result held more pairs before.
  const cxx::Result result = test::new_result();
  const minkq_query_desc ee_stored{MINKQ_QUERY_EE, MINKQ_MODE_BOX, 0, r};
  ASSERT_EQ(minkq_scene_query_result(scene.get(), &ee_stored, result.get()), MINKQ_SUCCESS) << message();
  ASSERT_NE(minkq_result_pairs(result.get()), nullptr);
  ASSERT_LT(vt, ee.size());  // the earlier pairs would cover the count
  ASSERT_EQ(minkq_scene_query_result(scene.get(), &vt_count, result.get()), MINKQ_SUCCESS) << message();
  EXPECT_EQ(minkq_result_count(result.get()), vt);
  EXPECT_EQ(minkq_result_pairs(result.get()), nullptr);
  // And a stored query after it has its pairs again.
  ASSERT_EQ(minkq_scene_query_result(scene.get(), &ee_stored, result.get()), MINKQ_SUCCESS) << message();
  EXPECT_EQ(minkq_result_count(result.get()), ee.size());
  EXPECT_NE(minkq_result_pairs(result.get()), nullptr);
}

TEST(CountBvh, user_box_queries_count_what_they_would_write) {
  test::Random rng(test::fresh_seed());
  test::Device device;
  std::vector<Box> boxes(500);
  for (Box& b : boxes) b = rng.box(rng.vec3(0, 10), 0.4f);
  const cxx::Bvh bvh = test::new_bvh(device.get(), host_buffer(boxes.data(), boxes.size()));
  std::vector<Vec3> centres(200);
  for (Vec3& c : centres) c = rng.vec3(0, 10);
  minkq_bvh_query_desc q{MINKQ_SHAPE_SPHERE, MINKQ_MODE_SPHERE, 0, 0.3f, host_buffer(centres.data(), centres.size()),
                         host_buffer(nullptr, 0)};
  std::vector<int32_t> out(2 * boxes.size() * centres.size());
  minkq_query_info stored{}, counted{};
  ASSERT_EQ(minkq_bvh_query(bvh.get(), &q, out.data(), out.size() / 2, MINKQ_MEMORY_HOST, &stored), MINKQ_SUCCESS);
  ASSERT_GT(stored.count, 0u);
  q.flags = MINKQ_QUERY_COUNT;
  ASSERT_EQ(minkq_bvh_query(bvh.get(), &q, nullptr, 0, MINKQ_MEMORY_HOST, &counted), MINKQ_SUCCESS) << message();
  EXPECT_EQ(counted.count, stored.count);
  q.flags = MINKQ_QUERY_COUNT | MINKQ_QUERY_DIGEST;
  EXPECT_EQ(minkq_bvh_query(bvh.get(), &q, nullptr, 0, MINKQ_MEMORY_HOST, &counted), MINKQ_ERROR_INVALID_ARGUMENT);
}

}  // namespace
}  // namespace minkq
