// The C++ classes of minkq.hpp (minkq::api) against the C calls they wrap: the same pairs for
// one-mesh scenes, scenes of many geometries and BVHs, in every form (vector, reused buffer,
// count, VT + EE in one pass, stream-ordered on the CPU), and failures thrown as minkq::api::Error
// with the status and the library's message (or the wrapper's own, for a view of the wrong size).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <limits>
#include <string>
#include <vector>

#include "capi_util.h"

namespace minkq::test {
namespace {

namespace ref = minkq::reference;

Pairs as_pairs(const std::vector<api::Pair>& v) {
  Pairs out;
  for (const api::Pair& p : v) out.emplace_back(p.first, p.second);
  return out;
}

// Runs `f`, which must throw Error with `status` and a message containing `part`.
template <class F>
void expect_error(F&& f, minkq_status status, const std::string& part) {
  try {
    f();
    ADD_FAILURE() << "no Error thrown; expected " << minkq_status_name(status);
  } catch (const api::Error& e) {
    EXPECT_EQ(e.status(), status) << e.what();
    EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
  }
}

class CppApi : public ::testing::Test {
 protected:
  ref::Mesh mesh = ref::twisted_sheet(24, 1.5);
  float r = float(0.5 * ref::mean_edge_length(mesh));
  api::Device device{"cpu"};
};

TEST_F(CppApi, MeshSceneQueriesEqualTheCCalls) {
  api::Scene scene(device, mesh.xyz, mesh.tris);
  Scene c(device.get(), mesh, api::Scene::kMeshFlags);
  EXPECT_EQ(scene.vertex_count(), mesh.vertex_count());
  EXPECT_EQ(scene.triangle_count(), mesh.triangle_count());
  EXPECT_EQ(scene.geometry_count(), 1u);
  std::vector<int32_t> edges;
  for (const api::Pair& e : scene.edges()) edges.push_back(e.first), edges.push_back(e.second);
  EXPECT_EQ(edges, mesh.edges);
  for (const minkq_query_kind kind : {MINKQ_QUERY_VT, MINKQ_QUERY_EE})
    for (const minkq_mode mode : {MINKQ_MODE_BOX, MINKQ_MODE_CAPSULE_EXACT})
      for (const uint32_t flags : {0u, uint32_t(MINKQ_QUERY_LEAF_EXACT)}) {
        uint64_t digest = 0;
        const Pairs want = c.query(kind, mode, r, flags, &digest);
        ASSERT_FALSE(want.empty());
        const api::Query q{kind, r, mode, flags | MINKQ_QUERY_CANONICAL};
        EXPECT_EQ(as_pairs(scene.query(q)), want);
        // Into a reused buffer: grown once, then kept.
        std::vector<api::Pair> out;
        const minkq_query_info info = scene.query(api::Query{kind, r, mode, flags | MINKQ_QUERY_DIGEST}, out);
        EXPECT_EQ(as_pairs(out), want);
        EXPECT_EQ(info.count, want.size());
        EXPECT_EQ(info.digest, digest);
        const api::Pair* storage = out.data();
        scene.query(q, out);
        EXPECT_EQ(out.data(), storage);
        EXPECT_EQ(as_pairs(out), want);
        // Count only, with the stats of a stored query.
        minkq_query_stats stats{};
        EXPECT_EQ(scene.count(api::Query{kind, r, mode, flags | MINKQ_QUERY_STATS}, &stats), want.size());
        EXPECT_EQ(stats.candidates, want.size());
        EXPECT_EQ(stats.primitive_tests, work_of(c.get(), kind, mode, r, flags).primitive_tests);
      }
  const api::VtEePairs both = scene.query_vt_ee({MINKQ_QUERY_VT, r, MINKQ_MODE_BOX, MINKQ_QUERY_CANONICAL},
                                                {MINKQ_QUERY_EE, r, MINKQ_MODE_BOX, MINKQ_QUERY_CANONICAL});
  EXPECT_EQ(as_pairs(both.vt), c.query(MINKQ_QUERY_VT, MINKQ_MODE_BOX, r));
  EXPECT_EQ(as_pairs(both.ee), c.query(MINKQ_QUERY_EE, MINKQ_MODE_BOX, r));
}

TEST_F(CppApi, RefitsFloat64AndViewsOfEveryKind) {
  ref::set_float64(mesh, std::vector<double>(mesh.xyz.begin(), mesh.xyz.end()));
  api::Scene scene(device, mesh.xyz64, mesh.tris);  // doubles: a float64 scene
  Scene c(device.get(), mesh, api::Scene::kMeshFlags | MINKQ_SCENE_FLOAT64);
  const api::Query q{MINKQ_QUERY_VT, r, MINKQ_MODE_BOX, MINKQ_QUERY_CANONICAL};
  EXPECT_EQ(as_pairs(scene.query(q)), c.query(MINKQ_QUERY_VT, MINKQ_MODE_BOX, r));
  // Moved: every vertex twice as far from the origin, in both scenes.
  std::vector<double> moved = mesh.xyz64;
  for (double& x : moved) x *= 2;
  scene.refit(moved);
  ASSERT_EQ(minkq_scene_refit(c.get(), host_buffer(moved.data(), moved.size() / 3)), MINKQ_SUCCESS);
  EXPECT_EQ(as_pairs(scene.query(q)), c.query(MINKQ_QUERY_VT, MINKQ_MODE_BOX, r));
  scene.rebuild(api::View<double>(moved.data(), moved.size()));
  EXPECT_EQ(as_pairs(scene.query(q)), c.query(MINKQ_QUERY_VT, MINKQ_MODE_BOX, r));
  EXPECT_DOUBLE_EQ(scene.tree_growth(), 1.0);
  // std::array and C arrays: two parallel triangles 0.01 apart, each vertex within 0.02 of the other.
  const std::array<float, 18> xyz{0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 0.01f, 1, 0, 0.01f, 0, 1, 0.01f};
  const int32_t tris[] = {0, 1, 2, 3, 4, 5};
  api::Scene two(device, xyz, tris);
  EXPECT_EQ(two.query({MINKQ_QUERY_VT, 0.02f, MINKQ_MODE_BOX, MINKQ_QUERY_LEAF_EXACT}).size(), 6u);
}

TEST_F(CppApi, GeometriesEqualTheCCalls) {
  const ref::Mesh other = ref::twisted_sheet(9, 0.5);
  std::vector<float> thickness(other.vertex_count(), 0.25f * r);
  std::vector<api::GeometryDesc> geometries(2);
  geometries[0].vertices(mesh.xyz).triangles(mesh.tris);
  geometries[1].vertices(other.xyz).triangles(other.tris).thickness(thickness).self(false).is_static(true);
  api::Scene scene(device, geometries);
  std::vector<minkq_geometry_desc> descs{geometries[0].desc(), geometries[1].desc()};
  cxx::Scene c = created<cxx::Scene>(
      [&](minkq_scene** out) { return minkq_scene_create_geometries(device.get(), descs.data(), descs.size(), out); });
  EXPECT_EQ(scene.geometry_count(), 2u);
  const api::Range vertices = scene.geometry_range(1, MINKQ_ELEMENT_VERTEX);
  EXPECT_EQ(vertices.first, mesh.vertex_count());
  EXPECT_EQ(vertices.count, other.vertex_count());
  for (const minkq_query_kind kind : {MINKQ_QUERY_VT, MINKQ_QUERY_EE}) {
    const Pairs want = Scene::query_pairs(c.get(), kind, MINKQ_MODE_BOX, r);
    EXPECT_FALSE(want.empty());
    EXPECT_EQ(as_pairs(scene.query({kind, r, MINKQ_MODE_BOX, MINKQ_QUERY_CANONICAL})), want);
  }
  // Each pair's elements located: VT and EE pairs join the two geometries or lie within the
  // cloth (geometry 1 reports no pairs of its own).
  const std::vector<api::Pair> vt = scene.query({MINKQ_QUERY_VT, r});
  size_t cross = 0;
  for (const api::Pair& p : vt) {
    const api::Local v = scene.locate(MINKQ_ELEMENT_VERTEX, p.first), t = scene.locate(MINKQ_ELEMENT_TRIANGLE, p.second);
    EXPECT_FALSE(v.geometry == 1 && t.geometry == 1);
    EXPECT_LT(v.id, v.geometry ? other.vertex_count() : mesh.vertex_count());
    EXPECT_LT(t.id, t.geometry ? other.triangle_count() : mesh.triangle_count());
    cross += v.geometry != t.geometry;
  }
  EXPECT_GT(cross, 0u);
  const api::Local last = scene.locate(MINKQ_ELEMENT_TRIANGLE, int64_t(scene.triangle_count()) - 1);
  EXPECT_EQ(last.geometry, 1u);
  EXPECT_EQ(last.id, other.triangle_count() - 1);
  EXPECT_EQ(scene.locate(MINKQ_ELEMENT_VERTEX, int64_t(mesh.vertex_count())).geometry, 1u);
  EXPECT_EQ(scene.locate(MINKQ_ELEMENT_VERTEX, int64_t(mesh.vertex_count()) - 1).id, mesh.vertex_count() - 1);
  expect_error([&] { scene.locate(MINKQ_ELEMENT_EDGE, int64_t(scene.edge_count())); }, MINKQ_ERROR_INVALID_ARGUMENT,
               "is not an element of the scene");
  expect_error([&] { scene.locate(MINKQ_ELEMENT_EDGE, -1); }, MINKQ_ERROR_INVALID_ARGUMENT, "id -1");
  // One geometry moved; the static one refuses to move, naming itself.
  api::Scene moving(device, geometries);
  std::vector<float> shifted = mesh.xyz;
  for (size_t i = 2; i < shifted.size(); i += 3) shifted[i] += 10;  // far away in z
  moving.geometry_refit(0, shifted);
  ASSERT_EQ(minkq_scene_geometry_refit(c.get(), 0, host_buffer(shifted.data(), shifted.size() / 3)), MINKQ_SUCCESS);
  EXPECT_EQ(as_pairs(moving.query({MINKQ_QUERY_VT, r, MINKQ_MODE_BOX, MINKQ_QUERY_CANONICAL})),
            Scene::query_pairs(c.get(), MINKQ_QUERY_VT, MINKQ_MODE_BOX, r));
  expect_error([&] { moving.geometry_rebuild(1, other.xyz); }, MINKQ_ERROR_INVALID_ARGUMENT, "geometry 1");
}

TEST_F(CppApi, BvhQueriesEqualTheCCalls) {
  std::vector<float> boxes;  // one box per triangle
  for (size_t t = 0; t < mesh.triangle_count(); ++t) {
    float lo[3] = {1e30f, 1e30f, 1e30f}, hi[3] = {-1e30f, -1e30f, -1e30f};
    for (int k = 0; k < 3; ++k)
      for (int a = 0; a < 3; ++a) {
        const float x = mesh.xyz[3 * size_t(mesh.tris[3 * t + k]) + a];
        lo[a] = std::min(lo[a], x), hi[a] = std::max(hi[a], x);
      }
    boxes.insert(boxes.end(), lo, lo + 3), boxes.insert(boxes.end(), hi, hi + 3);
  }
  api::Bvh bvh(device, boxes);
  cxx::Bvh c = new_bvh(device.get(), host_buffer(boxes.data(), boxes.size() / 6, 6 * sizeof(float)));
  minkq_bvh_query_desc d{MINKQ_SHAPE_SPHERE, MINKQ_MODE_SPHERE, MINKQ_QUERY_CANONICAL, r,
                         host_buffer(mesh.xyz.data(), mesh.vertex_count(), 3 * sizeof(float)), host_buffer(nullptr, 0)};
  minkq_query_info info{};
  ASSERT_EQ(minkq_bvh_query(c.get(), &d, nullptr, 0, MINKQ_MEMORY_HOST, &info), MINKQ_ERROR_CAPACITY);
  std::vector<int32_t> raw(2 * info.count);
  ASSERT_EQ(minkq_bvh_query(c.get(), &d, raw.data(), info.count, MINKQ_MEMORY_HOST, &info), MINKQ_SUCCESS);
  Pairs want;
  for (size_t i = 0; i < info.count; ++i) want.emplace_back(raw[2 * i], raw[2 * i + 1]);
  ASSERT_FALSE(want.empty());
  EXPECT_EQ(as_pairs(bvh.spheres(mesh.xyz, r, MINKQ_MODE_SPHERE, MINKQ_QUERY_CANONICAL)), want);
  // Each box against itself (and its neighbours): every box index appears.
  const std::vector<float> lo(boxes.begin(), boxes.begin() + 3), hi(boxes.begin() + 3, boxes.begin() + 6);
  const std::vector<api::Pair> hits = bvh.boxes(lo, hi);
  EXPECT_TRUE(std::find(hits.begin(), hits.end(), api::Pair{0, 0}) != hits.end());
  bvh.refit(boxes);
  EXPECT_DOUBLE_EQ(bvh.tree_growth(), 1.0);
  expect_error([&] { bvh.capsules(lo, hi, r, MINKQ_MODE_SPHERE); }, MINKQ_ERROR_INVALID_ARGUMENT, "minkq_bvh_query");
}

TEST_F(CppApi, StreamOrderedCallsOnTheCpuEqualTheBlockingOnes) {
  api::Scene scene(device, mesh.xyz, mesh.tris);
  const api::Query q{MINKQ_QUERY_EE, r, MINKQ_MODE_BOX, MINKQ_QUERY_CANONICAL};
  const std::vector<api::Pair> want = scene.query(q);
  scene.reserve(MINKQ_RESERVE_REFIT, want.size());
  std::vector<int32_t> pairs(2 * want.size());
  uint64_t count = 0;
  scene.refit_async(host_buffer(mesh.xyz.data(), mesh.vertex_count()), nullptr);
  scene.query_async(q, pairs.data(), want.size(), &count, nullptr);
  scene.async_status(nullptr);
  ASSERT_EQ(count, want.size());
  std::vector<api::Pair> got(count);
  for (size_t i = 0; i < count; ++i) got[i] = api::Pair{pairs[2 * i], pairs[2 * i + 1]};
  EXPECT_EQ(got, want);
  // A refit with a NaN: its error, pending or at once, throws with the library's message.
  std::vector<float> bad = mesh.xyz;
  bad[3 * 5 + 1] = std::numeric_limits<float>::quiet_NaN();
  expect_error(
      [&] {
        scene.refit_async(host_buffer(bad.data(), mesh.vertex_count()), nullptr);
        scene.async_status(nullptr);
      },
      MINKQ_ERROR_NON_FINITE, "vertex 5");
}

TEST_F(CppApi, ErrorsCarryTheStatusAndTheMessage) {
  // The wrapper's own check: a view that is not whole records.
  const std::vector<float> seven(7, 0.0f);
  expect_error([&] { const api::Scene s(device, seven, mesh.tris); }, MINKQ_ERROR_INVALID_ARGUMENT,
               "vertices hold 7 values, not a multiple of 3");
  expect_error([&] { api::GeometryDesc().triangles(std::vector<int32_t>(4)); }, MINKQ_ERROR_INVALID_ARGUMENT,
               "triangles hold 4 values");
  // The library's: a triangle past the vertices, a negative radius, a kind the scene lacks, a device.
  const std::vector<int32_t> tris{0, 1, 9};
  const std::vector<float> xyz(9, 0.0f);
  expect_error([&] { const api::Scene s(device, xyz, tris); }, MINKQ_ERROR_INDEX_OUT_OF_RANGE,
               "triangle 0 references vertex 9");
  api::Scene scene(device, mesh.xyz, mesh.tris, MINKQ_SCENE_VT);
  expect_error([&] { scene.query({MINKQ_QUERY_VT, -1.0f}); }, MINKQ_ERROR_INVALID_ARGUMENT, "minkq_scene_query_result");
  std::vector<api::Pair> out;
  expect_error([&] { scene.query({MINKQ_QUERY_EE, r}, out); }, MINKQ_ERROR_INVALID_ARGUMENT, "minkq_scene_query");
  expect_error([] { const api::Device d("gpu7"); }, MINKQ_ERROR_INVALID_ARGUMENT, "minkq_device_create(\"gpu7\")");
}

}  // namespace
}  // namespace minkq::test
