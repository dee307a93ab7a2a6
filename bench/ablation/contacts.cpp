// minkq_ablation's contact study (contacts.md, issue 8): the node test and the leaf screen under
// the leaf distance test.
#include <cmath>
#include <cstdio>

#include "ablation/ablation.h"

namespace minkq::bench::ablation {
namespace {

// A library source with a study's leaf test in place of its own: `candidates` (the source
// without kLeafExact) keeps its incident-pair and reverse finer tests, then leaf_test(q, prim).
template <class Queries, class LeafTest>
struct WithLeafTest {
  Queries candidates;
  LeafTest leaf_test;
  WithLeafTest(Queries source, LeafTest test) : candidates(source), leaf_test(test) { candidates.filters &= ~kLeafExact; }
  QueryTarget target(int32_t i) const { return candidates.target(i); }
  QueryGeometry geometry(QueryTarget t) const { return candidates.geometry(t); }
  unsigned dropped_lanes(QueryTarget t, int64_t base, unsigned hits, const int32_t* sorted_prims) const {
    return candidates.dropped_lanes(t, base, hits, sorted_prims);
  }
  template <class Shape>
  bool tests_rest() const {
    return true;
  }
  template <class Shape>
  bool accept_rest(QueryTarget t, int32_t prim, int64_t p) const {
    return candidates.template accept_rest<Shape>(t, prim, p) && leaf_test(t.q, prim);
  }
  Pair pair(int32_t q, int32_t prim) const { return candidates.pair(q, prim); }
};

// EE's screen tried for VT (not kept): point p against triangle abc along v = 3 (p - the
// centroid), where the triangle's projection ends at max_k v.x_k, so the gap is
// min_k v.(p - x_k) / |v|; "apart" beyond r + 2^-18 T, T = max_k |p - x_k|_1 >= S (the bound
// argument of predicates.h's segments_apart).
bool point_triangle_apart(Vec3 p, Vec3 a, Vec3 b, Vec3 c, float r) {
  const Vec3d pd = to_double(p);
  const Vec3d pa = pd - to_double(a), pb = pd - to_double(b), pc = pd - to_double(c);
  const Vec3d v = pa + pb + pc;
  const double vv = dot(v, v);
  if (!(vv > 0.0)) return false;  // p at the centroid: no axis
  const double gap = min_num(dot(v, pa), min_num(dot(v, pb), dot(v, pc))) / std::sqrt(vv);
  return gap > double(r) + 0x1p-18 * max3(abs_sum(pa), abs_sum(pb), abs_sum(pc));
}

}  // namespace

// Contacts (MINKQ_QUERY_LEAF_EXACT) four ways on the library's trees at the last frame: the
// finer node mode (sphere for VT, capsule_exact for EE: the benchmark's leaf_exact before) or
// the box test, each with the full distance test alone or behind the separation screen (EE:
// the library's; VT: the study's). The four must return the same pairs; they run round-robin.
std::string compare_contacts(const SceneFrames& sc, int repeats, bool& ok) {
  const auto* v = reinterpret_cast<const Vec3*>(sc.frames.back().data());
  const auto* t = reinterpret_cast<const Triangle*>(sc.mesh.tris.data());
  const auto* e = reinterpret_cast<const Edge*>(sc.mesh.edges.data());
  const float r = float(sc.radius_factor * sc.mean_edge);
  std::fprintf(stderr, "%s (contacts): %zu V, %zu T, r = %.4g\n", sc.name.c_str(), sc.mesh.vertex_count(),
               sc.mesh.triangle_count(), double(r));
  const FrameTrees trees(sc, v, t, e);
  const uint32_t filters = kDropIncident | kLeafExact;
  const VertexTriangleQueries vt{v, t, trees.order.data(), r, filters};
  const EdgeEdgeQueries ee{v, e, trees.edges.sorted_prims().data(), r, filters};
  // VT behind the study's screen; EE with the full distance alone (before the library's screen).
  const WithLeafTest vt_screened(vt, [&vt](int32_t q, int32_t t) {
    const Triangle tri = vt.prims[t];
    const Vec3 *x = vt.vertices, p = x[q], a = x[tri.v[0]], b = x[tri.v[1]], c = x[tri.v[2]];
    return !point_triangle_apart(p, a, b, c, vt.r) && point_triangle_within(p, a, b, c, vt.r);
  });
  const WithLeafTest ee_full(ee, [&ee](int32_t e, int32_t f) {
    const Edge lo = ee.edges[e < f ? e : f], hi = ee.edges[e < f ? f : e];
    const Vec3* x = ee.vertices;
    return segment_segment_distance_within(x[lo.v[0]], x[lo.v[1]], x[hi.v[0]], x[hi.v[1]], ee.r);
  });
  const BvhView tri = trees.triangles.view(), edge = trees.edges.view();
  // [kind][variant]; variants: finer + full, box + full, box + screen, finer + screen.
  static const char* const labels[2][4] = {
      {"finer node test, full distance test (before)", "box node test, full distance test (kept)",
       "box node test, separation screen first", "finer node test, separation screen first"},
      {"finer node test, full distance test (before)", "box node test, full distance test",
       "box node test, separation screen first (kept)", "finer node test, separation screen first"}};
  const auto got = round_robin(4, 2, 3 * repeats, [&](size_t variant, int kind, int reps) {
    if (kind == 0) {
      switch (variant) {
        case 0: return run<SphereShape>(tri, vt, trees.nv, reps);
        case 1: return run<BoxShape>(tri, vt, trees.nv, reps);
        case 2: return run<BoxShape>(tri, vt_screened, trees.nv, reps);
        default: return run<SphereShape>(tri, vt_screened, trees.nv, reps);
      }
    }
    switch (variant) {
      case 0: return run<CapsuleExactShape>(edge, ee_full, trees.ne, reps);
      case 1: return run<BoxShape>(edge, ee_full, trees.ne, reps);
      case 2: return run<BoxShape>(edge, ee, trees.ne, reps);
      default: return run<CapsuleExactShape>(edge, ee, trees.ne, reps);
    }
  });
  std::string out;
  for (int kind = 0; kind < 2; ++kind)
    for (size_t i = 0; i < 4; ++i) {
      ok &= got[i][size_t(kind)].pairs == got[0][size_t(kind)].pairs;
      const bool box = i == 1 || i == 2;
      out += row(sc.name, kind ? "EE" : "VT", box ? "box" : kind ? "capsule_exact" : "sphere", labels[kind][i],
                 got[i][size_t(kind)], kind ? trees.ne : trees.nv, got[0][size_t(kind)]);
    }
  return out;
}

}  // namespace minkq::bench::ablation
