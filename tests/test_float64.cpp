// Float64 input (MINKQ_SCENE_FLOAT64): a pair within r in double is never lost, whatever the
// rounding to float does to it. Constructed cases that rounding to nearest pulls apart (lost by
// a float scene of the rounded positions), random double scenes at large offsets and at scales
// 1e-6 to 1e6 against the long-double oracle on the double input, leaf-exact extras within
// r + 2 rho plus the float slack, doubles that are floats already giving the float scene's
// pairs, digests and work exactly, and the errors of bad float64 input.
#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <string>
#include <vector>

#include "capi_util.h"
#include "contact_checks.h"
#include "minkq_reference.h"
#include "test_util.h"

namespace minkq {
namespace {

using reference::Mesh;
using test::Pairs;

constexpr uint32_t kVT = MINKQ_SCENE_VT, kEE = MINKQ_SCENE_EE, kF64 = MINKQ_SCENE_FLOAT64;
const minkq_mode kVtModes[] = {MINKQ_MODE_BOX, MINKQ_MODE_SPHERE, MINKQ_MODE_CAPSULE_RAY, MINKQ_MODE_CAPSULE_EXACT};
const minkq_mode kEeModes[] = {MINKQ_MODE_BOX, MINKQ_MODE_CAPSULE_RAY, MINKQ_MODE_CAPSULE_EXACT};

// rho of minkq.h: the farthest rounding to nearest float moves a vertex of the mesh.
double rounding_rho(const Mesh& mesh) {
  double rho = 0;
  for (size_t v = 0; v < mesh.vertex_count(); ++v) {
    double d2 = 0;
    for (int k = 0; k < 3; ++k) {
      const double d = mesh.xyz64[3 * v + k] - double(float(mesh.xyz64[3 * v + k]));
      d2 += d * d;
    }
    rho = std::max(rho, std::sqrt(d2));
  }
  return rho;
}

// The float spacing at x (x > 0 a float).
double ulp(float x) { return double(std::nextafter(x, INFINITY)) - double(x); }

// Offsets in units of the spacing u at `base` that put a plane at base + o u and a point at
// base + o u + d so that, rounded to nearest float, they lie more than r apart while d <= r.
std::vector<std::pair<double, double>> pulled_apart(float base, double r, int wanted) {
  const double u = ulp(base);
  std::vector<std::pair<double, double>> found;  // (plane, point)
  for (double fraction : {0.90, 0.93, 0.95, 0.97, 0.99, 0.999})
    for (int k = 0; k < 64 && int(found.size()) < wanted; ++k) {
      const double plane = double(base) + (k / 64.0 - 0.5) * u, point = plane + fraction * r;
      if (double(float(point)) - double(float(plane)) > r) {
        found.push_back({plane, point});
        break;
      }
    }
  return found;
}

// Vertex p at x = point facing a triangle in the plane x = plane (distance point - plane).
Mesh vertex_over_triangle(double plane, double point) {
  Mesh m;
  reference::set_float64(m, {plane, -1, -1, plane, 2, -1, plane, -1, 2, point, 0, 0});
  m.tris = {0, 1, 2};
  m.edges = reference::derive_edges(m.tris);
  return m;
}
// Edge 0 along y at x = plane, edge 1 along z at x = point (an EE-only mesh).
Mesh crossed_edges(double plane, double point) {
  Mesh m;
  reference::set_float64(m, {plane, -1, 0, plane, 1, 0, point, 0, -1, point, 0, 1});
  m.edges = {0, 1, 2, 3};
  return m;
}

TEST(Float64, pairs_that_rounding_pulls_apart_are_found_in_every_mode) {
  const test::Device cpu;
  // Float distances are multiples of the spacing u, so rounding can only carry a pair at 0.9 r
  // beyond r where r < u: r = 1e-3 near 2e4 (u = 2^-9), as at 1e4 with r = 5e-4.
  const double r = 1e-3;
  const auto cases = pulled_apart(2e4f, r, 6);
  ASSERT_EQ(cases.size(), 6u);
  for (const auto& [plane, point] : cases) {
    SCOPED_TRACE("plane " + std::to_string(plane) + " point " + std::to_string(point));
    const Mesh vt = vertex_over_triangle(plane, point), ee = crossed_edges(plane, point);
    ASSERT_EQ(reference::vt_contacts(vt, r, true), (Pairs{{3, 0}}));
    ASSERT_EQ(reference::ee_contacts(ee, r, true), (Pairs{{0, 1}}));
    // The rounded positions as a float scene (what float64 input used to become): the leaf
    // test rightly finds them beyond r.
    test::Scene rounded(cpu.get(), vt, kVT | MINKQ_SCENE_DROP_INCIDENT);
    EXPECT_TRUE(rounded.query(MINKQ_QUERY_VT, MINKQ_MODE_BOX, float(r), MINKQ_QUERY_LEAF_EXACT).empty());
    test::Scene vt_scene(cpu.get(), vt, kVT | MINKQ_SCENE_DROP_INCIDENT | kF64);
    test::Scene ee_scene(cpu.get(), ee, kEE | MINKQ_SCENE_DROP_INCIDENT | kF64);
    for (uint32_t flags : {0u, uint32_t(MINKQ_QUERY_LEAF_EXACT)}) {
      for (minkq_mode mode : kVtModes)
        EXPECT_EQ(vt_scene.query(MINKQ_QUERY_VT, mode, float(r), flags), (Pairs{{3, 0}})) << "VT mode " << mode;
      for (minkq_mode mode : kEeModes)
        EXPECT_EQ(ee_scene.query(MINKQ_QUERY_EE, mode, float(r), flags), (Pairs{{0, 1}})) << "EE mode " << mode;
    }
  }
}

// A twisted sheet in double at `scale` and `offset`, each coordinate nudged by a random part of
// its float spacing so that rounding to nearest moves every vertex.
Mesh double_sheet(test::Random& rng, double scale, double offset) {
  Mesh m = reference::twisted_sheet(24, 2.0);
  std::vector<double> xyz(m.xyz.size());
  for (size_t i = 0; i < xyz.size(); ++i) {
    const double x = double(m.xyz[i]) * scale + offset;
    xyz[i] = x + rng.uniform(-0.5f, 0.5f) * ulp(float(std::fabs(x)) + FLT_MIN);
  }
  reference::set_float64(m, std::move(xyz));
  return m;
}

// Every mode's pairs contain the oracle's contacts on the double input; leaf-exact extras lie
// within r + 2 rho (the widened radius) plus the float slack.
void check_against_oracle(minkq_device* device, const Mesh& mesh, double r) {
  test::Scene scene(device, mesh, kVT | kEE | MINKQ_SCENE_DROP_INCIDENT | kF64);
  const Pairs vt_truth = reference::vt_contacts(mesh, r, true), ee_truth = reference::ee_contacts(mesh, r, true);
  const double wide = r + 2 * rounding_rho(mesh);
  const std::vector<int32_t> edges = reference::derive_edges(mesh.tris);
  for (uint32_t flags : {0u, uint32_t(MINKQ_QUERY_LEAF_EXACT)}) {
    for (minkq_mode mode : kVtModes) {
      const Pairs got = scene.query(MINKQ_QUERY_VT, mode, float(r), flags);
      EXPECT_TRUE(test::is_subset(vt_truth, got)) << "VT mode " << mode << " flags " << flags << " lost "
                                                  << test::describe(test::difference(vt_truth, got));
      if (flags)
        for (const auto& [v, t] : got) {
          double s = 0;
          const long double d = test::vt_distance(mesh, v, t, &s);
          EXPECT_LE(double(d), wide * (1 + 0x1p-20) + 0x1p-19 * s) << "VT (" << v << ", " << t << ")";
        }
    }
    for (minkq_mode mode : kEeModes) {
      const Pairs got = scene.query(MINKQ_QUERY_EE, mode, float(r), flags);
      EXPECT_TRUE(test::is_subset(ee_truth, got)) << "EE mode " << mode << " flags " << flags << " lost "
                                                  << test::describe(test::difference(ee_truth, got));
      if (flags)
        for (const auto& [e, f] : got) {
          double s = 0;
          const long double d = test::ee_distance(mesh, edges, e, f, &s);
          EXPECT_LE(double(d), wide * (1 + 0x1p-20) + 0x1p-19 * s) << "EE (" << e << ", " << f << ")";
        }
    }
  }
}

TEST(Float64, no_contact_of_the_double_input_is_lost_at_any_scale_or_offset) {
  const test::Device cpu;
  test::Random rng(test::fresh_seed());
  for (double scale : {1e-6, 1e-3, 1.0, 1e3, 1e6})
    for (double offset_units : {0.0, 3e3, 1e5}) {  // offsets in sheet widths: up to 1e5 sheets away
      SCOPED_TRACE("scale " + std::to_string(scale) + " offset " + std::to_string(offset_units));
      Mesh mesh = double_sheet(rng, scale, offset_units * scale);
      const double r = 0.5 * reference::mean_edge_length(mesh);
      check_against_oracle(cpu.get(), mesh, r);
      // Then refit and rebuild to other double positions of the same sheet.
      Mesh moved = double_sheet(rng, scale * 1.01, offset_units * scale);
      test::Scene scene(cpu.get(), mesh, kVT | kEE | MINKQ_SCENE_DROP_INCIDENT | kF64);
      for (bool rebuild : {false, true}) {
        const minkq_buffer vertices = test::vertices_of(moved, kF64);
        ASSERT_EQ(rebuild ? minkq_scene_rebuild(scene.get(), vertices) : minkq_scene_refit(scene.get(), vertices),
                  MINKQ_SUCCESS)
            << minkq_last_error_message();
        const Pairs truth = reference::ee_contacts(moved, r, true);
        const Pairs got = scene.query(MINKQ_QUERY_EE, MINKQ_MODE_BOX, float(r), MINKQ_QUERY_LEAF_EXACT);
        EXPECT_TRUE(test::is_subset(truth, got)) << (rebuild ? "rebuild" : "refit");
      }
    }
}

// Doubles that are floats already: rho = 0, and the float scene's pairs, digests and work.
TEST(Float64, doubles_that_are_floats_give_the_float_scene_exactly) {
  const test::Device cpu;
  Mesh mesh = reference::twisted_sheet(20, 3.0);
  Mesh as_double = mesh;
  reference::set_float64(as_double, std::vector<double>(mesh.xyz.begin(), mesh.xyz.end()));
  test::Scene floats(cpu.get(), mesh, kVT | kEE | MINKQ_SCENE_DROP_INCIDENT);
  test::Scene doubles(cpu.get(), as_double, kVT | kEE | MINKQ_SCENE_DROP_INCIDENT | kF64);
  const float r = float(0.4 * reference::mean_edge_length(mesh));
  for (uint32_t flags : {0u, uint32_t(MINKQ_QUERY_LEAF_EXACT)})
    for (minkq_mode mode : kEeModes) {
      uint64_t a = 0, b = 0;
      EXPECT_EQ(floats.query(MINKQ_QUERY_EE, mode, r, flags, &a), doubles.query(MINKQ_QUERY_EE, mode, r, flags, &b));
      EXPECT_EQ(a, b);
      const minkq_query_stats sa = test::work_of(floats.get(), MINKQ_QUERY_VT, mode, r, flags);
      const minkq_query_stats sb = test::work_of(doubles.get(), MINKQ_QUERY_VT, mode, r, flags);
      EXPECT_EQ(std::memcmp(&sa, &sb, sizeof sa), 0) << "VT work, mode " << mode;
    }
}

TEST(Float64, bad_float64_input_is_refused_naming_the_vertex) {
  const test::Device cpu;
  Mesh mesh = vertex_over_triangle(1.0, 1.5);
  auto create = [&](const std::vector<double>& xyz, size_t stride) {
    minkq_scene_desc desc{};
    desc.flags = kVT | kF64;
    desc.vertices = cxx::host_buffer(xyz.data(), xyz.size() / 3, stride);
    desc.triangles = cxx::host_buffer(mesh.tris.data(), 1);
    minkq_scene* scene = nullptr;
    const minkq_status status = minkq_scene_create(cpu.get(), &desc, &scene);
    minkq_scene_release(scene);
    return status;
  };
  std::vector<double> xyz = mesh.xyz64;
  EXPECT_EQ(create(xyz, 12), MINKQ_ERROR_INVALID_ARGUMENT);  // floats' stride: under 3 doubles
  EXPECT_NE(std::string(minkq_last_error_message()).find("smaller than one element (24 bytes)"), std::string::npos)
      << minkq_last_error_message();
  xyz[3 * 2 + 1] = 1e39;  // finite in double, beyond float
  EXPECT_EQ(create(xyz, 0), MINKQ_ERROR_NON_FINITE);
  EXPECT_NE(std::string(minkq_last_error_message()).find("vertex 2 has a coordinate that is not finite or beyond"),
            std::string::npos)
      << minkq_last_error_message();
  xyz[3 * 2 + 1] = NAN;
  EXPECT_EQ(create(xyz, 0), MINKQ_ERROR_NON_FINITE);
  // A refit keeps the positions on bad input; strided (unaligned) records are read as given.
  test::Scene scene(cpu.get(), mesh, kVT | MINKQ_SCENE_DROP_INCIDENT | kF64);
  EXPECT_EQ(minkq_scene_refit(scene.get(), cxx::host_buffer(xyz.data(), 4)), MINKQ_ERROR_NON_FINITE);
  std::vector<char> bytes(4 * 29 + 1);
  for (int v = 0; v < 4; ++v) std::memcpy(bytes.data() + 1 + 29 * v, &mesh.xyz64[3 * v], 24);
  ASSERT_EQ(minkq_scene_refit(scene.get(), cxx::host_buffer(bytes.data() + 1, 4, 29)), MINKQ_SUCCESS)
      << minkq_last_error_message();
  EXPECT_EQ(scene.query(MINKQ_QUERY_VT, MINKQ_MODE_BOX, 0.5f, MINKQ_QUERY_LEAF_EXACT), (Pairs{{3, 0}}));
}

}  // namespace
}  // namespace minkq
