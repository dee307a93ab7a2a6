// Codimensional elements: vertex-vertex (VV) and edge-vertex (EV) queries on scenes of points
// and rods with no triangles (and beside triangles), against a brute-force long-double oracle:
// zero false negatives in every mode, leaf-exact extras within r + 2^-19 S, each VV pair once as
// (v, w), v < w, incident EV pairs dropped; float64 input; swept steps (the static oracle at
// sampled times, and zero motion == static); the refusals.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "capi_util.h"
#include "minkq_reference.h"
#include "test_util.h"

namespace minkq {
namespace {

using reference::Mesh;
using test::Pairs;

constexpr uint32_t kCodim = MINKQ_SCENE_VV | MINKQ_SCENE_EV | MINKQ_SCENE_DROP_INCIDENT;
const minkq_mode kModes[] = {MINKQ_MODE_BOX, MINKQ_MODE_SPHERE, MINKQ_MODE_CAPSULE_RAY, MINKQ_MODE_CAPSULE_EXACT};

// `rods` polylines of `per_rod` vertices (edges between consecutive ones) and `loose` free
// particles, in the unit cube; coordinates in double when float64 (nudged off the floats).
Mesh rods_and_particles(test::Random& rng, int rods, int per_rod, int loose, double scale, double offset,
                        bool float64) {
  Mesh m;
  std::vector<double> xyz;
  for (int k = 0; k < rods; ++k) {
    double p[3] = {rng.uniform(0, 1), rng.uniform(0, 1), rng.uniform(0, 1)};
    for (int i = 0; i < per_rod; ++i) {
      if (i > 0) m.edges.insert(m.edges.end(), {int32_t(xyz.size() / 3) - 1, int32_t(xyz.size() / 3)});
      for (double& c : p) c += rng.uniform(-0.04f, 0.04f);
      xyz.insert(xyz.end(), {p[0], p[1], p[2]});
    }
  }
  for (int i = 0; i < loose; ++i) xyz.insert(xyz.end(), {rng.uniform(0, 1), rng.uniform(0, 1), rng.uniform(0, 1)});
  for (double& c : xyz) {
    c = c * scale + offset;
    if (float64) c += (double(std::nextafter(float(c), INFINITY)) - double(float(c))) * rng.uniform(-0.5f, 0.5f);
  }
  reference::set_float64(m, xyz);
  if (!float64) m.xyz64.clear();
  return m;
}

const double* point(const Mesh& m, std::vector<double>& tmp, int32_t v) {
  if (!m.xyz64.empty()) return &m.xyz64[3 * size_t(v)];
  tmp = {m.xyz[3 * size_t(v)], m.xyz[3 * size_t(v) + 1], m.xyz[3 * size_t(v) + 2]};
  return tmp.data();
}

// Brute force, in long double on the input (double input as given).
Pairs vv_truth(const Mesh& m, double r) {
  Pairs out;
  std::vector<double> a, b;
  for (int32_t v = 0; v < int32_t(m.vertex_count()); ++v)
    for (int32_t w = v + 1; w < int32_t(m.vertex_count()); ++w)
      if (reference::point_segment_distance(point(m, a, v), point(m, b, w), point(m, b, w)) <= r) out.push_back({v, w});
  return out;
}
Pairs ev_truth(const Mesh& m, double r) {
  Pairs out;
  std::vector<double> p, a, b;
  for (int32_t v = 0; v < int32_t(m.vertex_count()); ++v)
    for (int32_t e = 0; e < int32_t(m.edge_count()); ++e) {
      const int32_t a0 = m.edges[2 * size_t(e)], a1 = m.edges[2 * size_t(e) + 1];
      if (a0 == v || a1 == v) continue;
      std::vector<double> pa(point(m, a, a0), point(m, a, a0) + 3);
      if (reference::point_segment_distance(point(m, p, v), pa.data(), point(m, b, a1)) <= r) out.push_back({v, e});
    }
  return out;
}

void check_codim(minkq_device* device, const Mesh& mesh, double r, uint32_t extra_flags, const std::string& what) {
  SCOPED_TRACE(what);
  test::Scene scene(device, mesh, kCodim | extra_flags);
  const Pairs vv = vv_truth(mesh, r), ev = ev_truth(mesh, r);
  ASSERT_FALSE(vv.empty());
  ASSERT_FALSE(ev.empty());
  for (uint32_t flags : {0u, uint32_t(MINKQ_QUERY_LEAF_EXACT)})
    for (minkq_mode mode : kModes) {
      const Pairs got_vv = scene.query(MINKQ_QUERY_VV, mode, float(r), flags);
      const Pairs got_ev = scene.query(MINKQ_QUERY_EV, mode, float(r), flags);
      EXPECT_TRUE(test::is_subset(vv, got_vv)) << "VV mode " << mode << " flags " << flags << " lost "
                                               << test::describe(test::difference(vv, got_vv));
      EXPECT_TRUE(test::is_subset(ev, got_ev)) << "EV mode " << mode << " flags " << flags << " lost "
                                               << test::describe(test::difference(ev, got_ev));
      for (const auto& [v, w] : got_vv) ASSERT_LT(v, w) << "VV pairs once, lower id first";
      if (flags && !(extra_flags & MINKQ_SCENE_FLOAT64)) {  // float input: the truth plus the float slack
        EXPECT_LE(got_vv.size(), vv_truth(mesh, r * (1 + 1e-5)).size());
        EXPECT_LE(got_ev.size(), ev_truth(mesh, r * (1 + 1e-5)).size());
      }
    }
}

TEST(Codim, rods_and_particles_lose_no_pair_at_any_scale) {
  const test::Device cpu;
  test::Random rng(test::fresh_seed());
  for (double scale : {1e-6, 1.0, 1e6})
    for (bool float64 : {false, true}) {
      const Mesh mesh = rods_and_particles(rng, 12, 20, 60, scale, 0.25 * scale, float64);
      check_codim(cpu.get(), mesh, 0.05 * scale, float64 ? MINKQ_SCENE_FLOAT64 : 0u,
                  "scale " + std::to_string(scale) + (float64 ? " float64" : " float"));
    }
}

// VV and EV beside triangles: the same pairs as a codimensional scene of the same vertices and
// edges, and VT / EE unchanged by the extra trees.
TEST(Codim, vv_and_ev_beside_triangles) {
  const test::Device cpu;
  Mesh sheet = reference::twisted_sheet(12, 2.0);
  const float r = float(0.6 * reference::mean_edge_length(sheet));
  test::Scene all(cpu.get(), sheet, MINKQ_SCENE_VT | MINKQ_SCENE_EE | kCodim);
  test::Scene mesh_only(cpu.get(), sheet, MINKQ_SCENE_VT | MINKQ_SCENE_EE | MINKQ_SCENE_DROP_INCIDENT);
  Mesh codim = sheet;
  codim.tris.clear();  // the same vertices and (derived) edges, no triangles
  test::Scene points_and_rods(cpu.get(), codim, kCodim);
  for (minkq_mode mode : {MINKQ_MODE_BOX, MINKQ_MODE_SPHERE}) {
    EXPECT_EQ(all.query(MINKQ_QUERY_VV, mode, r), points_and_rods.query(MINKQ_QUERY_VV, mode, r));
    EXPECT_EQ(all.query(MINKQ_QUERY_EV, mode, r), points_and_rods.query(MINKQ_QUERY_EV, mode, r));
    EXPECT_EQ(all.query(MINKQ_QUERY_VT, mode, r), mesh_only.query(MINKQ_QUERY_VT, mode, r));
  }
  EXPECT_EQ(all.query(MINKQ_QUERY_EE, MINKQ_MODE_BOX, r), mesh_only.query(MINKQ_QUERY_EE, MINKQ_MODE_BOX, r));
  EXPECT_EQ(all.query(MINKQ_QUERY_EV, MINKQ_MODE_BOX, r, MINKQ_QUERY_LEAF_EXACT), ev_truth(sheet, r));
}

TEST(Codim, swept_steps_find_every_sampled_contact_and_rest_is_static) {
  const test::Device cpu;
  test::Random rng(test::fresh_seed());
  const Mesh from = rods_and_particles(rng, 8, 16, 40, 1.0, 0.0, false);
  Mesh to = from;
  for (size_t v = 0; v < to.vertex_count(); ++v)
    for (int a = 0; a < 3; ++a) to.xyz[3 * v + a] += 0.1f * float(std::sin(0.7 * double(v) + 2.1 * a));
  const float r = 0.03f;
  test::Scene scene(cpu.get(), from, kCodim);
  ASSERT_EQ(minkq_scene_rebuild_swept(scene.get(), test::vertices_of(from, 0), test::vertices_of(to, 0)), MINKQ_SUCCESS);
  Pairs vv_sampled, ev_sampled;
  for (int k = 0; k <= 16; ++k) {
    Mesh at = from;
    for (size_t i = 0; i < at.xyz.size(); ++i) at.xyz[i] = float(from.xyz[i] + (to.xyz[i] - from.xyz[i]) * (k / 16.0));
    for (auto [all, found] : {std::pair{&vv_sampled, vv_truth(at, r)}, std::pair{&ev_sampled, ev_truth(at, r)}}) {
      Pairs merged;
      std::set_union(all->begin(), all->end(), found.begin(), found.end(), std::back_inserter(merged));
      *all = merged;
    }
  }
  for (minkq_mode mode : kModes) {
    EXPECT_TRUE(test::is_subset(vv_sampled, scene.query(MINKQ_QUERY_VV, mode, r))) << "VV mode " << mode;
    EXPECT_TRUE(test::is_subset(ev_sampled, scene.query(MINKQ_QUERY_EV, mode, r))) << "EV mode " << mode;
  }
  minkq_query_info info{};
  const minkq_query_desc leaf{MINKQ_QUERY_EV, MINKQ_MODE_BOX, MINKQ_QUERY_LEAF_EXACT, r};
  EXPECT_EQ(minkq_scene_query(scene.get(), &leaf, nullptr, 0, MINKQ_MEMORY_HOST, &info), MINKQ_ERROR_UNSUPPORTED);
  // At zero motion the static pairs (capsule_exact: the static sphere mode's).
  ASSERT_EQ(minkq_scene_rebuild_swept(scene.get(), test::vertices_of(from, 0), test::vertices_of(from, 0)),
            MINKQ_SUCCESS);
  test::Scene fixed(cpu.get(), from, kCodim);
  for (minkq_query_kind kind : {MINKQ_QUERY_VV, MINKQ_QUERY_EV}) {
    EXPECT_EQ(scene.query(kind, MINKQ_MODE_BOX, r), fixed.query(kind, MINKQ_MODE_BOX, r));
    EXPECT_EQ(scene.query(kind, MINKQ_MODE_CAPSULE_EXACT, r), fixed.query(kind, MINKQ_MODE_SPHERE, r));
  }
}

TEST(Codim, kinds_a_scene_was_not_made_for_are_refused) {
  const test::Device cpu;
  const Mesh sheet = reference::twisted_sheet(4, 1.0);
  test::Scene mesh(cpu.get(), sheet, MINKQ_SCENE_VT | MINKQ_SCENE_EE);
  minkq_query_info info{};
  for (minkq_query_kind kind : {MINKQ_QUERY_VV, MINKQ_QUERY_EV}) {
    const minkq_query_desc q{kind, MINKQ_MODE_BOX, 0, 0.1f};
    EXPECT_EQ(minkq_scene_query(mesh.get(), &q, nullptr, 0, MINKQ_MEMORY_HOST, &info), MINKQ_ERROR_INVALID_ARGUMENT);
    const std::string name = kind == MINKQ_QUERY_VV ? "VV" : "EV";
    EXPECT_EQ(std::string(minkq_last_error_message()), name + " query on a scene created without MINKQ_SCENE_" + name);
  }
  const minkq_query_desc bad{minkq_query_kind(4), MINKQ_MODE_BOX, 0, 0.1f};
  EXPECT_EQ(minkq_scene_query(mesh.get(), &bad, nullptr, 0, MINKQ_MEMORY_HOST, &info), MINKQ_ERROR_INVALID_ARGUMENT);
  // A scene of loose particles: vertices only.
  const std::vector<float> xyz = {0, 0, 0, 0.05f, 0, 0, 1, 1, 1};
  minkq_scene_desc desc{};
  desc.flags = MINKQ_SCENE_VV;
  desc.vertices = cxx::host_buffer(xyz.data(), 3);
  cxx::Scene particles = test::new_scene(cpu.get(), desc);
  EXPECT_EQ(test::Scene::query_pairs(particles.get(), MINKQ_QUERY_VV, MINKQ_MODE_SPHERE, 0.1f, MINKQ_QUERY_LEAF_EXACT),
            (Pairs{{0, 1}}));
  EXPECT_EQ(test::Scene::query_pairs(particles.get(), MINKQ_QUERY_VV, MINKQ_MODE_BOX, 0.05f, MINKQ_QUERY_LEAF_EXACT),
            (Pairs{{0, 1}}));  // r = 0.05 exactly: touching counts
}

}  // namespace
}  // namespace minkq
