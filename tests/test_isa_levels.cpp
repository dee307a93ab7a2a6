// The CPU levels (core/src/cpu/isa.h) give the same pairs in the same order, with the same
// digests and work counts. The leaf scan, compiled at each level this machine has, against the
// shapes' tests box by box on random and extreme boxes; then every query kind, mode and filter
// of the C API, on meshes at three scales, user boxes and a scene of several geometries, run at
// each level and compared with the SSE2 run (tests link the core: cpu::set_active_isa).
#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <string>
#include <vector>

#include "backend.h"
#include "cpu/isa.h"
#include "cuda_checks.h"
#include "geometry_scenes.h"
#include "minkq/traversal.h"

namespace minkq {
namespace {

using cpu::Isa;
using cuda_test::expect_same;
using cuda_test::Outcome;

std::vector<Isa> levels_here() {
  std::vector<Isa> levels;
  for (int k = 0; k <= int(cpu::detected_isa()); ++k) levels.push_back(Isa(k));
  return levels;
}

// Queries run at `isa` while it lives, then at the detected level again.
struct AtLevel {
  explicit AtLevel(Isa isa) { cpu::set_active_isa(isa); }
  ~AtLevel() { cpu::set_active_isa(cpu::detected_isa()); }
};

// ---- The scan at each width and level ---------------------------------------------------------

struct Scanned {
  std::vector<int64_t> positions;  // the positions hit, in the order met
  uint64_t tests = 0;              // work.node_tests: positions scanned
  bool operator==(const Scanned& o) const { return positions == o.positions && tests == o.tests; }
};

template <int W, class Shape>
inline __attribute__((always_inline)) Scanned scan(const BoxGroup* groups, const Shape& shape, int32_t first, int32_t last, int32_t after) {
  Scanned out;
  auto on_hits = [&](int64_t base, unsigned hits, const BoxGroup& group) {
    EXPECT_EQ(&group, groups + base / 4);
    for (int k = 0; k < 4; ++k)
      if (hits >> k & 1u) out.positions.push_back(base + k);
  };
  WorkCounts work;
  scan_leaves<W>(groups, shape, first, last, after, on_hits, work);
  out.tests = work.node_tests;
  return out;
}
// The same 8-lane scan inlined into functions compiled for AVX2 and AVX-512, as cpu/passes.h
// compiles the query loop: the vector code these levels run.
template <class Shape>
__attribute__((target(MINKQ_TARGET_AVX2))) Scanned scan_avx2(const BoxGroup* groups,
                                                                                      const Shape& shape, int32_t first,
                                                                                      int32_t last, int32_t after) {
  return scan<8>(groups, shape, first, last, after);
}
template <class Shape>
__attribute__((target(MINKQ_TARGET_AVX512))) Scanned
scan_avx512(const BoxGroup* groups, const Shape& shape, int32_t first, int32_t last, int32_t after) {
  return scan<8>(groups, shape, first, last, after);
}

// A float from the values where the tests branch or round differently: zeros of both signs,
// subnormals, the float range's ends, infinities, or an ordinary value.
float extreme_or_plain(test::Random& rng, float plain) {
  static const float kEdges[] = {0.0f, -0.0f, 1e-45f, -1e-45f, FLT_MIN, -FLT_MIN, 1e-30f, 1e30f, -1e30f,
                                 FLT_MAX, -FLT_MAX, INFINITY, -INFINITY, 1.0f, -1.0f};
  if (rng.integer(0, 3) != 0) return plain;
  return kEdges[rng.integer(0, int(sizeof(kEdges) / sizeof(float)) - 1)];
}

Vec3 extreme_vec3(test::Random& rng) {
  const Vec3 v = rng.vec3(-1.0f, 1.0f);
  return {extreme_or_plain(rng, v.x), extreme_or_plain(rng, v.y), extreme_or_plain(rng, v.z)};
}

// Scanned positions of every range [first, last] (with `after` before, inside and at its end)
// at 4 and 8 lanes and at each level, against overlaps box by box.
template <class Shape>
void check_scans(const std::vector<Box>& boxes, const std::vector<BoxGroup>& groups, const Shape& shape,
                 const std::string& what) {
  const int32_t n = int32_t(boxes.size());
  for (int32_t first = 0; first < n; ++first)
    for (int32_t last = first; last < n; ++last)
      for (int32_t after : {first - 1, (first + last) / 2, last}) {
        Scanned want;
        for (int32_t p = std::max(first, after + 1); p <= last; ++p) {
          ++want.tests;
          if (shape.overlaps(boxes[size_t(p)])) want.positions.push_back(p);
        }
        const std::string at = what + " range " + std::to_string(first) + ".." + std::to_string(last) + " after " +
                               std::to_string(after);
        ASSERT_EQ(scan<4>(groups.data(), shape, first, last, after), want) << at << " (4 lanes)";
        ASSERT_EQ(scan<8>(groups.data(), shape, first, last, after), want) << at << " (8 lanes)";
        if (cpu::detected_isa() >= Isa::kAvx2)
          ASSERT_EQ(scan_avx2(groups.data(), shape, first, last, after), want) << at << " (avx2)";
        if (cpu::detected_isa() >= Isa::kAvx512)
          ASSERT_EQ(scan_avx512(groups.data(), shape, first, last, after), want) << at << " (avx512)";
      }
}

TEST(IsaLevels, leaf_scans_at_every_width_and_level_match_the_test_box_by_box) {
  std::printf("[ levels   ] this machine: up to %s\n", cpu::isa_name(cpu::detected_isa()));
  test::Random rng(test::fresh_seed());
  for (int trial = 0; trial < 24; ++trial) {
    const int32_t n = rng.integer(1, 27);
    std::vector<Box> boxes(static_cast<size_t>(n));
    for (Box& b : boxes) {
      b = rng.box(rng.vec3(-1.0f, 1.0f), 0.5f);
      if (rng.integer(0, 2) == 0) b = {extreme_vec3(rng), extreme_vec3(rng)};  // empty or unbounded too
    }
    // As a host tree keeps them: groups of four, the lanes past n zeroed, kScanPadGroups more.
    std::vector<BoxGroup> groups(size_t(box_group_count(n) + kScanPadGroups), BoxGroup{});
    for (int32_t p = 0; p < n; ++p) set_group_box(groups[size_t(p >> 2)], p & 3, boxes[size_t(p)]);
    for (int q = 0; q < 6; ++q) {
      const Vec3 p0 = extreme_vec3(rng), p1 = rng.integer(0, 3) == 0 ? p0 : extreme_vec3(rng);
      const float r = extreme_or_plain(rng, rng.log_uniform(1e-3f, 1.0f));
      if (!(r >= 0.0f)) continue;  // radii are checked non-negative before any query
      const QueryGeometry g{p0, p1, r};
      const std::string what = "trial " + std::to_string(trial) + " query " + std::to_string(q);
      check_scans(boxes, groups, BoxShape::from(g), what + " box");
      check_scans(boxes, groups, SphereShape::from(g), what + " sphere");
      check_scans(boxes, groups, CapsuleRayShape::from(g), what + " capsule_ray");
      check_scans(boxes, groups, CapsuleExactShape::from(g), what + " capsule_exact");
      if (HasFatalFailure()) return;
    }
  }
}

// ---- Whole queries at each level ---------------------------------------------------------------

// Every kind and mode of `scene`, with and without LEAF_EXACT, in the order the query writes
// them (not canonical) and canonical with a digest: at each level the same as at SSE2.
void compare_levels(minkq_scene* scene, bool codim, float r, const std::string& label) {
  std::vector<cuda_test::ModeCase> modes(std::begin(cuda_test::kModes), std::end(cuda_test::kModes));
  if (codim) modes.insert(modes.end(), std::begin(cuda_test::kCodimModes), std::end(cuda_test::kCodimModes));
  for (const cuda_test::ModeCase& m : modes)
    for (uint32_t leaf : {0u, uint32_t(MINKQ_QUERY_LEAF_EXACT)})
      for (uint32_t order : {0u, uint32_t(MINKQ_QUERY_CANONICAL | MINKQ_QUERY_DIGEST)}) {
        // Without MINKQ_QUERY_STATS: queries that count their work run at SSE2 (cpu/passes.h).
        const uint32_t flags = leaf | order;
        Outcome sse2;
        {
          AtLevel at(Isa::kSse2);
          sse2 = cuda_test::scene_query(scene, m.kind, m.mode, r, flags);
        }
        for (Isa isa : levels_here()) {
          AtLevel at(isa);
          const std::string what = label + " " + m.name + (leaf ? " leaf_exact" : "") + (order ? " canonical" : "") +
                                   " r=" + std::to_string(r) + " at " + cpu::isa_name(isa);
          expect_same(sse2, cuda_test::scene_query(scene, m.kind, m.mode, r, flags), what);
        }
      }
}

TEST(IsaLevels, every_kind_and_mode_gives_the_same_pairs_in_the_same_order_at_every_level) {
  const uint64_t seed = test::fresh_seed();
  test::Device cpu("cpu");
  const std::string name = minkq_device_name(cpu.get());
  EXPECT_NE(name.find(cpu::isa_name(cpu::active_isa())), std::string::npos) << name;
  for (auto [label, mesh] : {std::pair{std::string("soup"), reference::random_soup(700, seed, 0.12)},
                             std::pair{std::string("twisted sheet"), reference::twisted_sheet(16, 3.0)}})
    for (double scale : {1e-3, 1.0, 1e3}) {  // the same pairs at every scale: no absolute epsilon
      reference::Mesh scaled = mesh;
      reference::transform(scaled, scale, 0.0);
      const uint32_t flags = cuda_test::kBoth | MINKQ_SCENE_VV | MINKQ_SCENE_EV | MINKQ_SCENE_DROP_INCIDENT;
      cxx::Scene scene = test::new_scene(cpu.get(), scaled, flags);
      ASSERT_TRUE(scene);
      const double edge = reference::mean_edge_length(scaled);
      for (double factor : {0.0, 0.5, 1.5})
        compare_levels(scene.get(), true, float(factor * edge), label + " x" + std::to_string(scale));
    }
}

TEST(IsaLevels, user_boxes_and_scenes_of_many_geometries_are_the_same_at_every_level) {
  const uint64_t seed = test::fresh_seed();
  test::Device cpu("cpu");
  test::Random rng(seed);
  std::vector<Box> boxes(3000);
  for (Box& b : boxes) b = rng.box(rng.vec3(0.0f, 1.0f), 0.03f);
  std::vector<Vec3> p0(2000), p1(2000);
  for (size_t i = 0; i < p0.size(); ++i) {
    p0[i] = rng.vec3(0.0f, 1.0f);
    p1[i] = p0[i] + rng.vec3(-0.05f, 0.05f);
  }
  cxx::Bvh bvh = cuda_test::make_bvh(cpu.get(), boxes);
  ASSERT_TRUE(bvh);
  for (float r : {0.0f, 0.02f})
    for (minkq_mode mode : {MINKQ_MODE_BOX, MINKQ_MODE_CAPSULE_RAY, MINKQ_MODE_CAPSULE_EXACT}) {
      Outcome sse2;
      {
        AtLevel at(Isa::kSse2);
        sse2 = cuda_test::bvh_query(bvh.get(), MINKQ_SHAPE_CAPSULE, mode, r, p0, p1);
      }
      for (Isa isa : levels_here()) {
        AtLevel at(isa);
        expect_same(sse2, cuda_test::bvh_query(bvh.get(), MINKQ_SHAPE_CAPSULE, mode, r, p0, p1),
                    "capsules mode " + std::to_string(mode) + " r=" + std::to_string(r) + " at " + cpu::isa_name(isa));
      }
    }
  // Jobs across geometries (jobs.h's passes): a cloth, a rigid body and particles.
  std::vector<reference::Geometry> geometries = {
      test::make_geometry(reference::twisted_sheet(24, 2.0), test::kAllKinds, MINKQ_GEOMETRY_SELF),
      test::make_geometry(reference::random_soup(400, seed, 0.1), test::kAllKinds, 0),
      test::make_geometry(reference::random_soup(300, seed + 1, 0.05), test::kAllKinds, MINKQ_GEOMETRY_SELF)};
  cxx::Scene scene = test::new_geometry_scene(cpu.get(), geometries);
  ASSERT_TRUE(scene);
  compare_levels(scene.get(), true, 0.02f, "geometries");
}

TEST(IsaLevels, a_level_this_processor_lacks_is_refused_by_name) {
  if (cpu::detected_isa() == Isa::kAvx512) GTEST_SKIP() << "this processor has every level";
  try {
    cpu::set_active_isa(Isa::kAvx512);
    FAIL() << "avx512 accepted on a processor without it";
  } catch (const Failure& failure) {
    EXPECT_NE(std::string(failure.what()).find("avx512"), std::string::npos) << failure.what();
  }
}

}  // namespace
}  // namespace minkq
