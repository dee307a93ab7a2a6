// Every query mode through the C API against the double-precision oracle: zero false
// negatives, the containment chain, leaf-exact extras within the stated bound, traversal
// completeness, refit, scale invariance and the extreme cases of DESIGN.md.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>

#include "scene_checks.h"
#include "capi_util.h"
#include "contact_checks.h"
#include "minkq/query_sources.h"
#include "test_util.h"

namespace minkq {
namespace {

using test::Pairs;
using reference::Mesh;
using test::ee_distance;
using test::vt_distance;

constexpr uint32_t kBoth = MINKQ_SCENE_VT | MINKQ_SCENE_EE;

// Runs every mode of both kinds and checks the whole contract against the brute-force oracle.
void check_scene(const Mesh& mesh, float r, bool drop_incident, const char* label, bool check_definition = true) {
  SCOPED_TRACE(std::string(label) + " r=" + std::to_string(r) + (drop_incident ? " drop_incident" : ""));
  test::Device device;
  test::Scene scene(device.get(), mesh, kBoth | (drop_incident ? MINKQ_SCENE_DROP_INCIDENT : 0u));
  const std::vector<int32_t> edges = scene.edges();
  ASSERT_EQ(edges, reference::derive_edges(mesh.tris));
  Mesh with_edges = mesh;
  with_edges.edges = edges;

  const Pairs vt_true = reference::vt_contacts_brute(with_edges, r, drop_incident);
  const Pairs ee_true = reference::ee_contacts_brute(with_edges, r, drop_incident);

  const Pairs vt_box = scene.query(MINKQ_QUERY_VT, MINKQ_MODE_BOX, r);
  const Pairs vt_sphere = scene.query(MINKQ_QUERY_VT, MINKQ_MODE_SPHERE, r);
  const Pairs vt_leaf = scene.query(MINKQ_QUERY_VT, MINKQ_MODE_SPHERE, r, MINKQ_QUERY_LEAF_EXACT);
  const Pairs vt_box_leaf = scene.query(MINKQ_QUERY_VT, MINKQ_MODE_BOX, r, MINKQ_QUERY_LEAF_EXACT);
  EXPECT_TRUE(test::is_subset(vt_true, vt_leaf)) << "VT false negatives: " << test::describe(test::difference(vt_true, vt_leaf));
  EXPECT_TRUE(test::is_subset(vt_true, vt_box_leaf));
  EXPECT_TRUE(test::is_subset(vt_leaf, vt_sphere));
  EXPECT_TRUE(test::is_subset(vt_sphere, vt_box));
  EXPECT_TRUE(test::is_subset(vt_box_leaf, vt_box));
  // Capsule modes on points are the box and sphere tests.
  EXPECT_EQ(scene.query(MINKQ_QUERY_VT, MINKQ_MODE_CAPSULE_RAY, r), vt_box);
  EXPECT_EQ(scene.query(MINKQ_QUERY_VT, MINKQ_MODE_CAPSULE_EXACT, r), vt_sphere);

  const Pairs ee_box = scene.query(MINKQ_QUERY_EE, MINKQ_MODE_BOX, r);
  const Pairs ee_ray = scene.query(MINKQ_QUERY_EE, MINKQ_MODE_CAPSULE_RAY, r);
  const Pairs ee_exact = scene.query(MINKQ_QUERY_EE, MINKQ_MODE_CAPSULE_EXACT, r);
  const Pairs ee_leaf = scene.query(MINKQ_QUERY_EE, MINKQ_MODE_CAPSULE_EXACT, r, MINKQ_QUERY_LEAF_EXACT);
  const Pairs ee_box_leaf = scene.query(MINKQ_QUERY_EE, MINKQ_MODE_BOX, r, MINKQ_QUERY_LEAF_EXACT);
  EXPECT_TRUE(test::is_subset(ee_true, ee_leaf)) << "EE false negatives: " << test::describe(test::difference(ee_true, ee_leaf));
  EXPECT_TRUE(test::is_subset(ee_true, ee_box_leaf));
  EXPECT_TRUE(test::is_subset(ee_leaf, ee_exact));
  EXPECT_TRUE(test::is_subset(ee_exact, ee_ray));
  EXPECT_TRUE(test::is_subset(ee_ray, ee_box));
  for (const auto& [e, f] : ee_box) ASSERT_LT(e, f);

  // Leaf-exact extras lie within r + 2^-19 * S.
  for (const auto& [v, t] : test::difference(vt_leaf, vt_true)) {
    double s;
    const long double d = vt_distance(mesh, v, t, &s);
    ASSERT_LE(d, (long double)r + std::ldexp(s, -19)) << "VT extra (" << v << "," << t << ")";
  }
  for (const auto& [e, f] : test::difference(ee_leaf, ee_true)) {
    double s;
    const long double d = ee_distance(mesh, edges, e, f, &s);
    ASSERT_LE(d, (long double)r + std::ldexp(s, -19)) << "EE extra (" << e << "," << f << ")";
  }

  if (!check_definition) return;
  // The brute-force definitions the differential fuzzer uses (testing/scene_checks.h).
  const fuzz::MeshGeometry g(mesh.xyz, mesh.tris, edges);
  const uint32_t filters = drop_incident ? kDropIncident : 0u;
  const auto vt = g.vt(r, filters), vt_exact = g.vt(r, filters | kLeafExact);
  EXPECT_EQ(vt_box, fuzz::definition_set<BoxShape>(vt, g.nv(), g.triangle_boxes(), g.nt()));
  EXPECT_EQ(vt_sphere, fuzz::definition_set<SphereShape>(vt, g.nv(), g.triangle_boxes(), g.nt()));
  EXPECT_EQ(vt_leaf, fuzz::definition_set<SphereShape>(vt_exact, g.nv(), g.triangle_boxes(), g.nt()));
  const auto ee = g.ee(r, filters), ee_exact_q = g.ee(r, filters | kLeafExact);
  EXPECT_EQ(ee_box, fuzz::definition_set<BoxShape>(ee, g.ne(), g.edge_boxes(), g.ne()));
  EXPECT_EQ(ee_ray, fuzz::definition_set<CapsuleRayShape>(ee, g.ne(), g.edge_boxes(), g.ne()));
  EXPECT_EQ(ee_exact, fuzz::definition_set<CapsuleExactShape>(ee, g.ne(), g.edge_boxes(), g.ne()));
  EXPECT_EQ(ee_leaf, fuzz::definition_set<CapsuleExactShape>(ee_exact_q, g.ne(), g.edge_boxes(), g.ne()));
}

class Queries : public ::testing::Test {
 protected:
  uint64_t seed = test::fresh_seed();
};

TEST_F(Queries, random_soup_every_mode_contains_true_contacts_and_nests) {
  for (int round = 0; round < 3; ++round) {
    const Mesh mesh = reference::random_soup(600, seed + round, 0.1);
    const double edge = reference::mean_edge_length(mesh);
    for (double factor : {0.1, 0.5, 2.0}) check_scene(mesh, float(factor * edge), round % 2 == 0, "soup");
  }
}

TEST_F(Queries, twisted_sheet_every_mode_contains_true_contacts_and_nests) {
  const Mesh mesh = reference::twisted_sheet(24, 3.0);
  const double edge = reference::mean_edge_length(mesh);
  for (double factor : {0.1, 0.25, 1.0, 4.0}) check_scene(mesh, float(factor * edge), true, "twisted sheet");
  check_scene(mesh, float(0.5 * edge), false, "twisted sheet");
}

TEST_F(Queries, stacked_sheets_at_gap_equal_to_radius_and_a_few_ulps_around) {
  const double gap = 0.01;
  const Mesh mesh = reference::stacked_sheets(12, 3, gap);
  const float r = float(gap);
  for (float radius : {r, std::nextafter(r, 0.0f), std::nextafter(r, 1.0f), std::nextafter(std::nextafter(r, 0.0f), 0.0f)})
    check_scene(mesh, radius, true, "stacked sheets");
}

TEST_F(Queries, extreme_offsets_radii_and_degenerate_elements) {
  test::Random rng(seed);
  Mesh soup = reference::random_soup(300, seed, 0.1);
  // Degenerate triangles: repeated vertices, collinear vertices, and a point.
  const int32_t n = int32_t(soup.xyz.size() / 3);
  soup.tris.insert(soup.tris.end(), {0, 0, 1, 2, 3, 2, 5, 5, 5});
  soup.xyz.insert(soup.xyz.end(), {0.1f, 0.2f, 0.3f, 0.2f, 0.3f, 0.4f, 0.3f, 0.4f, 0.5f});  // collinear
  soup.tris.insert(soup.tris.end(), {n, n + 1, n + 2});
  const double size = 1.0;  // the soup spans the unit cube
  for (double radius_factor : {1e-9, 1e-5, 1e-2, 1.0, 1e3}) check_scene(soup, float(radius_factor * size), true, "degenerate soup");
  for (double offset : {1e3, 1e5, 1e7}) {
    Mesh moved = soup;
    reference::transform(moved, 1.0, offset);
    for (double radius_factor : {1e-9, 1e-3, 0.05}) check_scene(moved, float(radius_factor * size), true, "offset soup", false);
  }
}

TEST_F(Queries, coordinates_near_float_max_lose_no_contact) {
  // Sums and differences of coordinates overflow to infinity here; every test must still err
  // towards "may be within r".
  for (double s : {1e30, 1e37, 3e38}) {
    Mesh mesh = reference::random_soup(150, seed, 0.2);
    reference::transform(mesh, s, -0.5 * s);
    for (double factor : {0.01, 0.3}) check_scene(mesh, float(factor * s), false, "near FLT_MAX");
  }
}

TEST_F(Queries, scaling_by_powers_of_two_gives_identical_pairs) {
  const Mesh mesh = reference::twisted_sheet(20, 2.0);
  const float r = float(0.3 * reference::mean_edge_length(mesh));
  test::Device device;
  test::Scene base(device.get(), mesh, kBoth | MINKQ_SCENE_DROP_INCIDENT);
  for (int exponent : {-10, 10, -30, 30}) {
    Mesh scaled = mesh;
    reference::transform(scaled, std::ldexp(1.0, exponent), 0.0);
    test::Scene other(device.get(), scaled, kBoth | MINKQ_SCENE_DROP_INCIDENT);
    const float rs = std::ldexp(r, exponent);
    for (minkq_mode mode : {MINKQ_MODE_BOX, MINKQ_MODE_SPHERE})
      for (uint32_t flags : {0u, uint32_t(MINKQ_QUERY_LEAF_EXACT)})
        EXPECT_EQ(base.query(MINKQ_QUERY_VT, mode, r, flags), other.query(MINKQ_QUERY_VT, mode, rs, flags)) << exponent;
    for (minkq_mode mode : {MINKQ_MODE_BOX, MINKQ_MODE_CAPSULE_RAY, MINKQ_MODE_CAPSULE_EXACT})
      for (uint32_t flags : {0u, uint32_t(MINKQ_QUERY_LEAF_EXACT)})
        EXPECT_EQ(base.query(MINKQ_QUERY_EE, mode, r, flags), other.query(MINKQ_QUERY_EE, mode, rs, flags)) << exponent;
  }
}

TEST_F(Queries, scaling_by_decimal_factors_changes_only_pairs_at_the_boundary) {
  // x1e3 and x1e-3 round every coordinate, so only pairs whose distance is within the rounding
  // of r may change; every true contact of the scaled mesh is still found.
  const Mesh mesh = reference::twisted_sheet(20, 2.0);
  const double edge = reference::mean_edge_length(mesh);
  const float r = float(0.3 * edge);
  test::Device device;
  test::Scene base(device.get(), mesh, kBoth | MINKQ_SCENE_DROP_INCIDENT);
  const Pairs vt = base.query(MINKQ_QUERY_VT, MINKQ_MODE_SPHERE, r, MINKQ_QUERY_LEAF_EXACT);
  const Pairs ee = base.query(MINKQ_QUERY_EE, MINKQ_MODE_CAPSULE_EXACT, r, MINKQ_QUERY_LEAF_EXACT);
  for (double factor : {1e-3, 1e3}) {
    Mesh scaled = mesh;
    reference::transform(scaled, factor, 0.0);
    check_scene(scaled, float(r * factor), true, "decimal scale", false);
    test::Scene other(device.get(), scaled, kBoth | MINKQ_SCENE_DROP_INCIDENT);
    const Pairs vt_s = other.query(MINKQ_QUERY_VT, MINKQ_MODE_SPHERE, float(r * factor), MINKQ_QUERY_LEAF_EXACT);
    const Pairs ee_s = other.query(MINKQ_QUERY_EE, MINKQ_MODE_CAPSULE_EXACT, float(r * factor), MINKQ_QUERY_LEAF_EXACT);
    const std::vector<int32_t> edges = reference::derive_edges(mesh.tris);
    for (const auto& [v, t] : test::difference(vt, vt_s)) {
      double s;
      EXPECT_NEAR(double(vt_distance(mesh, v, t, &s)), r, 1e-5 * s) << "VT pair far from the boundary changed";
    }
    for (const auto& [v, t] : test::difference(vt_s, vt)) {
      double s;
      EXPECT_NEAR(double(vt_distance(mesh, v, t, &s)), r, 1e-5 * s) << "VT pair far from the boundary changed";
    }
    for (const auto& [e, f] : test::difference(ee, ee_s)) {
      double s;
      EXPECT_NEAR(double(ee_distance(mesh, edges, e, f, &s)), r, 1e-5 * s);
    }
    for (const auto& [e, f] : test::difference(ee_s, ee)) {
      double s;
      EXPECT_NEAR(double(ee_distance(mesh, edges, e, f, &s)), r, 1e-5 * s);
    }
  }
}

TEST_F(Queries, refit_matches_a_fresh_build_and_the_oracle) {
  test::Random rng(seed);
  Mesh mesh = reference::twisted_sheet(20, 1.0);
  const float r = float(0.5 * reference::mean_edge_length(mesh));
  test::Device device;
  test::Scene scene(device.get(), mesh, kBoth | MINKQ_SCENE_DROP_INCIDENT);
  for (int step = 0; step < 3; ++step) {
    for (float& x : mesh.xyz) x += rng.uniform(-0.02f, 0.02f);
    ASSERT_EQ(minkq_scene_refit(scene.get(), test::host_buffer(mesh.xyz.data(), mesh.xyz.size() / 3)), MINKQ_SUCCESS)
        << minkq_last_error_message();
    test::Scene fresh(device.get(), mesh, kBoth | MINKQ_SCENE_DROP_INCIDENT);
    for (minkq_mode mode : {MINKQ_MODE_BOX, MINKQ_MODE_SPHERE})
      EXPECT_EQ(scene.query(MINKQ_QUERY_VT, mode, r), fresh.query(MINKQ_QUERY_VT, mode, r));
    for (minkq_mode mode : {MINKQ_MODE_BOX, MINKQ_MODE_CAPSULE_RAY, MINKQ_MODE_CAPSULE_EXACT})
      EXPECT_EQ(scene.query(MINKQ_QUERY_EE, mode, r), fresh.query(MINKQ_QUERY_EE, mode, r));
    check_scene(mesh, r, true, "refit step", false);
  }
}

// A flat sheet wrung into three turns: refit keeps the flat sheet's grouping, whose boxes then
// span the twist. Rebuilding changes no pair, and tree growth tells the two trees apart.
double tree_growth(minkq_scene* scene) {
  double growth = -1.0;
  EXPECT_EQ(minkq_scene_tree_growth(scene, &growth), MINKQ_SUCCESS) << minkq_last_error_message();
  return growth;
}

TEST_F(Queries, rebuild_changes_no_pair_and_resets_tree_growth) {
  const Mesh flat = reference::twisted_sheet(24, 0.0);
  Mesh wrung = reference::twisted_sheet(24, 3.0);
  test::Random rng(seed);
  for (float& x : wrung.xyz) x += rng.uniform(-1e-3f, 1e-3f);  // fresh positions each run
  const float r = float(0.5 * reference::mean_edge_length(wrung));
  test::Device device;
  test::Scene refit(device.get(), flat, kBoth | MINKQ_SCENE_DROP_INCIDENT);
  test::Scene rebuilt(device.get(), flat, kBoth | MINKQ_SCENE_DROP_INCIDENT);
  EXPECT_EQ(tree_growth(refit.get()), 1.0);
  const minkq_buffer moved = test::host_buffer(wrung.xyz.data(), wrung.xyz.size() / 3);
  ASSERT_EQ(minkq_scene_refit(refit.get(), moved), MINKQ_SUCCESS) << minkq_last_error_message();
  ASSERT_EQ(minkq_scene_rebuild(rebuilt.get(), moved), MINKQ_SUCCESS) << minkq_last_error_message();
  const double grown = tree_growth(refit.get());
  EXPECT_GT(grown, 1.5);  // the flat sheet's boxes stretched over the turns
  EXPECT_EQ(tree_growth(rebuilt.get()), 1.0);
  test::Scene fresh(device.get(), wrung, kBoth | MINKQ_SCENE_DROP_INCIDENT);
  for (minkq_mode mode : {MINKQ_MODE_BOX, MINKQ_MODE_SPHERE}) {
    const Pairs expected = fresh.query(MINKQ_QUERY_VT, mode, r);
    EXPECT_EQ(refit.query(MINKQ_QUERY_VT, mode, r), expected);
    EXPECT_EQ(rebuilt.query(MINKQ_QUERY_VT, mode, r), expected);
  }
  for (minkq_mode mode : {MINKQ_MODE_BOX, MINKQ_MODE_CAPSULE_RAY, MINKQ_MODE_CAPSULE_EXACT}) {
    const Pairs expected = fresh.query(MINKQ_QUERY_EE, mode, r);
    EXPECT_EQ(refit.query(MINKQ_QUERY_EE, mode, r), expected);
    EXPECT_EQ(rebuilt.query(MINKQ_QUERY_EE, mode, r), expected);
  }
  EXPECT_EQ(rebuilt.query(MINKQ_QUERY_EE, MINKQ_MODE_BOX, r, MINKQ_QUERY_LEAF_EXACT),
            fresh.query(MINKQ_QUERY_EE, MINKQ_MODE_BOX, r, MINKQ_QUERY_LEAF_EXACT));
  check_scene(wrung, r, true, "wrung sheet", false);
  // Scale-free: the same motion 1024 times larger (exact in float) grows the trees alike.
  Mesh flat_big = flat, wrung_big = wrung;
  for (float& x : flat_big.xyz) x *= 1024.0f;
  for (float& x : wrung_big.xyz) x *= 1024.0f;
  test::Scene big(device.get(), flat_big, kBoth | MINKQ_SCENE_DROP_INCIDENT);
  ASSERT_EQ(minkq_scene_refit(big.get(), test::host_buffer(wrung_big.xyz.data(), wrung_big.xyz.size() / 3)),
            MINKQ_SUCCESS);
  EXPECT_EQ(tree_growth(big.get()), grown);
  // Back to the build positions: the refit tree is the built one again.
  ASSERT_EQ(minkq_scene_refit(refit.get(), test::host_buffer(flat.xyz.data(), flat.xyz.size() / 3)), MINKQ_SUCCESS);
  EXPECT_EQ(tree_growth(refit.get()), 1.0);
}

TEST_F(Queries, strided_vertices_give_the_same_pairs) {
  const Mesh mesh = reference::random_soup(200, seed, 1.0);
  const size_t nv = mesh.xyz.size() / 3;
  std::vector<float> padded(nv * 5, -1.0f);
  for (size_t i = 0; i < nv; ++i) std::memcpy(&padded[5 * i + 1], &mesh.xyz[3 * i], 12);
  test::Device device;
  test::Scene packed(device.get(), mesh, kBoth);
  minkq_scene_desc desc{};
  desc.flags = kBoth;
  desc.vertices = {padded.data() + 1, 20, nv, MINKQ_MEMORY_HOST};
  desc.triangles = test::host_buffer(mesh.tris.data(), mesh.tris.size() / 3);
  minkq_scene* strided = nullptr;
  ASSERT_EQ(minkq_scene_create(device.get(), &desc, &strided), MINKQ_SUCCESS) << minkq_last_error_message();
  const float r = 0.05f;
  minkq_query_desc q{MINKQ_QUERY_EE, MINKQ_MODE_CAPSULE_EXACT, MINKQ_QUERY_DIGEST, r};
  minkq_result* result = nullptr;
  ASSERT_EQ(minkq_result_create(&result), MINKQ_SUCCESS);
  ASSERT_EQ(minkq_scene_query_result(strided, &q, result), MINKQ_SUCCESS);
  uint64_t digest = 0;
  const Pairs expected = packed.query(MINKQ_QUERY_EE, MINKQ_MODE_CAPSULE_EXACT, r, 0, &digest);
  EXPECT_EQ(minkq_result_count(result), expected.size());
  EXPECT_EQ(minkq_result_digest(result), digest);
  minkq_result_release(result);
  minkq_scene_release(strided);
}

TEST_F(Queries, empty_and_single_element_scenes) {
  test::Device device;
  Mesh empty;
  test::Scene none(device.get(), empty, kBoth);
  EXPECT_TRUE(none.query(MINKQ_QUERY_VT, MINKQ_MODE_SPHERE, 1.0f).empty());
  EXPECT_TRUE(none.query(MINKQ_QUERY_EE, MINKQ_MODE_CAPSULE_EXACT, 1.0f).empty());
  Mesh one;
  one.xyz = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0.2f, 0.2f, 0.1f};
  one.tris = {0, 1, 2};
  check_scene(one, 0.15f, false, "one triangle");
  check_scene(one, 0.15f, true, "one triangle");
}

// One query's output through the C API: status, info and the pairs written.
struct QueryOutput {
  minkq_status status;
  minkq_query_info info;
  std::vector<int32_t> pairs;
};

// Pairs as a sorted list, for outputs not asked to be canonical.
std::vector<int32_t> as_sorted(std::vector<int32_t> raw) {
  std::vector<std::pair<int32_t, int32_t>> pairs(raw.size() / 2);
  for (size_t i = 0; i < pairs.size(); ++i) pairs[i] = {raw[2 * i], raw[2 * i + 1]};
  std::sort(pairs.begin(), pairs.end());
  for (size_t i = 0; i < pairs.size(); ++i) raw[2 * i] = pairs[i].first, raw[2 * i + 1] = pairs[i].second;
  return raw;
}

void expect_same_output(const QueryOutput& alone, const QueryOutput& fused, uint32_t flags, const std::string& what) {
  EXPECT_EQ(fused.status, alone.status) << what;
  EXPECT_EQ(fused.info.count, alone.info.count) << what;
  EXPECT_EQ(fused.info.digest, alone.info.digest) << what;
  EXPECT_EQ(fused.info.stats.nodes_visited, alone.info.stats.nodes_visited) << what;
  EXPECT_EQ(fused.info.stats.node_tests, alone.info.stats.node_tests) << what;
  EXPECT_EQ(fused.info.stats.primitive_tests, alone.info.stats.primitive_tests) << what;
  EXPECT_EQ(fused.info.stats.candidates, alone.info.stats.candidates) << what;
  if (flags & (MINKQ_QUERY_CANONICAL | MINKQ_QUERY_DIGEST)) EXPECT_EQ(fused.pairs, alone.pairs) << what;
  else EXPECT_EQ(as_sorted(fused.pairs), as_sorted(alone.pairs)) << what;
}

// minkq_scene_query_vt_ee: each query's pairs, count, digest and work are what a call of its
// own gives, for every pair of modes and mixes of flags and radii.
TEST_F(Queries, vt_and_ee_in_one_call_give_what_each_gives_alone) {
  const Mesh soup = reference::random_soup(800, seed, 0.1), sheet = reference::twisted_sheet(24, 3.0);
  for (const auto& [mesh, flags] : {std::pair{&soup, kBoth}, std::pair{&sheet, kBoth | MINKQ_SCENE_DROP_INCIDENT}}) {
    test::Device device;
    test::Scene scene(device.get(), *mesh, flags);
    const double edge = reference::mean_edge_length(*mesh);
    const float vt_r = float(0.5 * edge), ee_r = float(0.25 * edge);  // unequal: a mix-up shows
    auto alone = [&](const minkq_query_desc& q) {
      QueryOutput out{};
      out.status = minkq_scene_query(scene.get(), &q, nullptr, 0, MINKQ_MEMORY_HOST, &out.info);
      out.pairs.resize(2 * out.info.count);
      out.status = minkq_scene_query(scene.get(), &q, out.pairs.data(), out.info.count, MINKQ_MEMORY_HOST, &out.info);
      return out;
    };
    for (minkq_mode vt_mode : {MINKQ_MODE_BOX, MINKQ_MODE_SPHERE, MINKQ_MODE_CAPSULE_RAY, MINKQ_MODE_CAPSULE_EXACT})
      for (minkq_mode ee_mode : {MINKQ_MODE_BOX, MINKQ_MODE_CAPSULE_RAY, MINKQ_MODE_CAPSULE_EXACT})
        for (uint32_t vt_flags : {0u, uint32_t(MINKQ_QUERY_LEAF_EXACT | MINKQ_QUERY_DIGEST | MINKQ_QUERY_STATS)})
          for (uint32_t ee_flags : {uint32_t(MINKQ_QUERY_CANONICAL | MINKQ_QUERY_STATS),
                                    uint32_t(MINKQ_QUERY_LEAF_EXACT | MINKQ_QUERY_DIGEST)}) {
            const std::string what = "VT mode " + std::to_string(vt_mode) + " flags " + std::to_string(vt_flags) +
                                     ", EE mode " + std::to_string(ee_mode) + " flags " + std::to_string(ee_flags);
            const minkq_query_desc vt{MINKQ_QUERY_VT, vt_mode, vt_flags, vt_r}, ee{MINKQ_QUERY_EE, ee_mode, ee_flags, ee_r};
            const QueryOutput vt_alone = alone(vt), ee_alone = alone(ee);
            ASSERT_EQ(vt_alone.status, MINKQ_SUCCESS) << minkq_last_error_message();
            ASSERT_EQ(ee_alone.status, MINKQ_SUCCESS) << minkq_last_error_message();
            ASSERT_GT(vt_alone.info.count, 0u) << what;
            ASSERT_GT(ee_alone.info.count, 0u) << what;
            QueryOutput vt_fused{}, ee_fused{};
            vt_fused.pairs.resize(vt_alone.pairs.size());
            ee_fused.pairs.resize(ee_alone.pairs.size());
            vt_fused.status = ee_fused.status = minkq_scene_query_vt_ee(
                scene.get(), &vt, &ee, vt_fused.pairs.data(), vt_alone.info.count, ee_fused.pairs.data(),
                ee_alone.info.count, MINKQ_MEMORY_HOST, &vt_fused.info, &ee_fused.info);
            expect_same_output(vt_alone, vt_fused, vt_flags, what + " (VT)");
            expect_same_output(ee_alone, ee_fused, ee_flags, what + " (EE)");
          }
  }
}

// A fused call whose EE pairs do not fit: CAPACITY naming EE, both counts exact, the VT pairs
// written in full and nothing past the EE buffer; results grow both buffers as needed.
TEST_F(Queries, vt_and_ee_in_one_call_report_capacity_per_query) {
  const Mesh mesh = reference::random_soup(500, seed, 0.1);
  test::Device device;
  test::Scene scene(device.get(), mesh, kBoth);
  const float r = float(0.5 * reference::mean_edge_length(mesh));
  const minkq_query_desc vt{MINKQ_QUERY_VT, MINKQ_MODE_SPHERE, MINKQ_QUERY_DIGEST, r};
  const minkq_query_desc ee{MINKQ_QUERY_EE, MINKQ_MODE_BOX, MINKQ_QUERY_CANONICAL, r};
  uint64_t vt_digest = 0;
  const Pairs vt_all = scene.query(MINKQ_QUERY_VT, MINKQ_MODE_SPHERE, r, 0, &vt_digest);
  const Pairs ee_all = scene.query(MINKQ_QUERY_EE, MINKQ_MODE_BOX, r);
  ASSERT_GT(ee_all.size(), 1u);
  std::vector<int32_t> vt_pairs(2 * vt_all.size()), ee_pairs(2 * ee_all.size() + 8, -77);
  minkq_query_info vt_info{}, ee_info{};
  const size_t ee_capacity = ee_all.size() - 1;
  EXPECT_EQ(minkq_scene_query_vt_ee(scene.get(), &vt, &ee, vt_pairs.data(), vt_all.size(), ee_pairs.data(),
                                    ee_capacity, MINKQ_MEMORY_HOST, &vt_info, &ee_info),
            MINKQ_ERROR_CAPACITY);
  const std::string message = minkq_last_error_message();
  EXPECT_EQ(message.rfind("EE: " + std::to_string(ee_all.size()) + " pairs found", 0), 0u) << message;
  EXPECT_EQ(vt_info.count, vt_all.size());
  EXPECT_EQ(vt_info.digest, vt_digest);
  EXPECT_EQ(ee_info.count, ee_all.size());
  for (size_t i = 0; i < vt_all.size(); ++i) ASSERT_EQ(vt_all[i], std::make_pair(vt_pairs[2 * i], vt_pairs[2 * i + 1]));
  for (size_t i = 2 * ee_capacity; i < ee_pairs.size(); ++i) ASSERT_EQ(ee_pairs[i], -77) << "written past the buffer";
  // VT short too: the message names VT first.
  EXPECT_EQ(minkq_scene_query_vt_ee(scene.get(), &vt, &ee, nullptr, 0, nullptr, 0, MINKQ_MEMORY_HOST, &vt_info,
                                    &ee_info),
            MINKQ_ERROR_CAPACITY);
  EXPECT_EQ(std::string(minkq_last_error_message()).rfind("VT: ", 0), 0u) << minkq_last_error_message();
  EXPECT_EQ(vt_info.count, vt_all.size());
  EXPECT_EQ(ee_info.count, ee_all.size());

  minkq_result *vt_result = nullptr, *ee_result = nullptr;
  ASSERT_EQ(minkq_result_create(&vt_result), MINKQ_SUCCESS);
  ASSERT_EQ(minkq_result_create(&ee_result), MINKQ_SUCCESS);
  for (int round = 0; round < 2; ++round) {  // grows both, then reuses them
    ASSERT_EQ(minkq_scene_query_vt_ee_result(scene.get(), &vt, &ee, vt_result, ee_result), MINKQ_SUCCESS)
        << minkq_last_error_message();
    ASSERT_EQ(minkq_result_count(vt_result), vt_all.size());
    ASSERT_EQ(minkq_result_count(ee_result), ee_all.size());
    EXPECT_EQ(minkq_result_digest(vt_result), vt_digest);
    const int32_t* ee_got = minkq_result_pairs(ee_result);
    for (size_t i = 0; i < ee_all.size(); ++i) ASSERT_EQ(ee_all[i], std::make_pair(ee_got[2 * i], ee_got[2 * i + 1]));
  }
  EXPECT_EQ(minkq_scene_query_vt_ee_result(scene.get(), &vt, &ee, vt_result, vt_result), MINKQ_ERROR_INVALID_ARGUMENT);
  minkq_result_release(vt_result);
  minkq_result_release(ee_result);
}

// A result grows to the count and an eighth more, so that a count that grows a little from one
// query to the next (a moving mesh's contacts) fits where it is: no second run, no new buffer.
TEST_F(Queries, a_result_keeps_its_buffer_while_the_count_grows_by_less_than_an_eighth) {
  const Mesh mesh = reference::twisted_sheet(40 + int(seed % 20), 3.0);
  test::Device device;
  test::Scene scene(device.get(), mesh, kBoth);
  const float r0 = float(0.25 * reference::mean_edge_length(mesh));
  const cxx::Result result = test::new_result();
  auto query = [&](float r) {
    const minkq_query_desc q{MINKQ_QUERY_EE, MINKQ_MODE_BOX, 0, r};
    EXPECT_EQ(minkq_scene_query_result(scene.get(), &q, result.get()), MINKQ_SUCCESS) << minkq_last_error_message();
    const Pairs expected = scene.query(MINKQ_QUERY_EE, MINKQ_MODE_BOX, r);
    EXPECT_EQ(minkq_result_count(result.get()), expected.size());
    const int32_t* p = minkq_result_pairs(result.get());
    Pairs got(minkq_result_count(result.get()));
    for (size_t i = 0; i < got.size(); ++i) got[i] = {p[2 * i], p[2 * i + 1]};
    std::sort(got.begin(), got.end());
    EXPECT_TRUE(got == expected);
    return expected.size();
  };
  const size_t c0 = query(r0);
  ASSERT_GT(c0, 100u);
  const int32_t* buffer = minkq_result_pairs(result.get());
  // A radius a little larger: more pairs, fewer than an eighth more.
  float r1 = r0;
  size_t c1 = c0;
  while (c1 == c0) c1 = scene.query(MINKQ_QUERY_EE, MINKQ_MODE_BOX, r1 *= 1.002f).size();
  ASSERT_LE(c1, c0 + c0 / 8);
  EXPECT_EQ(query(r1), c1);
  EXPECT_EQ(minkq_result_pairs(result.get()), buffer) << c0 << " pairs, then " << c1;
  // Twice as many pairs: it grows again, and holds them all.
  EXPECT_GT(query(2.5f * r0), 2 * c0);
}

}  // namespace
}  // namespace minkq
