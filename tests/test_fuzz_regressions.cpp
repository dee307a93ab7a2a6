// Every failure the fuzzers (fuzz/) found, as a regression test, plus a replay of scenes in the
// format the differential fuzzer prints ("paste into tests/test_fuzz_regressions.cpp"). The
// scene checks are the fuzzer's own (testing/scene_checks.h: definition, chain, oracle, refit,
// buffers, float64 input and swept steps, and every CUDA device against the CPU where one
// exists), without the Embree part.
// fuzz/RESULTS.md lists each bug with the test that covers it.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "capi_util.h"
#include "geometry_scene_checks.h"
#include "scene_checks.h"

namespace minkq {
namespace {

// Runs the differential fuzzer's checks on a scene; fails the test with its report. Returns
// what the checks counted.
fuzz::Stats replay(const fuzz::MeshScene& s) {
  const std::vector<cxx::Device> devices = fuzz::open_devices();
  fuzz::Report report;
  fuzz::Stats stats;
  if (devices.empty()) {
    ADD_FAILURE() << minkq_last_error_message();
    return stats;
  }
  fuzz::check_mesh_scene(devices, s, nullptr, report, stats);
  EXPECT_TRUE(report.ok()) << report.text() << fuzz::describe(s);
  EXPECT_EQ(stats.mesh_scenes, 1u);
  EXPECT_EQ(stats.float64_scenes, s.float64() ? 1u : 0u);
  EXPECT_EQ(stats.swept_scenes, s.swept() ? 1u : 0u);
  return stats;
}

void replay(const fuzz::BoxScene& s) {
  const std::vector<cxx::Device> devices = fuzz::open_devices();
  ASSERT_FALSE(devices.empty()) << minkq_last_error_message();
  fuzz::Report report;
  fuzz::Stats stats;
  fuzz::check_box_scene(devices, s, nullptr, report, stats);
  EXPECT_TRUE(report.ok()) << report.text() << fuzz::describe(s);
  EXPECT_EQ(stats.box_scenes, 1u);
}

// The same for a scene of many geometries (testing/geometry_scene_checks.h) on every device.
void replay(const fuzz::GeometryScene& s) {
  const std::vector<cxx::Device> devices = fuzz::open_devices();
  ASSERT_FALSE(devices.empty()) << minkq_last_error_message();
  fuzz::Report report;
  fuzz::GeometryStats stats;
  for (const cxx::Device& device : devices) fuzz::check_geometry_fuzz_scene(device.get(), s, report, stats);
  EXPECT_TRUE(report.ok()) << report.text() << fuzz::describe(s);
  EXPECT_EQ(stats.scenes, devices.size());
}

using test::Device;

// Stores an out-of-range value in an enum-typed field the way a C caller can (C enums are
// integers); the test itself never loads the field as the C++ enum type.
template <class E>
void store_raw(E& field, uint32_t value) {
  static_assert(sizeof(E) == sizeof(value), "C enums are 32-bit here");
  std::memcpy(&field, &value, sizeof value);
}

// ---- C API fuzzer findings -------------------------------------------------------------------

// fuzz_capi, bug 1 (fuzz/RESULTS.md): enum fields and arguments outside their enumerators (as
// C callers may pass) were loaded as the C++ enum type before validation: undefined behaviour
// (UBSan: "load of value 4294967295, which is not a valid value for type 'minkq_memory'").
// They are now validated through their object representation and answer INVALID_ARGUMENT.
// (By-value enum arguments, minkq_status_name's and out_memory, cannot be passed out of range
// from C++ without undefined behaviour in the test itself; fuzz/corpus/fuzz_capi holds the
// reproducers, replayed by fuzz/run.sh through capi_shim.c.)
TEST(FuzzRegressions, enum_fields_out_of_range_are_rejected) {
  Device device;
  const float xyz[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  const int32_t tri[3] = {0, 1, 2};
  minkq_scene_desc desc{};
  desc.flags = MINKQ_SCENE_VT | MINKQ_SCENE_EE;
  desc.vertices = {xyz, 0, 3, MINKQ_MEMORY_HOST};
  desc.triangles = {tri, 0, 1, MINKQ_MEMORY_HOST};
  minkq_scene* scene = nullptr;
  ASSERT_EQ(minkq_scene_create(device.get(), &desc, &scene), MINKQ_SUCCESS);
  minkq_query_info info{};
  for (uint32_t bad : {4u, 99u, 0x80000000u, 0xffffffffu}) {
    minkq_query_desc q{MINKQ_QUERY_VT, MINKQ_MODE_BOX, 0, 1.0f};
    store_raw(q.mode, bad);
    EXPECT_EQ(minkq_scene_query(scene, &q, nullptr, 0, MINKQ_MEMORY_HOST, &info), MINKQ_ERROR_INVALID_ARGUMENT) << bad;
    q = {MINKQ_QUERY_VT, MINKQ_MODE_BOX, 0, 1.0f};
    store_raw(q.kind, bad);
    EXPECT_EQ(minkq_scene_query(scene, &q, nullptr, 0, MINKQ_MEMORY_HOST, &info), MINKQ_ERROR_INVALID_ARGUMENT) << bad;
    minkq_buffer vertices{xyz, 0, 3, MINKQ_MEMORY_HOST};
    store_raw(vertices.memory, bad);
    EXPECT_EQ(minkq_scene_refit(scene, vertices), MINKQ_ERROR_INVALID_ARGUMENT) << bad;
    EXPECT_NE(std::string(minkq_last_error_message()).find("vertices.memory"), std::string::npos);
  }
  minkq_scene_release(scene);

  const float box[6] = {0, 0, 0, 1, 1, 1};
  minkq_bvh* bvh = nullptr;
  ASSERT_EQ(minkq_bvh_create(device.get(), {box, 0, 1, MINKQ_MEMORY_HOST}, &bvh), MINKQ_SUCCESS);
  const float point[3] = {0.5f, 0.5f, 2.0f};
  for (uint32_t bad : {3u, 17u, 0xfffffffeu}) {
    minkq_bvh_query_desc q{MINKQ_SHAPE_SPHERE, MINKQ_MODE_SPHERE, 0, 1.0f, {point, 0, 1, MINKQ_MEMORY_HOST}, {}};
    store_raw(q.shape, bad);
    EXPECT_EQ(minkq_bvh_query(bvh, &q, nullptr, 0, MINKQ_MEMORY_HOST, &info), MINKQ_ERROR_INVALID_ARGUMENT) << bad;
    q.shape = MINKQ_SHAPE_SPHERE;
    store_raw(q.mode, bad + 1);
    EXPECT_EQ(minkq_bvh_query(bvh, &q, nullptr, 0, MINKQ_MEMORY_HOST, &info), MINKQ_ERROR_INVALID_ARGUMENT) << bad;
  }
  EXPECT_STREQ(minkq_status_name(MINKQ_ERROR_INTERNAL), "MINKQ_ERROR_INTERNAL");
  minkq_bvh_release(bvh);
}

// fuzz_capi, bug 2 (fuzz/RESULTS.md): minkq.h says box queries take radius 0, but a non-zero
// radius was accepted (and silently grew the query boxes). It is now INVALID_ARGUMENT.
TEST(FuzzRegressions, box_queries_with_a_nonzero_radius_are_rejected) {
  Device device;
  const float box[6] = {0, 0, 0, 1, 1, 1};
  minkq_bvh* bvh = nullptr;
  ASSERT_EQ(minkq_bvh_create(device.get(), {box, 0, 1, MINKQ_MEMORY_HOST}, &bvh), MINKQ_SUCCESS);
  const float lo[3] = {1.5f, 0, 0}, hi[3] = {2, 1, 1};
  minkq_query_info info{};
  minkq_bvh_query_desc q{MINKQ_SHAPE_BOX, MINKQ_MODE_BOX, 0, 0.75f, {lo, 0, 1, MINKQ_MEMORY_HOST},
                         {hi, 0, 1, MINKQ_MEMORY_HOST}};
  EXPECT_EQ(minkq_bvh_query(bvh, &q, nullptr, 0, MINKQ_MEMORY_HOST, &info), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(minkq_last_error_message()).find("radius 0"), std::string::npos) << minkq_last_error_message();
  for (float zero : {0.0f, -0.0f}) {
    q.radius = zero;
    EXPECT_EQ(minkq_bvh_query(bvh, &q, nullptr, 0, MINKQ_MEMORY_HOST, &info), MINKQ_SUCCESS) << minkq_last_error_message();
    EXPECT_EQ(info.count, 0u);  // 0.5 apart: no overlap without a radius
  }
  minkq_bvh_release(bvh);
}

// ---- Differential fuzzer findings -------------------------------------------------------------

// fuzz_differential, bug 3 (fuzz/RESULTS.md): capsule_exact lost a true contact (distance 0)
// when the segment was longer than about 2^64: in segment_box_distance2 the closed-form
// minimiser's sums (face * d, d * d) overflowed to inf / inf = NaN, the NaN was clamped to the
// bracket's low end, and g there (the distance at the segment's start, ~2^63) rejected the
// box. Components of 2^62 and more now answer "may overlap". Found as EE pair (46,51) of a
// stacked sheet scaled by 2^70 and offset by 2^126; the first case below is that pair.
TEST(FuzzRegressions, capsule_exact_keeps_contacts_of_segments_longer_than_2_to_62) {
  for (float offset : {0x1p+126f, 0.0f, -0x1p+100f}) {
    const Vec3 p0{offset, 0x1.7e14e4p+70f, -offset}, p1{offset, 0x1.b13242p+70f, -offset};
    const Vec3 q{offset, 0x1.8p+70f, -offset};  // on the segment
    const float r = 0x1.12e0bep+41f;
    EXPECT_TRUE(CapsuleExactShape::from({p0, p1, r}).overlaps(Box::of_point(q))) << offset;
    EXPECT_TRUE(CapsuleExactShape::from({p0, p1, 0.0f}).overlaps(Box::of_point(q))) << offset;
    // The same pair as a scene: every mode, every check of the fuzzer.
    fuzz::MeshScene s;
    s.xyz = {p0.x, p0.y, p0.z, p1.x, p1.y, p1.z, q.x, q.y, q.z};
    s.tris = {0, 1, 2};
    s.edges = {0, 1, 2, 2};
    s.r = r;
    s.variant = 3145984;
    replay(s);
  }
  // Below 2^62 the distance is still computed (not answered "may overlap").
  const float d2 = segment_box_distance2({0, 0, 0}, {0x1p+61f, 0, 0}, Box::of_point({0x1p+60f, 0x1p+40f, 0}));
  EXPECT_NEAR(d2, 0x1p+80f, 0x1p+62f);
}

// fuzz_differential, bug 6 (fuzz/RESULTS.md), fixed: capsule_ray and capsule_exact lost true
// contacts of a segment whose extent along an axis exceeds FLT_MAX. CapsuleRayShape::from takes
// d = p1 - p0 in float, which overflows to infinity; every slab's t-interval (bound - o) / d is
// then about 0, so the slab test sees only the segment's start and rejects the box the segment
// passes through. capsule_exact applies the slab test first and loses the pair too. Found by
// the 10-minute campaign of 2026-12-02 as a swept step (the minimised scene below: a vertex
// flying from -P to P through a point triangle at the origin, |P.y| ~ 2^127, r ~ 2.1e28), and it
// is the same for a static EE edge (the second scene). Fixed: such a segment's shape leaves the
// decision to its box test (CapsuleRayShape::box_decides).
fuzz::MeshScene segments_longer_than_flt_max(bool swept) {
  fuzz::MeshScene s;
  if (swept) {
    s.xyz = {0, 0, 0, 0, 0, 0, 0, 0, 0};
    s.tris = {0, 0, 0};
    s.r = 0x1.12e0bep+94f;  // 2.12676473e+28
    s.moved = std::vector<float>(9, -0x1.0c6f7ap+103f);
    s.swept0 = {0, 0, 0, 0, 0, 0, -0x1.45697cp+125f, 0x1.0f2d3cp+127f, -0x1.2a4b5cp+126f};
    s.swept1 = {0, 0, 0, 0, 0, 0, 0x1.45697cp+125f, -0x1.0f2d3cp+127f, 0x1.2a4b5cp+126f};
  } else {  // edge 0-1 through the origin, where the zero-length edge 2-3 lies
    s.xyz = {-0x1.45697cp+125f, 0x1.0f2d3cp+127f, -0x1.2a4b5cp+126f, 0x1.45697cp+125f, -0x1.0f2d3cp+127f,
             0x1.2a4b5cp+126f, 0, 0, 0, 0, 0, 0};
    s.tris = {2, 2, 3};
    s.edges = {0, 1, 2, 3};
    s.r = 1.0f;
  }
  return s;
}

TEST(FuzzRegressions, segment_modes_keep_contacts_of_segments_longer_than_flt_max) {
  for (bool swept : {true, false}) replay(segments_longer_than_flt_max(swept));
}

// fuzz_differential, bug 7 (fuzz/RESULTS.md), fixed: minkq.h says a swept step of zero motion
// gives the static pairs (VT sphere and capsule_exact: the static sphere mode's). Swept, a
// still vertex was a zero-length segment under CapsuleExactShape, whose threshold has more
// slack than SphereShape's: on this sheet at offset 1e3 (r = 0.5593088) six pairs at point-box
// distance r (1 + 3.6e-6) were kept by the still step's sphere and capsule_exact modes and
// dropped by the static sphere mode. Found by the campaign of 2026-12-02 (the scene as it
// printed it). Fixed: a point (p0 == p1) takes the point tests in the segment shapes
// (compare_still_step requires the sets equal).
fuzz::MeshScene still_sheet_at_the_sphere_tests_boundary() {
  fuzz::MeshScene s;
  s.xyz = {0x1.f4p+9f, 0x1.f4p+9f, 0x1.f4p+9f,
    0x1.f42p+9f, 0x1.f4p+9f, 0x1.f3fdbp+9f,
    0x1.f42p+9f, 0x1.f44p+9f, 0x1.f3fdbp+9f,
    0x1.f4p+9f, 0x1.f44p+9f, 0x1.f4p+9f,
    0x1.f44p+9f, 0x1.f4p+9f, 0x1.f3fb5ep+9f,
    0x1.f4p+9f, 0x1.f4p+9f, 0x1.f4p+9f,
    0x1.f46p+9f, 0x1.f4p+9f, 0x1.f3f90ep+9f,
    0x1.f46p+9f, 0x1.f44p+9f, 0x1.f3f90ep+9f,
    0x1.f48p+9f, 0x1.f4p+9f, 0x1.f3f6bcp+9f,
    0x1.f4p+9f, 0x1.f4p+9f, 0x1.f4p+9f,
    0x1.f42p+9f, 0x1.f48p+9f, 0x1.f3fdbp+9f,
    0x1.f4p+9f, 0x1.f48p+9f, 0x1.f4p+9f,
    0x1.f44p+9f, 0x1.f48p+9f, 0x1.f3fb5ep+9f};
  s.tris = {0, 1, 2, 0, 2, 3, 1, 4, 5, 1, 5, 2, 4, 6, 7, 4, 7, 5, 6, 8, 9, 6, 9, 7,
    3, 2, 10, 3, 10, 11, 2, 5, 12, 2, 12, 10};
  s.r = 0x1.1e5dbap-1f;  // 0.559308827
  s.drop_incident = false;
  s.moved = s.xyz;
  s.swept0 = s.xyz;
  s.swept1 = s.xyz;
  s.variant = 1682314176;
  return s;
}

TEST(FuzzRegressions, still_swept_step_gives_exactly_the_static_sphere_pairs) {
  EXPECT_EQ(replay(still_sheet_at_the_sphere_tests_boundary()).still_steps, 1u);
}

// ---- Scenes in the differential fuzzer's format --------------------------------------------

// Two layers at a gap equal to r in float (the fuzzer's "stacked" kind at its boundary case),
// moved for a refit: every check of the fuzzer, through the format it prints.
TEST(FuzzRegressions, replay_stacked_layers_at_gap_r_with_refit) {
  fuzz::MeshScene s;
  s.xyz = {0x0p+0f, 0x0p+0f, 0x0p+0f,  0x1p+0f, 0x0p+0f, 0x0p+0f,  0x0p+0f, 0x1p+0f, 0x0p+0f,
           0x1p+0f, 0x1p+0f, 0x0p+0f,  0x0p+0f, 0x0p+0f, 0x1.99999ap-4f, 0x1p+0f, 0x0p+0f, 0x1.99999ap-4f,
           0x0p+0f, 0x1p+0f, 0x1.99999ap-4f, 0x1p+0f, 0x1p+0f, 0x1.99999ap-4f};
  s.tris = {0, 1, 3, 0, 3, 2, 4, 5, 7, 4, 7, 6};
  s.r = 0x1.99999ap-4f;  // the gap
  s.drop_incident = true;
  s.moved = s.xyz;
  for (size_t i = 2; i < s.moved.size(); i += 3) s.moved[i] += 0x1p-30f;
  for (uint32_t variant : {0u, 0x5555u, 0xaaaaaaaau, 0xffffffffu}) {
    s.variant = variant;
    replay(s);
  }
}

// The EE leaf-exact test in the order the traversal met the pair (the edge earlier in the tree's
// leaf order first) instead of the pair's own order: at coordinates near 2^126 the rounding of
// the two orders differed and minkq kept two pairs the definition did not. Found by
// fuzz_differential after EE traversal began visiting each pair once.
TEST(FuzzRegressions, ee_leaf_exact_is_evaluated_in_the_pairs_own_order) {
  fuzz::MeshScene s;
  s.xyz = {0x0p+0f, 0x0p+0f, -0x1p+126f,
    0x1p+97f, 0x0p+0f, -0x1p+126f,
    0x1p+98f, 0x0p+0f, -0x1p+126f,
    0x1.8p+98f, 0x0p+0f, -0x1p+126f,
    0x0p+0f, 0x0p+0f, -0x1p+126f,
    0x0p+0f, 0x1p+97f, -0x1p+126f,
    0x1p+97f, 0x1p+97f, -0x1p+126f,
    0x1p+98f, 0x1p+97f, -0x1p+126f,
    0x1.8p+98f, 0x1p+97f, -0x1p+126f,
    0x1p+99f, 0x1p+97f, -0x1p+126f,
    0x0p+0f, 0x1p+98f, -0x1p+126f,
    0x1p+97f, 0x1p+98f, -0x1p+126f,
    0x1p+98f, 0x1p+98f, -0x1p+126f,
    0x1.8p+98f, 0x1p+98f, -0x1p+126f,
    0x1p+99f, 0x1p+98f, -0x1p+126f,
    0x0p+0f, 0x1.8p+98f, -0x1p+126f,
    0x1p+97f, 0x1.8p+98f, -0x1p+126f,
    0x1p+98f, 0x1.8p+98f, -0x1p+126f,
    0x1.8p+98f, 0x1.8p+98f, -0x1p+126f,
    0x1p+99f, 0x1.8p+98f, -0x1p+126f,
    0x0p+0f, 0x1p+99f, -0x1p+126f,
    0x1p+97f, 0x1p+99f, -0x1p+126f,
    0x1p+98f, 0x1p+99f, -0x1p+126f,
    0x1.8p+98f, 0x1p+99f, -0x1p+126f,
    0x1p+99f, 0x1p+99f, -0x1p+126f,
    0x0p+0f, 0x0p+0f, -0x1p+126f,
    0x1p+97f, 0x0p+0f, -0x1p+126f,
    0x1p+98f, 0x0p+0f, -0x1p+126f,
    0x1.8p+98f, 0x0p+0f, -0x1p+126f,
    0x1p+99f, 0x0p+0f, -0x1p+126f,
    0x0p+0f, 0x1p+97f, -0x1p+126f,
    0x1p+97f, 0x1p+97f, -0x1p+126f,
    0x1p+98f, 0x1p+97f, -0x1p+126f,
    0x1.8p+98f, 0x1p+97f, -0x1p+126f,
    0x1p+99f, 0x1p+97f, -0x1p+126f,
    0x0p+0f, 0x1p+98f, -0x1p+126f,
    0x1p+97f, 0x1p+98f, -0x1p+126f,
    0x1p+98f, 0x1p+98f, -0x1p+126f,
    0x1.8p+98f, 0x1p+98f, -0x1p+126f,
    0x1p+99f, 0x1p+98f, -0x1p+126f,
    0x0p+0f, 0x1.8p+98f, -0x1p+126f,
    0x1p+97f, 0x1.8p+98f, -0x1p+126f,
    0x1p+98f, 0x1.8p+98f, -0x1p+126f,
    0x1.8p+98f, 0x1.8p+98f, -0x1p+126f,
    0x1p+99f, 0x1.8p+98f, -0x1p+126f,
    0x0p+0f, 0x1p+99f, -0x1p+126f,
    0x1p+97f, 0x1p+99f, -0x1p+126f,
    0x1p+98f, 0x1p+99f, -0x1p+126f,
    0x1.8p+98f, 0x1p+99f, -0x1p+126f,
    0x1p+99f, 0x1p+99f, -0x1p+126f};
  s.tris = {0, 1, 6, 0, 6, 5, 1, 2, 7, 1, 7, 6, 2, 3, 8, 2, 8, 7, 3, 4, 9, 3, 9, 8,
    5, 6, 11, 5, 11, 10, 6, 7, 12, 6, 12, 11, 7, 8, 13, 7, 13, 12, 8, 9, 14, 8, 14, 13,
    10, 11, 16, 10, 16, 15, 11, 12, 17, 11, 17, 16, 12, 13, 18, 12, 18, 17, 13, 14, 19, 13, 19, 18,
    15, 16, 21, 15, 21, 20, 16, 17, 22, 16, 22, 21, 17, 18, 23, 17, 23, 22, 18, 19, 24, 18, 24, 23,
    25, 26, 31, 25, 31, 30, 26, 27, 32, 26, 32, 31, 27, 28, 33, 27, 33, 32, 28, 29, 34, 28, 34, 33,
    30, 31, 36, 30, 36, 35, 31, 32, 37, 31, 37, 36, 32, 33, 38, 32, 38, 37, 33, 34, 39, 33, 39, 38,
    35, 36, 41, 35, 41, 40, 36, 37, 42, 36, 42, 41, 37, 38, 43, 37, 43, 42, 38, 39, 44, 38, 44, 43,
    40, 41, 46, 40, 46, 45, 41, 42, 47, 41, 47, 46, 42, 43, 48, 42, 48, 47, 43, 44, 49, 43, 49, 48};
  s.r = 0x1.12e0bep+69f;  // 6.33825282e+20
  s.drop_incident = false;
  s.moved = {-0x1.0c6f7ap+78f, -0x1.0c6f7ap+78f, -0x1p+126f,
    0x1.fffffp+96f, -0x1.f94a5p+73f, -0x1p+126f,
    0x1.fffff8p+97f, -0x1.4a11a4p+77f, -0x1p+126f,
    0x1.7ffffp+98f, -0x1.0c6f7ap+78f, -0x1p+126f,
    -0x1.0c6f7ap+78f, -0x1.0c6f7ap+78f, -0x1p+126f,
    -0x1.0c6f7ap+78f, 0x1.ffffbcp+96f, -0x1p+126f,
    0x1.ffffbcp+96f, 0x1.ffffbcp+96f, -0x1p+126f,
    0x1.ffffdep+97f, 0x1.ffffbcp+96f, -0x1p+126f,
    0x1.7ffffp+98f, 0x1.ffffbcp+96f, -0x1p+126f,
    0x1.fffffp+98f, 0x1.ffffbep+96f, -0x1p+126f,
    -0x1.2dfc7ep+77f, 0x1.ffffdep+97f, -0x1p+126f,
    0x1.ffffep+96f, 0x1.ffffdep+97f, -0x1p+126f,
    0x1.ffffdep+97f, 0x1.ffffdep+97f, -0x1p+126f,
    0x1.7ffffp+98f, 0x1.ffffdep+97f, -0x1p+126f,
    0x1.fffffp+98f, 0x1.ffffdep+97f, -0x1p+126f,
    -0x1.0c6f7ap+78f, 0x1.7ffffp+98f, -0x1p+126f,
    0x1.ffffbcp+96f, 0x1.7ffffp+98f, -0x1p+126f,
    0x1.ffffdep+97f, 0x1.7ffffp+98f, -0x1p+126f,
    0x1.7ffffp+98f, 0x1.7ffffp+98f, -0x1p+126f,
    0x1.fffffp+98f, 0x1.7ffffp+98f, -0x1p+126f,
    -0x1.0c6f7ap+78f, 0x1.fffffp+98f, -0x1p+126f,
    0x1.ffffbcp+96f, 0x1.fffffp+98f, -0x1p+126f,
    0x1.ffffdep+97f, 0x1.fffffp+98f, -0x1p+126f,
    0x1.7ffffp+98f, 0x1.fffffp+98f, -0x1p+126f,
    0x1.fffffp+98f, 0x1.fffffp+98f, -0x1p+126f,
    -0x1.0c6f7ap+78f, -0x1.0c6f7ap+78f, -0x1p+126f,
    0x1.ffffbcp+96f, -0x1.0c6f7ap+78f, -0x1p+126f,
    0x1.ffffdep+97f, -0x1.0c6f7ap+78f, -0x1p+126f,
    0x1.7ffffp+98f, -0x1.0c6f7ap+78f, -0x1p+126f,
    0x1.fffffp+98f, -0x1.0c6f7ap+78f, -0x1p+126f,
    -0x1.0c6f7ap+78f, 0x1.ffffbcp+96f, -0x1p+126f,
    0x1.ffffbcp+96f, 0x1.ffffbcp+96f, -0x1p+126f,
    0x1.ffffdep+97f, 0x1.ffffbcp+96f, -0x1p+126f,
    0x1.7ffffp+98f, 0x1.ffffbcp+96f, -0x1p+126f,
    0x1.fffffp+98f, 0x1.ffffbcp+96f, -0x1p+126f,
    -0x1.0c6f7ap+78f, 0x1.ffffdep+97f, -0x1p+126f,
    0x1.ffffbcp+96f, 0x1.ffffdep+97f, -0x1p+126f,
    0x1.ffffdep+97f, 0x1.ffffdep+97f, -0x1p+126f,
    0x1.7ffffp+98f, 0x1.ffffdep+97f, -0x1p+126f,
    0x1.fffffp+98f, 0x1.ffffdep+97f, -0x1p+126f,
    -0x1.0c6f7ap+78f, 0x1.7ffffp+98f, -0x1p+126f,
    0x1.ffffbcp+96f, 0x1.7ffffp+98f, -0x1p+126f,
    0x1.ffffdep+97f, 0x1.7ffffp+98f, -0x1p+126f,
    0x1.7ffffp+98f, 0x1.7ffffp+98f, -0x1p+126f,
    0x1.fffffp+98f, 0x1.7ffffp+98f, -0x1p+126f,
    -0x1.0c6f7ap+78f, 0x1.fffffp+98f, -0x1p+126f,
    0x1.ffffbcp+96f, 0x1.fffffp+98f, -0x1p+126f,
    0x1.ffffdep+97f, 0x1.fffffp+98f, -0x1p+126f,
    0x1.7ffffp+98f, 0x1.fffffp+98f, -0x1p+126f,
    0x1.fffffp+98f, 0x1.fffffp+98f, -0x1p+126f};
  s.variant = 6422528;
  replay(s);
}

// Coincident vertices, a point triangle and an explicit zero-length edge at radius 0.
TEST(FuzzRegressions, replay_cluster_of_coincident_vertices_at_radius_zero) {
  fuzz::MeshScene s;
  s.xyz = {0x1p-1f, 0x1p-1f, 0x1p-1f, 0x1p-1f, 0x1p-1f, 0x1p-1f, 0x1.000002p-1f, 0x1p-1f, 0x1p-1f, 0x0p+0f, 0x0p+0f, 0x0p+0f};
  s.tris = {0, 1, 2, 1, 1, 1, 0, 2, 3};
  s.edges = {0, 1, 2, 2, 0, 3, 1, 3, 0, 1};
  s.r = 0.0f;
  s.variant = 7;
  replay(s);
  s.drop_incident = true;
  replay(s);
}

// A capsule scene over user boxes, with a refit.
TEST(FuzzRegressions, replay_user_box_capsules_with_refit) {
  fuzz::BoxScene s;
  s.boxes = {0, 0, 0, 1, 1, 1, 2, 0, 0, 2, 1, 1, 0.5f, 0.5f, 3, 0.5f, 0.5f, 3};
  s.shape = MINKQ_SHAPE_CAPSULE;
  s.first = {-1, 0.5f, 0.5f, 1.5f, -1, 0.5f};
  s.second = {3, 0.5f, 0.5f, 1.5f, 2, 0.5f};
  s.r = 0.25f;
  s.moved = s.boxes;
  for (float& x : s.moved) x += 0.125f;
  s.variant = 0x1234567u;
  replay(s);
}

// ---- Float64 and swept scenes in the differential fuzzer's format ----------------------------

// The float spacing at x (x > 0).
double spacing(float x) { return double(std::nextafter(x, INFINITY)) - double(x); }

// Float64 input that rounding to float pulls apart: a vertex 0.95 r in front of a triangle, and
// an edge 0.95 r from two of its edges, near 2e4 where the float spacing (2^-9) exceeds r = 1e-3.
// Rounded to nearest, plane and point lie a whole spacing (> r) apart, so a float scene of the
// rounding loses both pairs; the float64 scene (radius widened by 2 rho) must find them in every
// mode, and its refit to other doubles too.
TEST(FuzzRegressions, replay_float64_pairs_that_rounding_pulls_apart) {
  const double u = spacing(2e4f), r = 1e-3;
  const double plane = 2e4 + 0.49 * u, point = plane + 0.95 * r;
  ASSERT_GT(double(float(point)) - double(float(plane)), r);  // the rounding pulls them apart
  fuzz::MeshScene s;
  s.xyz64 = {plane, -1, -1, plane, 2, -1, plane, -1, 2,  // triangle 0, in the plane x = plane
             point, 0, 0,                                // vertex 3, 0.95 r in front of it
             point, 0.5, -1, point, 0.5, 1};             // edge 4-5, 0.95 r from edges 0-1 and 1-2
  s.tris = {0, 1, 2};
  s.edges = {0, 1, 0, 2, 1, 2, 4, 5};
  s.r = float(r);
  s.drop_incident = true;
  // The refit moves everything by -0.2 u: still 0.95 r apart, and still pulled apart by rounding.
  ASSERT_GT(double(float(point - 0.2 * u)) - double(float(plane - 0.2 * u)), r);
  s.moved64 = s.xyz64;
  for (size_t i = 0; i < s.moved64.size(); i += 3) s.moved64[i] -= 0.2 * u;
  for (uint32_t variant : {0u, 0x2468aceu, 0xffffffffu}) {
    s.variant = variant;
    // VT (3, 0), (4, 0) and EE (0, 3), (2, 3) (vertex 4 and edge 4-5 touch the triangle's edge
    // 0-1 too), before and after the refit.
    EXPECT_EQ(replay(s).true_contacts, 8u);
  }
}

// A vertex and an edge fly through a triangle and an edge that stay still, far past them
// (motions up to 10^4 times the elements' size), apart at t = 0 and t = 1: the swept step must
// find both pairs (the static oracle sees them at t = 1/2), in every VT mode and in EE box mode.
TEST(FuzzRegressions, replay_swept_step_flying_far_past_still_elements) {
  for (float length : {1.0f, 100.0f, 1e4f}) {
    fuzz::MeshScene s;
    s.xyz = {0, -1, -1, 0, 2, -1, 0, -1, 2,                           // triangle 0 in the plane x = 0 (still)
             -length, 0.1f, 0.1f,                                     // vertex 3: crosses the triangle
             0, 0, -5, 0, 0, -4,                                      // edge 4-5 along z (still)
             -length, 0.5f, -4.5f, -length, -0.5f, -4.5f};            // edge 6-7 along y: sweeps through it
    s.tris = {0, 1, 2};
    s.edges = {0, 1, 0, 2, 1, 2, 4, 5, 6, 7};
    s.r = 0.01f;
    s.drop_incident = true;
    s.swept0 = s.xyz;
    s.swept1 = s.xyz;
    s.swept1[9] = s.swept1[18] = s.swept1[21] = length;
    for (uint32_t variant : {0u, 1u << 26, 0x5a5a5a5au}) {  // bit 26: rebuild_swept, else refit_swept
      s.variant = variant;
      EXPECT_EQ(replay(s).sampled_contacts, 2u) << "the oracle sees (3, 0) and EE (3, 4) at t = 1/2";
    }
  }
}

// A step of zero motion (two layers at a gap equal to r in float) gives the static sets; so
// does a float64 step of zero motion far from the origin, with sub-ulp detail, whose refit and
// swept step then move one layer through the other.
TEST(FuzzRegressions, replay_swept_steps_of_zero_motion_and_float64_steps) {
  fuzz::MeshScene s;
  s.xyz = {0x0p+0f, 0x0p+0f, 0x0p+0f,  0x1p+0f, 0x0p+0f, 0x0p+0f,  0x0p+0f, 0x1p+0f, 0x0p+0f,
           0x1p+0f, 0x1p+0f, 0x0p+0f,  0x0p+0f, 0x0p+0f, 0x1.99999ap-4f, 0x1p+0f, 0x0p+0f, 0x1.99999ap-4f,
           0x0p+0f, 0x1p+0f, 0x1.99999ap-4f, 0x1p+0f, 0x1p+0f, 0x1.99999ap-4f};
  s.tris = {0, 1, 3, 0, 3, 2, 4, 5, 7, 4, 7, 6};
  s.r = 0x1.99999ap-4f;  // the gap
  s.swept0 = s.swept1 = s.xyz;
  for (bool drop : {false, true}) {
    s.drop_incident = drop;
    s.variant = drop ? 0x4000001u : 6u;
    EXPECT_EQ(replay(s).still_steps, 1u);
  }
  // The same layers as doubles at 3e6 + detail below the float spacing (0.25 there).
  fuzz::MeshScene d;
  d.tris = s.tris;
  d.r = 0.125f;
  for (size_t i = 0; i < s.xyz.size(); ++i) d.xyz64.push_back(3e6 + double(s.xyz[i]) + 0.01 * double(i % 5));
  d.swept0_64 = d.swept1_64 = d.xyz64;
  EXPECT_EQ(replay(d).still_steps, 1u);
  d.moved64 = d.xyz64;
  d.swept1_64 = d.xyz64;
  for (size_t i = 14; i < d.xyz64.size(); i += 3) {  // the upper layer (vertices 4-7): z
    d.moved64[i] += 0.03;                           // a refit a fraction of the spacing up
    d.swept0_64[i] += 2.0;                          // and a step from above, through the other layer, to below
    d.swept1_64[i] -= 3.0;
  }
  for (uint32_t variant : {0u, 1u << 26}) {
    d.variant = variant;
    EXPECT_GT(replay(d).sampled_contacts, 0u);
  }
}

// A scene of many geometries as the differential fuzzer prints it (a seed of its corpus): a
// static rod set (SELF; EE, VV and EV) beside a mesh (VT), swept as a whole scene (the mesh
// alone moves, far across the rods): every swept mode against the oracle at sampled times, the
// refit back, and the first geometry alone against minkq_scene_create.
TEST(FuzzRegressions, replay_geometry_scene_swept_as_a_whole) {
  // soup rods, soup mesh, r 0.2421875, step 3 of -1, motion 4
  fuzz::GeometryScene s;
  s.r = 0x1.fp-3f;
  s.variant = 1288703686;
  s.step = fuzz::GeometryStep::kSwept;
  s.moving = -1;
  s.geometries.emplace_back();
  s.geometries[0].mesh.xyz = {0x1.0ap+6f, 0x1.b4p+6f, 0x1.6cp+5f,
      0x1.b8p+5f, 0x1.46p+6f, 0x1.44p+6f,
      0x1.54p+6f, 0x1.9cp+5f, 0x1.84p+5f,
      0x1.04p+5f, 0x1.18p+6f, 0x1.f4p+5f,
      0x1.6cp+5f, 0x1.38p+5f, 0x1.fp+4f,
      0x1.9cp+5f, 0x1.8p+4f, 0x1.dcp+6f,
      0x1.bp+4f, 0x1.26p+6f, 0x1.2cp+6f,
      0x1p+5f, 0x1.1cp+6f, 0x1.5ep+6f,
      0x1.acp+6f, 0x1.0cp+5f, 0x1p+6f};
  s.geometries[0].mesh.tris = {};
  s.geometries[0].mesh.edges = {0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5, 6, 6, 7, 7, 8, 4, 5, 6, 8, 7, 7};
  s.geometries[0].kinds = 50, s.geometries[0].flags = 9, s.geometries[0].world = 0, s.geometries[0].group = 163u, s.geometries[0].mask = 4294967295u;
  s.geometries.emplace_back();
  s.geometries[1].mesh.xyz = {0x1.daeap+6f, 0x1.ca3ap+6f, 0x1.4c98p+4f,
      0x1.ef6ap+6f, 0x1.ba5cp+5f, 0x1.d9e4p+6f,
      0x1.374p+2f, 0x1.8db4p+6f, 0x1.ad92p+6f,
      0x1.5cfp+6f, 0x1.f01p+6f, 0x1.f5e8p+5f,
      0x1.c0b4p+6f, 0x1.85c8p+6f, 0x1.a834p+5f,
      0x1.f308p+5f, 0x1.155cp+5f, 0x1.4eap+2f,
      0x1.1p-2f, 0x1.720cp+6f, 0x1.8024p+6f,
      0x1.c11cp+6f, 0x1.0a62p+6f, 0x1.222cp+5f,
      0x1.a92cp+6f, 0x1.5c5cp+6f, 0x1.cffap+6f,
      0x1.c66p+3f, 0x1.ab0cp+5f, 0x1.51c8p+6f};
  s.geometries[1].mesh.tris = {4, 9, 7, 2, 4, 0, 0, 0, 0, 0, 0, 0};
  s.geometries[1].mesh.edges = {};
  s.geometries[1].kinds = 1, s.geometries[1].flags = 0, s.geometries[1].world = 0, s.geometries[1].group = 1u, s.geometries[1].mask = 4294967295u;
  s.moved.push_back(s.geometries[0].mesh);
  s.moved.emplace_back();
  s.moved[1].xyz = {-0x1.128bp+7f, -0x1.1ae3p+7f, -0x1.d66dp+7f,
      -0x1.084bp+7f, -0x1.9169p+7f, -0x1.130ep+7f,
      -0x1.f646p+7f, -0x1.3926p+7f, -0x1.2937p+7f,
      -0x1.5188p+7f, -0x1.07f8p+7f, -0x1.8286p+7f,
      -0x1.1fa6p+7f, -0x1.3d1cp+7f, -0x1.95f3p+7f,
      -0x1.833ep+7f, -0x1.baa9p+7f, -0x1.f58bp+7f,
      -0x1.ff78p+7f, -0x1.46fap+7f, -0x1.3feep+7f,
      -0x1.1f72p+7f, -0x1.7acfp+7f, -0x1.b775p+7f,
      -0x1.2b6ap+7f, -0x1.51d2p+7f, -0x1.1803p+7f,
      -0x1.e39ap+7f, -0x1.953dp+7f, -0x1.571cp+7f};
  replay(s);
}

}  // namespace
}  // namespace minkq
