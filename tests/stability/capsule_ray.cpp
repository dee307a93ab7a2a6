// test_stability's capsule ray check: the capsule_ray node test with the core's parametrisation
// (direction e1 - e0, t in [0, 1]; through the C API and through a test traversal of the same
// tree) beside a unit direction with t in [0, |e|], implemented here only (CapsuleUnitShape),
// plain and with the length taken after rescaling. Its meshes and oracle runs are apart from
// the cases of every mode.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "cpu/tree.h"
#include "minkq/predicates.h"
#include "minkq/query_sources.h"
#include "minkq/shapes.h"
#include "minkq/traversal.h"
#include "capi_util.h"
#include "stability/stability.h"

namespace minkq::test::stability {
namespace {

// ---- The unit-direction capsule ray (here only) ---------------------------------------------
// Segment p0 + t u, u = d / |d| rounded, t in [0, L] with L = |d| rounded up, against the box
// inflated by r in every axis; the same outward rounding as capsule_ray_overlaps_box: inflated
// box rounded outward, each slab's t-interval widened by 2^-20 relative plus FLT_MIN, the far
// bound L widened by 2^-20 relative. `rescale` takes the length of d / max|d_k| (then times
// max|d_k|), the usual guard against the square under- or overflowing.
struct CapsuleUnitShape {
  minkq::Box box;
  minkq::Vec3 p0, u;
  float t_max, r;
  static CapsuleUnitShape make(minkq::Vec3 p0, minkq::Vec3 p1, float r, bool rescale) {
    const minkq::Vec3 d = p1 - p0;
    float len;
    minkq::Vec3 u;
    if (rescale) {
      const float m = fmaxf(fabsf(d.x), fmaxf(fabsf(d.y), fabsf(d.z)));
      if (m > 0.0f) {
        const minkq::Vec3 s{d.x / m, d.y / m, d.z / m};
        const float ls = sqrtf(s.x * s.x + s.y * s.y + s.z * s.z);
        u = {s.x / ls, s.y / ls, s.z / ls};
        len = ls * m;
      } else {
        u = {0, 0, 0}, len = 0;
      }
    } else {
      len = sqrtf(d.x * d.x + d.y * d.y + d.z * d.z);
      u = len > 0.0f ? minkq::Vec3{d.x / len, d.y / len, d.z / len} : minkq::Vec3{0, 0, 0};
    }
    const float t_max = minkq::next_up(len * (1.0f + minkq::kSlabWidening));
    return {minkq::padded_segment_box(p0, p1, r), p0, u, t_max, r};
  }
  // The Shape contract's constructor (shapes.h): the plain unit-direction form.
  static CapsuleUnitShape from(const minkq::QueryGeometry& q) { return make(q.p0, q.p1, q.r, false); }
  // Its box inside the tree, the slab test at primitives (as the core's shapes).
  bool may_overlap(const minkq::Box& b) const { return minkq::boxes_overlap(box, b); }
  bool overlaps(const minkq::Box& b) const { return may_overlap(b) && finer(b); }
  unsigned overlaps_group(const minkq::BoxGroup& g, unsigned lanes) const { return minkq::overlaps_each(*this, g, lanes); }
  bool finer(const minkq::Box& b) const { return minkq::segment_slabs_overlap(p0, u, t_max, r, b); }
};

// The core's shape through the same test traversal (a cross-check of the C API's capsule_ray).
struct CoreRayShape {
  minkq::CapsuleRayShape s;
  static CoreRayShape from(const minkq::QueryGeometry& q) { return {minkq::CapsuleRayShape::from(q)}; }
  bool may_overlap(const minkq::Box& b) const { return s.may_overlap(b); }
  unsigned overlaps_group(const minkq::BoxGroup& g, unsigned lanes) const { return s.overlaps_group(g, lanes); }
  bool overlaps(const minkq::Box& b) const { return s.overlaps(b); }
  bool finer(const minkq::Box& b) const { return s.finer(b); }
};

// EE pairs (e, f), e < f, no shared vertex, from a traversal of an edge tree with a shape.
template <class MakeShape>
PairSet ee_pairs_with(const ref::Mesh& m, MakeShape make) {
  const auto* v = reinterpret_cast<const minkq::Vec3*>(m.xyz.data());
  const auto* e = reinterpret_cast<const minkq::Edge*>(m.edges.data());
  const int32_t n = int32_t(m.edge_count());
  minkq::CpuTree tree;
  tree.build(minkq::EdgeBoxes{v, e}, n);
  std::vector<std::vector<uint64_t>> parts(size_t(n + 255) / 256);
  tbb::parallel_for(int32_t(0), int32_t(parts.size()), [&](int32_t b) {
    for (int32_t q = b * 256; q < std::min(n, (b + 1) * 256); ++q) {
      const auto shape = make(v[e[q].v[0]], v[e[q].v[1]]);
      auto on_leaf = [&](int32_t f, const minkq::Box&) {
        if (f <= q) return;
        if (minkq::share_vertex(e[q], e[f])) return;
        parts[size_t(b)].push_back(minkq::pack_pair(q, f));
      };
      minkq::NoWork work;
      minkq::traverse(tree.view(), shape, -1, on_leaf, work);
    }
  });
  PairSet out;
  for (const auto& p : parts) out.insert(out.end(), p.begin(), p.end());
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

std::vector<RayRow> ray_study() {
  std::vector<std::pair<std::string, std::pair<ref::Mesh, float>>> meshes;
  const ref::Mesh sheets = ref::stacked_sheets(10, 3, 0.05);
  const float rs = 0.06f;  // above the layer gap: every layer meets its neighbours
  for (int k : {-120, -100, -80, -70, -64, -40, 0, 40, 62, 64, 66, 70, 100, 120}) {
    ref::Mesh m = sheets;
    ref::transform(m, std::ldexp(1.0, k), 0.0);
    meshes.push_back({"stacked sheets x 2^" + std::to_string(k), {m, std::ldexp(rs, k)}});
  }
  {
    // Short edges beside long ones in one mesh: a sheet with every 3rd row collapsed to 2^-40.
    ref::Mesh m = ref::grid_sheet(16);
    for (size_t v = 0; v < m.vertex_count(); ++v) {
      const int j = int(v / 16);
      if (j % 3 == 1) m.xyz[3 * v + 1] = float(double(m.xyz[3 * v + 1] - 1.0f / 15) + std::ldexp(1.0, -40));
      m.xyz[3 * v + 2] = float(0.01 * (v % 2));
    }
    meshes.push_back({"sheet with 2^-40-short edges", {m, float(0.02)}});
  }
  std::vector<RayRow> out;
  for (auto& [name, mr] : meshes) {
    const ref::Mesh& m = mr.first;
    const float r = mr.second;
    RayRow row;
    row.name = name;
    std::fprintf(stderr, "[capsule ray] %s: r = %.9g\n", name.c_str(), double(r));
    const PairSet truth = to_set(ref::ee_contacts(m, r, true));
    row.truth = truth.size();
    // 0: the C API's capsule_ray; 1: the core shape through the bench traversal; 2: unit
    // direction; 3: unit direction with the length rescaled.
    {
      const Device dev;
      const cxx::Scene scene = new_scene(dev.get(), m, MINKQ_SCENE_VT | MINKQ_SCENE_EE | MINKQ_SCENE_DROP_INCIDENT);
      const cxx::Result res = new_result();
      const minkq_query_desc q{MINKQ_QUERY_EE, MINKQ_MODE_CAPSULE_RAY, 0, r};
      EXPECT_EQ(minkq_scene_query_result(scene.get(), &q, res.get()), MINKQ_SUCCESS) << minkq_last_error_message();
      const PairSet got = to_set(minkq_result_pairs(res.get()), minkq_result_count(res.get()));
      row.cand[0] = got.size(), row.fn[0] = missing(truth, got);
    }
    const PairSet core = ee_pairs_with(m, [r](minkq::Vec3 a, minkq::Vec3 b) {
      return CoreRayShape::from({a, b, r});
    });
    const PairSet unit = ee_pairs_with(m, [r](minkq::Vec3 a, minkq::Vec3 b) { return CapsuleUnitShape::from({a, b, r}); });
    const PairSet unit_rescaled = ee_pairs_with(m, [r](minkq::Vec3 a, minkq::Vec3 b) { return CapsuleUnitShape::make(a, b, r, true); });
    row.cand[1] = core.size(), row.fn[1] = missing(truth, core);
    row.cand[2] = unit.size(), row.fn[2] = missing(truth, unit);
    row.cand[3] = unit_rescaled.size(), row.fn[3] = missing(truth, unit_rescaled);
    out.push_back(row);
  }
  return out;
}

}  // namespace minkq::test::stability
