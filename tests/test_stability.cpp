// Numerical stability on stiff and extreme inputs (issue 7; formerly bench/stability's report):
// large offsets, scaled meshes, radii from 1e-9 to 1e3 of the scene, near-parallel edges, sheets
// stacked at exactly r and r +- a few ulp, degenerate elements (tests/stability/cases.cpp), each
// through every mode on every backend. Checked per case, backend and mode:
//  - no false negative against the long-double oracle;
//  - every candidate within the bound core/include/minkq/predicates.h states for its mode
//    (tests/stability/bounds.cpp), except where a node predicate's intermediate went non-finite
//    (squares beyond FLT_MAX), where the finer tests may accept what the box test accepts;
//  - a scaling by 2^k (|k| <= 40) or 1e+-3 gives the unscaled case's candidate sets.
// And the capsule ray: the core's parametrisation (e1 - e0, t <= 1) misses nothing at any edge
// length, where a unit direction with t <= |e| does unless |e| is taken after rescaling
// (tests/stability/capsule_ray.cpp).
#include <gtest/gtest.h>

#include <map>
#include <string>

#include "capi_util.h"
#include "stability/stability.h"

namespace minkq::test::stability {
namespace {

struct ModeSpec {
  minkq_query_kind kind;
  const char* name;
  minkq_mode mode;
  uint32_t flags;
  Metric metric;
};
const ModeSpec kModes[] = {
    {MINKQ_QUERY_VT, "box", MINKQ_MODE_BOX, 0, Metric::kBox},
    {MINKQ_QUERY_VT, "sphere", MINKQ_MODE_SPHERE, 0, Metric::kSphere},
    {MINKQ_QUERY_VT, "leaf_exact", MINKQ_MODE_SPHERE, MINKQ_QUERY_LEAF_EXACT, Metric::kLeaf},
    {MINKQ_QUERY_EE, "box", MINKQ_MODE_BOX, 0, Metric::kBox},
    {MINKQ_QUERY_EE, "capsule_ray", MINKQ_MODE_CAPSULE_RAY, 0, Metric::kRay},
    {MINKQ_QUERY_EE, "capsule_exact", MINKQ_MODE_CAPSULE_EXACT, 0, Metric::kCapsuleExact},
    {MINKQ_QUERY_EE, "leaf_exact", MINKQ_MODE_CAPSULE_EXACT, MINKQ_QUERY_LEAF_EXACT, Metric::kLeaf},
};

std::vector<std::string> backends() {
  std::vector<std::string> out = {"cpu"};
  if (minkq_cuda_device_count() > 0) out.push_back("cuda");
  return out;
}

// Candidate sets of the cases run so far: case -> backend/kind/mode -> set.
using Sets = std::map<std::string, std::map<std::string, PairSet>>;

void check_case(const Case& c, Sets& sets) {
  SCOPED_TRACE("case " + c.name + ", r = " + fmt(c.r, 9));
  const PairSet vt_truth = to_set(ref::vt_contacts(c.mesh, c.r, true));
  const PairSet ee_truth = to_set(ref::ee_contacts(c.mesh, c.r, true));
  for (const std::string& backend : backends()) {
    const Device device(backend.c_str());
    minkq_scene_desc desc{};
    desc.flags = MINKQ_SCENE_VT | MINKQ_SCENE_EE | MINKQ_SCENE_DROP_INCIDENT;
    desc.vertices = host_buffer(c.mesh.xyz.data(), c.mesh.vertex_count());
    desc.triangles = host_buffer(c.mesh.tris.data(), c.mesh.triangle_count());
    desc.edges = host_buffer(c.mesh.edges.data(), c.mesh.edge_count());
    const cxx::Scene scene = new_scene(device.get(), desc);
    ASSERT_TRUE(scene);
    const cxx::Result result = new_result();
    PairSet vt_box, ee_box;
    std::map<std::string, Excess> excess;
    for (const ModeSpec& m : kModes) {
      const bool vt = m.kind == MINKQ_QUERY_VT;
      const std::string key = backend + "/" + (vt ? "VT/" : "EE/") + m.name;
      SCOPED_TRACE(key);
      const minkq_query_desc q{m.kind, m.mode, m.flags, c.r};
      ASSERT_EQ(minkq_scene_query_result(scene.get(), &q, result.get()), MINKQ_SUCCESS) << minkq_last_error_message();
      const PairSet got = to_set(minkq_result_pairs(result.get()), minkq_result_count(result.get()));
      if (m.mode == MINKQ_MODE_BOX) (vt ? vt_box : ee_box) = got;
      EXPECT_EQ(missing(vt ? vt_truth : ee_truth, got), 0u) << "false negatives";
      Excess& ex = excess[key];
      for (uint64_t packed : got) {
        const minkq::Pair pair = minkq::unpack_pair(packed);
        measure_excess(c.mesh, vt, pair.first, pair.second, LD(c.r), m.metric, ex);
      }
      if (!c.compare_to.empty() && !c.compare_only) {
        const PairSet& unscaled = sets.at(c.compare_to).at(key);
        EXPECT_EQ(missing(unscaled, got) + missing(got, unscaled), 0u) << "candidates differ from " << c.compare_to;
      }
      sets[c.name][key] = got;
    }
    // Beyond the stated bound only where an intermediate overflowed (predicates.h's bounds
    // assume finite squares).
    const NonFinite nf = non_finite(c.mesh, c.r, vt_box, ee_box);
    for (const auto& [key, ex] : excess)
      if (nf.text() == "0")
        EXPECT_EQ(ex.over, 0u) << key << ": candidates beyond the stated bound (worst excess / slack "
                               << double(ex.worst_ratio) << ") with every intermediate finite";
  }
}

void check_group(const std::string& group) {
  Sets sets;
  for (const Case& c : cases())
    if (c.group == group || (group == "scale" && c.name == "base")) check_case(c, sets);
}

TEST(Stability, Offsets) { check_group("offset"); }
TEST(Stability, Scalings) { check_group("scale"); }
TEST(Stability, Radii) { check_group("radius"); }
TEST(Stability, NearParallelEdges) { check_group("near-parallel"); }
TEST(Stability, SheetsStackedAtRPlusMinusUlps) { check_group("stacked"); }
TEST(Stability, DegenerateElements) { check_group("degenerate"); }

// The capsule ray with direction e1 - e0 and t <= 1 (the core's) finds every contact for edges
// from 2^-120 to 2^120 long; so does a unit direction with the length taken after rescaling,
// while the plain unit direction misses contacts there (which shows the check sees misses).
TEST(Stability, CapsuleRayParametrisation) {
  uint64_t unit_misses = 0;
  for (const RayRow& row : ray_study()) {
    SCOPED_TRACE(row.name);
    EXPECT_GT(row.truth, 0u);
    EXPECT_EQ(row.fn[0], 0u) << "C API capsule_ray";
    EXPECT_EQ(row.fn[1], 0u) << "core CapsuleRayShape";
    EXPECT_EQ(row.fn[3], 0u) << "unit direction, rescaled";
    unit_misses += row.fn[2];
  }
  EXPECT_GT(unit_misses, 0u) << "the unit direction without rescaling was expected to miss contacts";
}

}  // namespace
}  // namespace minkq::test::stability
