// Scenes of many geometries (minkq_scene_create_geometries), through the C API, against the
// oracle's contacts in the global numbering (reference::geometry_contacts): a cloth over a
// static body (cross pairs, then self pairs too), groups and masks, worlds, per-vertex
// thickness, double input, swept steps, moving geometries refit one at a time and all at once,
// a one-geometry scene equal to a one-mesh scene, the global numbering of edges and ranges,
// and the refusals of bad descriptions. Fresh random inputs each run (the seed is printed;
// MINKQ_TEST_SEED repeats one).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iterator>
#include <string>
#include <vector>

#include "capi_util.h"
#include "geometry_scenes.h"
#include "minkq_reference.h"
#include "test_util.h"

namespace minkq {
namespace {

namespace ref = reference;
using ref::Geometry;
using ref::Mesh;
using test::kAllKinds;
using test::Pairs;

constexpr uint32_t kSelfDrop = MINKQ_GEOMETRY_SELF | MINKQ_GEOMETRY_DROP_INCIDENT;

// The height of the static body's surface over (x, y).
double body_height(double x, double y) { return 0.08 * std::sin(5 * x) * std::cos(4 * y); }

// A bumpy body surface (n x n vertices on the unit square).
Mesh body_mesh(int n) {
  Mesh m = ref::grid_sheet(n);
  for (size_t v = 0; v < m.vertex_count(); ++v) m.xyz[3 * v + 2] = float(body_height(m.xyz[3 * v], m.xyz[3 * v + 1]));
  return m;
}

// An n x n cloth over [0.1, 0.9]^2 hovering over the body, each vertex between `low` and
// `high` above the surface.
Mesh cloth_mesh(test::Random& rng, int n, double low, double high) {
  Mesh m = ref::grid_sheet(n);
  for (size_t v = 0; v < m.vertex_count(); ++v) {
    const double x = 0.1 + 0.8 * m.xyz[3 * v], y = 0.1 + 0.8 * m.xyz[3 * v + 1];
    m.xyz[3 * v] = float(x), m.xyz[3 * v + 1] = float(y);
    m.xyz[3 * v + 2] = float(body_height(x, y) + rng.uniform(float(low), float(high)));
  }
  return m;
}

// A mesh moved by a smooth field of amplitude `amount`, in float (or double for xyz64).
Mesh moved(const Mesh& mesh, double amount, double phase) {
  Mesh m = mesh;
  auto shift = [&](size_t i) { return amount * std::sin(0.37 * double(i / 3) + phase + 1.7 * double(i % 3)); };
  if (!m.xyz64.empty()) {
    std::vector<double> xyz = m.xyz64;
    for (size_t i = 0; i < xyz.size(); ++i) xyz[i] += shift(i);
    ref::set_float64(m, std::move(xyz));
  } else {
    for (size_t i = 0; i < m.xyz.size(); ++i) m.xyz[i] = float(m.xyz[i] + shift(i));
  }
  return m;
}

std::vector<float> random_thickness(test::Random& rng, size_t n, float most) {
  std::vector<float> t(n);
  for (float& x : t) x = rng.integer(0, 3) == 0 ? 0.0f : rng.uniform(0, most);
  return t;
}

// The cross pairs of `kind` among `pairs`: those whose elements lie in different geometries.
size_t cross_count(const std::vector<Geometry>& g, ref::Kind kind, const Pairs& pairs) {
  const int first_element = kind == ref::Kind::EE ? 2 : 0;
  const int second_element = kind == ref::Kind::VT ? 1 : kind == ref::Kind::VV ? 0 : 2;
  auto owner = [&](int element, int32_t id) {
    for (size_t i = 0; i < g.size(); ++i) {
      const auto [first, count] = ref::geometry_range(g, i, element);
      if (size_t(id) >= first && size_t(id) < first + count) return i;
    }
    return g.size();
  };
  size_t n = 0;
  for (const auto& [a, b] : pairs) n += owner(first_element, a) != owner(second_element, b);
  return n;
}

TEST(Geometries, cloth_over_a_static_body_cross_pairs_then_self_pairs) {
  const test::Device cpu;
  test::Random rng(test::fresh_seed());
  const Mesh cloth = cloth_mesh(rng, 14, -0.02, 0.1);
  const float r = float(0.5 * ref::mean_edge_length(cloth));
  std::vector<Geometry> g = {test::make_geometry(cloth, kAllKinds, 0),
                             test::make_geometry(body_mesh(20), kAllKinds, MINKQ_GEOMETRY_STATIC)};
  {
    cxx::Scene scene = test::new_geometry_scene(cpu.get(), g);
    for (ref::Kind kind : test::kAllQueryKinds) {
      const Pairs truth = test::check_kind(scene.get(), g, kind, r, "cross only");
      EXPECT_FALSE(truth.empty()) << test::kind_name(kind);
      EXPECT_EQ(cross_count(g, kind, truth), truth.size()) << "no geometry has SELF";
    }
  }
  g[0].flags |= kSelfDrop;
  g[1].flags |= kSelfDrop;
  cxx::Scene scene = test::new_geometry_scene(cpu.get(), g);
  for (ref::Kind kind : test::kAllQueryKinds) {
    const Pairs truth = test::check_kind(scene.get(), g, kind, r, "self and cross");
    if (kind != ref::Kind::VV)  // VV: no two vertices of the grids lie within r
      EXPECT_LT(cross_count(g, kind, truth), truth.size()) << test::kind_name(kind) << ": self pairs too";
  }
  // The combined VT + EE call and COUNT give each query's own pairs and count.
  const cxx::Result vt = test::new_result(), ee = test::new_result();
  const minkq_query_desc vt_desc{MINKQ_QUERY_VT, MINKQ_MODE_BOX, MINKQ_QUERY_CANONICAL | MINKQ_QUERY_LEAF_EXACT, r};
  const minkq_query_desc ee_desc{MINKQ_QUERY_EE, MINKQ_MODE_CAPSULE_EXACT, MINKQ_QUERY_CANONICAL, r};
  ASSERT_EQ(minkq_scene_query_vt_ee_result(scene.get(), &vt_desc, &ee_desc, vt.get(), ee.get()), MINKQ_SUCCESS)
      << minkq_last_error_message();
  for (auto [result, desc] : {std::pair{vt.get(), vt_desc}, std::pair{ee.get(), ee_desc}}) {
    const Pairs alone = test::Scene::query_pairs(scene.get(), desc.kind, desc.mode, r, desc.flags);
    const int32_t* raw = minkq_result_pairs(result);
    Pairs got(minkq_result_count(result));
    for (size_t i = 0; i < got.size(); ++i) got[i] = {raw[2 * i], raw[2 * i + 1]};
    EXPECT_EQ(got, alone) << "kind " << desc.kind;
    minkq_query_desc count = desc;
    count.flags = MINKQ_QUERY_COUNT | (desc.flags & MINKQ_QUERY_LEAF_EXACT);
    minkq_query_info info{};
    ASSERT_EQ(minkq_scene_query(scene.get(), &count, nullptr, 0, MINKQ_MEMORY_HOST, &info), MINKQ_SUCCESS);
    EXPECT_EQ(info.count, alone.size()) << "kind " << desc.kind;
  }
}

// Moving geometries refit or rebuilt one at a time, or all at once from one buffer of theirs
// in geometry order; a static geometry is refused, and a refused call keeps the scene as it was.
TEST(Geometries, moving_geometries_refit_alone_or_together_and_static_ones_are_refused) {
  const test::Device cpu;
  test::Random rng(test::fresh_seed());
  Mesh rods;  // short rods over the body: explicit edges, no triangles
  for (int k = 0; k < 30; ++k) {
    const float x = rng.uniform(0.1f, 0.9f), y = rng.uniform(0.1f, 0.9f), z = float(body_height(x, y)) + 0.03f;
    const int32_t v = int32_t(rods.vertex_count());
    rods.xyz.insert(rods.xyz.end(), {x, y, z, x + 0.05f, y + rng.uniform(-0.05f, 0.05f), z + 0.01f});
    rods.edges.insert(rods.edges.end(), {v, v + 1});
  }
  const Mesh cloth = cloth_mesh(rng, 12, 0.0, 0.08);
  const float r = float(0.5 * ref::mean_edge_length(cloth));
  std::vector<Geometry> g = {test::make_geometry(rods, ref::kKindEE | ref::kKindVV | ref::kKindEV, kSelfDrop),
                             test::make_geometry(body_mesh(16), kAllKinds, MINKQ_GEOMETRY_STATIC),
                             test::make_geometry(cloth, kAllKinds, kSelfDrop)};
  cxx::Scene scene = test::new_geometry_scene(cpu.get(), g);
  test::check_scene(scene.get(), g, r, "as created");

  g[2].mesh = moved(cloth, 0.03, 0.5);
  ASSERT_EQ(minkq_scene_geometry_refit(scene.get(), 2, test::geometry_vertices(g[2])), MINKQ_SUCCESS)
      << minkq_last_error_message();
  test::check_scene(scene.get(), g, r, "cloth refit alone");
  g[0].mesh = moved(rods, 0.02, 1.5);
  ASSERT_EQ(minkq_scene_geometry_rebuild(scene.get(), 0, test::geometry_vertices(g[0])), MINKQ_SUCCESS)
      << minkq_last_error_message();
  test::check_scene(scene.get(), g, r, "rods rebuilt alone");

  for (bool rebuild : {false, true}) {
    g[0].mesh = moved(rods, 0.04, rebuild ? 2.0 : 3.0);
    g[2].mesh = moved(cloth, 0.05, rebuild ? 0.3 : 0.9);
    std::vector<float> both = g[0].mesh.xyz;  // the moving geometries in order: 0, then 2
    both.insert(both.end(), g[2].mesh.xyz.begin(), g[2].mesh.xyz.end());
    const minkq_buffer all = cxx::host_buffer(both.data(), both.size() / 3);
    ASSERT_EQ(rebuild ? minkq_scene_rebuild(scene.get(), all) : minkq_scene_refit(scene.get(), all), MINKQ_SUCCESS)
        << minkq_last_error_message();
    test::check_scene(scene.get(), g, r, rebuild ? "all moving rebuilt" : "all moving refit");
  }

  const Pairs before = test::Scene::query_pairs(scene.get(), MINKQ_QUERY_VT, MINKQ_MODE_BOX, r);
  const std::vector<float> body_moved = moved(g[1].mesh, 0.1, 0.0).xyz;
  const minkq_buffer body_buffer = cxx::host_buffer(body_moved.data(), body_moved.size() / 3);
  EXPECT_EQ(minkq_scene_geometry_refit(scene.get(), 1, body_buffer), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(minkq_last_error_message()).find("geometry 1"), std::string::npos) << minkq_last_error_message();
  EXPECT_EQ(minkq_scene_geometry_rebuild(scene.get(), 1, body_buffer), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(minkq_scene_geometry_refit_swept(scene.get(), 1, body_buffer, body_buffer), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(minkq_scene_geometry_refit(scene.get(), 3, test::geometry_vertices(g[2])), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(minkq_scene_geometry_refit(scene.get(), 2, test::geometry_vertices(g[0])), MINKQ_ERROR_INVALID_ARGUMENT)
      << "another geometry's vertex count";
  EXPECT_NE(std::string(minkq_last_error_message()).find("geometry 2"), std::string::npos) << minkq_last_error_message();
  std::vector<float> bad = g[2].mesh.xyz;
  bad[4] = NAN;
  EXPECT_EQ(minkq_scene_geometry_refit(scene.get(), 2, cxx::host_buffer(bad.data(), bad.size() / 3)),
            MINKQ_ERROR_NON_FINITE);
  EXPECT_EQ(minkq_scene_refit(scene.get(), test::geometry_vertices(g[2])), MINKQ_ERROR_INVALID_ARGUMENT)
      << "the cloth alone is not every moving geometry";
  EXPECT_EQ(test::Scene::query_pairs(scene.get(), MINKQ_QUERY_VT, MINKQ_MODE_BOX, r), before) << "refusals changed it";
}

// Pairs present exactly when each side's group is in the other's mask.
TEST(Geometries, groups_and_masks_decide_the_cross_pairs) {
  const test::Device cpu;
  const uint64_t seed = test::fresh_seed();
  test::Random rng(seed);
  std::vector<Geometry> g;
  for (int k = 0; k < 6; ++k) {
    Mesh m = ref::random_soup(60, seed + uint64_t(k), 0.12);
    if (k == 4) m.tris.clear();  // a set of rods
    Geometry x = test::make_geometry(std::move(m), kAllKinds, rng.integer(0, 1) ? kSelfDrop : 0u);
    x.group = 1u << rng.integer(0, 3);
    x.mask = uint32_t(rng.integer(0, 15)) | x.group;
    g.push_back(std::move(x));
  }
  g[0].mask = 0;  // takes part in no cross pair
  const float r = 0.02f;
  cxx::Scene scene = test::new_geometry_scene(cpu.get(), g);
  test::check_scene(scene.get(), g, r, "groups and masks");
  // The rule must have excluded something for this to test it.
  std::vector<Geometry> open = g;
  for (Geometry& x : open) x.mask = ~0u;
  EXPECT_GT(ref::geometry_contacts(open, ref::Kind::VT, r).size(), ref::geometry_contacts(g, ref::Kind::VT, r).size());
}

// Random mixed scenes: meshes, rods and particles with random kinds, SELF, DROP_INCIDENT,
// worlds, groups, masks, thickness, precision and static flags, all in one unit cube.
TEST(Geometries, random_mixed_scenes_lose_no_contact) {
  const test::Device cpu;
  const uint64_t seed = test::fresh_seed();
  test::Random rng(seed);
  for (int trial = 0; trial < 10; ++trial) {
    std::vector<Geometry> g;
    const int count = rng.integer(2, 7);
    for (int k = 0; k < count; ++k) {
      Mesh m = ref::random_soup(rng.integer(1, 50), seed + uint64_t(10 * trial + k), rng.uniform(0.02f, 0.3f));
      const int type = rng.integer(0, 2);  // mesh, rods, particles
      if (type > 0) m.tris.clear();
      if (type == 2) m.edges.clear();
      else if (type == 0 && rng.integer(0, 1)) m.edges.clear();  // derived by the scene
      uint32_t kinds = uint32_t(rng.integer(1, 15));               // bits of VT, EE, VV, EV
      kinds = (kinds & 3u) | ((kinds & 12u) << 2);
      uint32_t flags = uint32_t(rng.integer(0, 3)) | (rng.integer(0, 3) == 0 ? MINKQ_GEOMETRY_STATIC : 0u);
      if (rng.integer(0, 3) == 0) {
        flags |= MINKQ_GEOMETRY_FLOAT64;
        std::vector<double> xyz(m.xyz.begin(), m.xyz.end());
        for (double& x : xyz) x += rng.uniform(-1e-7f, 1e-7f);
        ref::set_float64(m, std::move(xyz));
      }
      Geometry x = test::make_geometry(std::move(m), kinds, flags, rng.integer(-1, 2));
      x.group = 1u << rng.integer(0, 2);
      x.mask = rng.integer(0, 2) ? ~0u : uint32_t(rng.integer(0, 7));
      if (rng.integer(0, 1)) test::set_thickness(x, random_thickness(rng, x.mesh.vertex_count(), 0.05f));
      g.push_back(std::move(x));
    }
    cxx::Scene scene = test::new_geometry_scene(cpu.get(), g);
    test::check_scene(scene.get(), g, rng.integer(0, 4) ? rng.uniform(0.0f, 0.05f) : 0.0f,
                      "trial " + std::to_string(trial));
  }
}

// Eight copies of a sheet at the same place, each in its own world, over a plane of every world
// (-1): no pair between two copies, and each copy meets itself and the plane as the first does.
TEST(Geometries, worlds_never_meet_and_each_sees_the_same_pairs) {
  const test::Device cpu;
  test::Random rng(test::fresh_seed());
  Mesh sheet = ref::twisted_sheet(9, 0.6);
  for (size_t v = 0; v < sheet.vertex_count(); ++v) sheet.xyz[3 * v + 2] = 0.2f * sheet.xyz[3 * v + 2] + 0.02f;
  const float r = float(0.6 * ref::mean_edge_length(sheet));
  Mesh plane = ref::grid_sheet(12);
  ref::transform(plane, 1.2, -0.1);
  for (size_t v = 0; v < plane.vertex_count(); ++v) plane.xyz[3 * v + 2] = rng.uniform(-0.02f, 0.0f);
  std::vector<Geometry> g;
  for (int32_t w = 0; w < 8; ++w) g.push_back(test::make_geometry(sheet, kAllKinds, kSelfDrop, w));
  g.push_back(test::make_geometry(plane, kAllKinds, MINKQ_GEOMETRY_STATIC, -1));
  cxx::Scene scene = test::new_geometry_scene(cpu.get(), g);
  test::check_scene(scene.get(), g, r, "eight worlds");
  // Which copy holds global id `id` of `element` (-1: the plane), and id made the first copy's.
  auto world_of = [&](int element, int32_t& id) {
    for (int w = 0; w < 8; ++w) {
      const auto [first, count] = ref::geometry_range(g, size_t(w), element);
      if (size_t(id) >= first && size_t(id) < first + count) {
        id -= int32_t(first - ref::geometry_range(g, 0, element).first);
        return w;
      }
    }
    return -1;
  };
  const int first_side[] = {0, 2, 0, 0}, second_side[] = {1, 2, 0, 2};  // VT, EE, VV, EV
  for (ref::Kind kind : test::kAllQueryKinds) {
    const Pairs got = test::Scene::query_pairs(scene.get(), test::query_kind(kind), MINKQ_MODE_BOX, r);
    std::vector<Pairs> per_world(8);
    for (auto [a, b] : got) {
      const int wa = world_of(first_side[int(kind)], a), wb = world_of(second_side[int(kind)], b);
      ASSERT_TRUE(wa < 0 || wb < 0 || wa == wb) << test::kind_name(kind) << " pair across worlds " << wa << ", " << wb;
      ASSERT_GE(std::max(wa, wb), 0) << "the plane has no SELF";
      per_world[size_t(std::max(wa, wb))].emplace_back(a, b);
    }
    EXPECT_FALSE(per_world[0].empty()) << test::kind_name(kind);
    for (Pairs& p : per_world) std::sort(p.begin(), p.end());
    for (int w = 1; w < 8; ++w) EXPECT_EQ(per_world[w], per_world[0]) << test::kind_name(kind) << " world " << w;
  }
}

// Thickness from 0 to several r, per vertex, on the cloth and the body; r = 0 too.
TEST(Geometries, per_vertex_thickness_up_to_several_radii) {
  const test::Device cpu;
  test::Random rng(test::fresh_seed());
  const Mesh cloth = cloth_mesh(rng, 12, 0.0, 0.15);
  const float r = float(0.3 * ref::mean_edge_length(cloth));
  std::vector<Geometry> g = {test::make_geometry(cloth, kAllKinds, kSelfDrop),
                             test::make_geometry(body_mesh(16), kAllKinds, MINKQ_GEOMETRY_STATIC)};
  test::set_thickness(g[0], random_thickness(rng, g[0].mesh.vertex_count(), 4 * r));
  test::set_thickness(g[1], random_thickness(rng, g[1].mesh.vertex_count(), 2 * r));
  cxx::Scene scene = test::new_geometry_scene(cpu.get(), g);
  for (float radius : {r, 0.0f}) {
    test::check_scene(scene.get(), g, radius, "thickness");
    std::vector<Geometry> thin = g;
    for (Geometry& x : thin) x.thickness.clear();
    EXPECT_GT(ref::geometry_contacts(g, ref::Kind::VT, radius).size(), ref::geometry_contacts(thin, ref::Kind::VT, radius).size());
  }
  // Thickness 0 everywhere is no thickness: the same pairs and digests.
  std::vector<Geometry> zero = g, none = g;
  for (Geometry& x : zero) x.thickness.assign(x.mesh.vertex_count(), 0.0);
  for (Geometry& x : none) x.thickness.clear();
  cxx::Scene zeros = test::new_geometry_scene(cpu.get(), zero), nones = test::new_geometry_scene(cpu.get(), none);
  for (ref::Kind kind : test::kAllQueryKinds)
    for (uint32_t flags : {0u, uint32_t(MINKQ_QUERY_LEAF_EXACT)})
      for (minkq_mode mode : test::modes_of(kind)) {
        uint64_t a = 0, b = 0;
        EXPECT_EQ(test::Scene::query_pairs(zeros.get(), test::query_kind(kind), mode, r, flags, &a),
                  test::Scene::query_pairs(nones.get(), test::query_kind(kind), mode, r, flags, &b))
            << test::kind_name(kind) << " mode " << mode << " flags " << flags;
        EXPECT_EQ(a, b);
      }
}

// Double input far from the origin beside a float geometry; refit in double.
TEST(Geometries, float64_geometries_keep_the_guarantee_in_double) {
  const test::Device cpu;
  test::Random rng(test::fresh_seed());
  Mesh cloth = cloth_mesh(rng, 12, -0.01, 0.08), body = body_mesh(16);
  const double offset = 3e3;
  std::vector<double> xyz(cloth.xyz.size());
  for (size_t i = 0; i < xyz.size(); ++i) {
    const double x = double(cloth.xyz[i]) + offset;
    xyz[i] = x + rng.uniform(-0.5f, 0.5f) * (double(std::nextafter(float(x), INFINITY)) - double(float(x)));
  }
  ref::set_float64(cloth, std::move(xyz));
  ref::transform(body, 1.0, offset);
  const float r = float(0.5 * ref::mean_edge_length(cloth));
  std::vector<Geometry> g = {test::make_geometry(cloth, kAllKinds, kSelfDrop | MINKQ_GEOMETRY_FLOAT64),
                             test::make_geometry(body, kAllKinds, MINKQ_GEOMETRY_STATIC)};
  test::set_thickness(g[0], random_thickness(rng, g[0].mesh.vertex_count(), r));
  cxx::Scene scene = test::new_geometry_scene(cpu.get(), g);
  test::check_scene(scene.get(), g, r, "float64 cloth");
  g[0].mesh = moved(cloth, 0.02, 0.7);
  ASSERT_EQ(minkq_scene_geometry_refit(scene.get(), 0, test::geometry_vertices(g[0])), MINKQ_SUCCESS)
      << minkq_last_error_message();
  test::check_scene(scene.get(), g, r, "float64 cloth refit");
  // Moving geometries of mixed precision cannot move together from one buffer.
  g[1].flags = 0;
  cxx::Scene mixed = test::new_geometry_scene(cpu.get(), g);
  const std::vector<float> floats = ref::concatenate(g).xyz;
  EXPECT_EQ(minkq_scene_refit(mixed.get(), cxx::host_buffer(floats.data(), floats.size() / 3)),
            MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(minkq_scene_geometry_refit(mixed.get(), 1, test::geometry_vertices(g[1])), MINKQ_SUCCESS)
      << minkq_last_error_message();
}

// A swept step of the cloth alone: at zero motion the static pairs; moving, every contact of
// the oracle at sampled times of the step (a lower bound of the swept set).
TEST(Geometries, swept_steps_of_one_geometry) {
  const test::Device cpu;
  test::Random rng(test::fresh_seed());
  const Mesh cloth = cloth_mesh(rng, 12, 0.02, 0.12);
  const float r = float(0.4 * ref::mean_edge_length(cloth));
  std::vector<Geometry> g = {test::make_geometry(body_mesh(16), kAllKinds, MINKQ_GEOMETRY_STATIC),
                             test::make_geometry(cloth, kAllKinds, kSelfDrop)};
  test::set_thickness(g[1], random_thickness(rng, g[1].mesh.vertex_count(), r));
  cxx::Scene fixed = test::new_geometry_scene(cpu.get(), g), scene = test::new_geometry_scene(cpu.get(), g);
  const minkq_buffer x0 = test::geometry_vertices(g[1]);
  ASSERT_EQ(minkq_scene_geometry_refit_swept(scene.get(), 1, x0, x0), MINKQ_SUCCESS) << minkq_last_error_message();
  EXPECT_EQ(minkq_scene_is_swept(scene.get()), 1);
  for (ref::Kind kind : test::kAllQueryKinds)
    for (minkq_mode mode : test::modes_of(kind)) {
      if (kind == ref::Kind::EE && mode != MINKQ_MODE_BOX) continue;  // swept EE: box mode only
      const minkq_mode same = mode == MINKQ_MODE_CAPSULE_EXACT ? MINKQ_MODE_SPHERE
                              : mode == MINKQ_MODE_CAPSULE_RAY ? MINKQ_MODE_BOX : mode;
      uint64_t a = 0, b = 0;
      EXPECT_EQ(test::Scene::query_pairs(scene.get(), test::query_kind(kind), mode, r, 0, &a),
                test::Scene::query_pairs(fixed.get(), test::query_kind(kind), same, r, 0, &b))
          << test::kind_name(kind) << " mode " << mode;
      EXPECT_EQ(a, b);
    }
  const Mesh to = moved(cloth, 0.08, 0.2);
  ASSERT_EQ(minkq_scene_geometry_rebuild_swept(scene.get(), 1, x0, cxx::host_buffer(to.xyz.data(), to.vertex_count())),
            MINKQ_SUCCESS)
      << minkq_last_error_message();
  for (ref::Kind kind : test::kAllQueryKinds) {
    Pairs sampled;
    for (int k = 0; k <= 16; ++k) {
      std::vector<Geometry> at = g;
      std::vector<double> xyz(cloth.xyz.size());
      for (size_t i = 0; i < xyz.size(); ++i) xyz[i] = cloth.xyz[i] + (k / 16.0) * (double(to.xyz[i]) - cloth.xyz[i]);
      ref::set_float64(at[1].mesh, std::move(xyz));  // the oracle reads the exact positions between
      const Pairs found = ref::geometry_contacts(at, kind, r);
      Pairs merged;
      std::set_union(sampled.begin(), sampled.end(), found.begin(), found.end(), std::back_inserter(merged));
      sampled = std::move(merged);
    }
    EXPECT_FALSE(sampled.empty());
    for (minkq_mode mode : test::modes_of(kind)) {
      if (kind == ref::Kind::EE && mode != MINKQ_MODE_BOX) continue;
      const Pairs got = test::Scene::query_pairs(scene.get(), test::query_kind(kind), mode, r);
      EXPECT_TRUE(test::is_subset(sampled, got)) << test::kind_name(kind) << " mode " << mode << " lost "
                                                 << test::describe(test::difference(sampled, got));
    }
  }
  // The whole-scene swept call moves every moving geometry (here the cloth alone) the same way.
  ASSERT_EQ(minkq_scene_refit_swept(fixed.get(), x0, cxx::host_buffer(to.xyz.data(), to.vertex_count())), MINKQ_SUCCESS)
      << minkq_last_error_message();
  for (ref::Kind kind : test::kAllQueryKinds)
    EXPECT_EQ(test::Scene::query_pairs(fixed.get(), test::query_kind(kind), MINKQ_MODE_BOX, r),
              test::Scene::query_pairs(scene.get(), test::query_kind(kind), MINKQ_MODE_BOX, r))
        << test::kind_name(kind);
  ASSERT_EQ(minkq_scene_geometry_refit(scene.get(), 1, x0), MINKQ_SUCCESS);
  EXPECT_EQ(minkq_scene_is_swept(scene.get()), 0);
}

// One geometry through minkq_scene_create_geometries is the one-mesh scene: pairs and digests.
TEST(Geometries, one_geometry_is_the_one_mesh_scene_exactly) {
  const test::Device cpu;
  const Mesh sheet = ref::twisted_sheet(16, 2.5);
  const float r = float(0.5 * ref::mean_edge_length(sheet));
  test::Scene one_mesh(cpu.get(), sheet, kAllKinds | MINKQ_SCENE_DROP_INCIDENT);
  const std::vector<Geometry> g = {test::make_geometry(sheet, kAllKinds, kSelfDrop)};
  cxx::Scene scene = test::new_geometry_scene(cpu.get(), g);
  EXPECT_EQ(minkq_scene_geometry_count(scene.get()), 1u);
  EXPECT_EQ(minkq_scene_geometry_count(one_mesh.get()), 1u);
  EXPECT_EQ(minkq_scene_geometry_count(nullptr), 0u);
  for (ref::Kind kind : test::kAllQueryKinds)
    for (uint32_t flags : {0u, uint32_t(MINKQ_QUERY_LEAF_EXACT)})
      for (minkq_mode mode : test::modes_of(kind)) {
        uint64_t a = 0, b = 0;
        EXPECT_EQ(test::Scene::query_pairs(scene.get(), test::query_kind(kind), mode, r, flags, &a),
                  one_mesh.query(test::query_kind(kind), mode, r, flags, &b))
            << test::kind_name(kind) << " mode " << mode << " flags " << flags;
        EXPECT_EQ(a, b) << test::kind_name(kind) << " mode " << mode << " flags " << flags;
      }
  EXPECT_EQ(test::Scene::edges_of(scene.get()), one_mesh.edges());
  size_t first = 9, count = 0;
  ASSERT_EQ(minkq_scene_geometry_range(one_mesh.get(), 0, MINKQ_ELEMENT_EDGE, &first, &count), MINKQ_SUCCESS);
  EXPECT_EQ(first, 0u);
  EXPECT_EQ(count, minkq_scene_edge_count(one_mesh.get()));
}

// Counts, edges and ranges in the global numbering; edges derived only where EE or EV needs them.
TEST(Geometries, global_numbering_of_edges_and_ranges) {
  const test::Device cpu;
  Mesh particles;
  particles.xyz = {0.5f, 0.5f, 0.5f, 0.6f, 0.5f, 0.5f, 2, 2, 2};
  Mesh rods = particles;
  rods.edges = {2, 0, 1, 2};  // as given, not sorted
  std::vector<Geometry> g = {test::make_geometry(ref::grid_sheet(4), ref::kKindVT, kSelfDrop),
                             test::make_geometry(rods, ref::kKindEE | ref::kKindEV, kSelfDrop),
                             test::make_geometry(ref::grid_sheet(3), kAllKinds, kSelfDrop),
                             test::make_geometry(particles, ref::kKindVV, kSelfDrop)};
  g[0].mesh.edges.clear();  // VT only: none derived
  g[2].mesh.edges.clear();  // derived for EE and EV
  cxx::Scene scene = test::new_geometry_scene(cpu.get(), g);
  const Mesh all = ref::concatenate(g);
  EXPECT_EQ(minkq_scene_geometry_count(scene.get()), 4u);
  EXPECT_EQ(minkq_scene_vertex_count(scene.get()), all.vertex_count());
  EXPECT_EQ(minkq_scene_triangle_count(scene.get()), all.triangle_count());
  EXPECT_EQ(minkq_scene_edge_count(scene.get()), all.edge_count());
  EXPECT_EQ(test::Scene::edges_of(scene.get()), all.edges);
  for (uint32_t i = 0; i < 4; ++i)
    for (minkq_element e : {MINKQ_ELEMENT_VERTEX, MINKQ_ELEMENT_TRIANGLE, MINKQ_ELEMENT_EDGE}) {
      size_t first = 99, count = 99;
      ASSERT_EQ(minkq_scene_geometry_range(scene.get(), i, e, &first, &count), MINKQ_SUCCESS) << minkq_last_error_message();
      EXPECT_EQ(std::make_pair(first, count), ref::geometry_range(g, i, int(e))) << "geometry " << i << " element " << e;
    }
  size_t first = 0, count = 0;
  EXPECT_EQ(minkq_scene_geometry_range(scene.get(), 4, MINKQ_ELEMENT_VERTEX, &first, &count), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(minkq_scene_geometry_range(scene.get(), 0, minkq_element(3), &first, &count), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(minkq_scene_geometry_range(scene.get(), 0, MINKQ_ELEMENT_VERTEX, nullptr, &count), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(minkq_scene_geometry_range(nullptr, 0, MINKQ_ELEMENT_VERTEX, &first, &count), MINKQ_ERROR_INVALID_ARGUMENT);
  test::check_scene(scene.get(), g, 0.15f, "mixed elements");
}

// Bad descriptions are refused with a message naming the geometry, and no scene is made.
TEST(Geometries, bad_descriptions_are_refused_naming_the_geometry) {
  const test::Device cpu;
  const std::vector<Geometry> g = {test::make_geometry(ref::grid_sheet(3), kAllKinds, kSelfDrop),
                                   test::make_geometry(ref::grid_sheet(2), kAllKinds, kSelfDrop),
                                   test::make_geometry(ref::grid_sheet(2), kAllKinds, kSelfDrop)};
  auto refused = [&](auto change, minkq_status want, const std::string& names) {
    test::GeometryDescriptions d(g);
    std::vector<float> thickness;
    change(d.descs, thickness);
    minkq_scene* const unset = reinterpret_cast<minkq_scene*>(&thickness);  // the call must set NULL
    minkq_scene* scene = unset;
    const minkq_status status = d.create(cpu.get(), &scene);
    const std::string message = minkq_last_error_message();
    EXPECT_EQ(scene, nullptr);
    if (scene != unset) minkq_scene_release(scene);
    EXPECT_EQ(status, want) << message;
    EXPECT_NE(message.find(names), std::string::npos) << message;
  };
  using Descs = std::vector<minkq_geometry_desc>;
  refused([](Descs& d, auto&) { d[0].struct_size = 8; }, MINKQ_ERROR_INVALID_ARGUMENT, "struct_size");
  refused([](Descs& d, auto&) { d[1].struct_size = 8; }, MINKQ_ERROR_INVALID_ARGUMENT, "geometry 1");
  refused([](Descs& d, auto& t) {
            t.assign(3, 0.1f);
            d[1].thickness = cxx::host_buffer(t.data(), 3);
          },
          MINKQ_ERROR_INVALID_ARGUMENT, "geometry 1");
  refused([](Descs& d, auto& t) {
            t = {0, 0, -0.5f, 0};
            d[2].thickness = cxx::host_buffer(t.data(), 4);
          },
          MINKQ_ERROR_INVALID_ARGUMENT, "geometry 2");
  refused([](Descs& d, auto&) { d[1].world = -2; }, MINKQ_ERROR_INVALID_ARGUMENT, "geometry 1");
  refused([](Descs& d, auto&) { d[1].kinds = 0; }, MINKQ_ERROR_INVALID_ARGUMENT, "geometry 1");
  refused([](Descs& d, auto&) { d[2].kinds = 64; }, MINKQ_ERROR_INVALID_ARGUMENT, "geometry 2");
  refused([](Descs& d, auto&) { d[0].flags = 16; }, MINKQ_ERROR_INVALID_ARGUMENT, "geometry 0");
  static const std::vector<int32_t> tris = {0, 1, 3, 0, 9, 2};
  refused([](Descs& d, auto&) { d[2].triangles = cxx::host_buffer(tris.data(), 2); }, MINKQ_ERROR_INDEX_OUT_OF_RANGE,
          "geometry 2: triangle 1 references vertex 9");
  // A NaN thickness: NON_FINITE or INVALID_ARGUMENT (minkq.h allows either), naming geometry 2.
  test::GeometryDescriptions d(g);
  const std::vector<float> nan_thickness = {0, NAN, 0, 0};
  d.descs[2].thickness = cxx::host_buffer(nan_thickness.data(), 4);
  minkq_scene* scene = nullptr;
  const minkq_status status = d.create(cpu.get(), &scene);
  EXPECT_TRUE(status == MINKQ_ERROR_NON_FINITE || status == MINKQ_ERROR_INVALID_ARGUMENT) << minkq_status_name(status);
  EXPECT_NE(std::string(minkq_last_error_message()).find("geometry 2"), std::string::npos) << minkq_last_error_message();
  EXPECT_EQ(scene, nullptr);
  EXPECT_EQ(minkq_scene_create_geometries(cpu.get(), d.descs.data(), 0, &scene), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(minkq_scene_create_geometries(cpu.get(), nullptr, 1, &scene), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(minkq_scene_create_geometries(cpu.get(), test::GeometryDescriptions(g).descs.data(), 3, nullptr),
            MINKQ_ERROR_INVALID_ARGUMENT);
  // The defaults.
  minkq_geometry_desc init;
  std::memset(&init, 0xab, sizeof init);
  minkq_geometry_desc_init(&init);
  EXPECT_EQ(init.struct_size, sizeof(minkq_geometry_desc));
  EXPECT_EQ(init.kinds, uint32_t(MINKQ_SCENE_VT | MINKQ_SCENE_EE));
  EXPECT_EQ(init.flags, kSelfDrop);
  EXPECT_EQ(init.world, 0);
  EXPECT_EQ(init.group, 1u);
  EXPECT_EQ(init.mask, ~0u);
  EXPECT_EQ(init.vertices.count + init.triangles.count + init.edges.count + init.thickness.count, 0u);
  minkq_geometry_desc_init(nullptr);
}

}  // namespace
}  // namespace minkq
