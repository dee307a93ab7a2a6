// test_stability's measures of a candidate: how far beyond r it
// lies in its mode's own metric against the slack the bound of core/include/minkq/predicates.h
// allows (long double, on the float coordinates), and which intermediates of the node
// predicates go non-finite on a case. Kept apart from the runs (test_stability.cpp): these
// metrics and slacks are what a reader checks against predicates.h.
#include <algorithm>
#include <cfloat>
#include <cmath>

#include "minkq/predicates.h"
#include "minkq/query_sources.h"
#include "stability/stability.h"

namespace minkq::test::stability {
namespace {

// ---- Long-double measures of how far a candidate lies --------------------------------------
struct P {
  LD x[3];
};
P at(const ref::Mesh& m, int32_t v) { return {{LD(m.xyz[3 * size_t(v)]), LD(m.xyz[3 * size_t(v) + 1]), LD(m.xyz[3 * size_t(v) + 2])}}; }
struct BoxL {
  LD lo[3], hi[3];
};
BoxL box_of(std::initializer_list<P> ps) {
  BoxL b;
  for (int k = 0; k < 3; ++k) b.lo[k] = INFINITY, b.hi[k] = -INFINITY;
  for (const P& p : ps)
    for (int k = 0; k < 3; ++k) b.lo[k] = std::min(b.lo[k], p.x[k]), b.hi[k] = std::max(b.hi[k], p.x[k]);
  return b;
}
LD excess_of(LD x, LD lo, LD hi) { return x < lo ? lo - x : (x > hi ? x - hi : 0); }
// Distance from p0 + t (p1 - p0) to the box, Euclidean or Chebyshev, minimised over t in [0, 1]
// by golden-section search (the distance is convex in t).
LD segment_box(const P& p0, const P& p1, const BoxL& b, bool chebyshev) {
  auto f = [&](LD t) {
    LD acc = 0;
    for (int k = 0; k < 3; ++k) {
      const LD e = excess_of(p0.x[k] + t * (p1.x[k] - p0.x[k]), b.lo[k], b.hi[k]);
      acc = chebyshev ? std::max(acc, e) : acc + e * e;
    }
    return chebyshev ? acc : std::sqrt(acc);
  };
  LD a = 0, c = 1;
  const LD g = (std::sqrt(LD(5)) - 1) / 2;
  LD x1 = c - g * (c - a), x2 = a + g * (c - a), f1 = f(x1), f2 = f(x2);
  for (int i = 0; i < 160; ++i) {
    if (f1 <= f2) { c = x2; x2 = x1; f2 = f1; x1 = c - g * (c - a); f1 = f(x1); }
    else { a = x1; x1 = x2; f1 = f2; x2 = a + g * (c - a); f2 = f(x2); }
  }
  return std::min({f(0), f(1), f1, f2});
}
LD dist(const P& a, const P& b) {
  LD s = 0;
  for (int k = 0; k < 3; ++k) s += (a.x[k] - b.x[k]) * (a.x[k] - b.x[k]);
  return std::sqrt(s);
}
LD float_ulp(LD x) {  // ulp of a float of magnitude x
  x = std::fabs(x);
  if (x < LD(FLT_MIN)) return LD(1.40129846e-45f);
  int e;
  std::frexp(double(x), &e);
  return std::ldexp(LD(1), e - 24);
}

minkq::Vec3 vf(const ref::Mesh& m, int32_t v) { return {m.xyz[3 * size_t(v)], m.xyz[3 * size_t(v) + 1], m.xyz[3 * size_t(v) + 2]}; }
bool finite_box(const minkq::Box& b) {
  return std::isfinite(b.lo.x) && std::isfinite(b.lo.y) && std::isfinite(b.lo.z) && std::isfinite(b.hi.x) &&
         std::isfinite(b.hi.y) && std::isfinite(b.hi.z);
}

}  // namespace

// Distance of candidate (q, p) in the mode's own metric, and the slack its stated bound allows:
//  box            Chebyshev gap between the query's exact box and p's box; slack half an ulp of
//                 r (box_gap_within: a float difference rounded to at most r)
//  sphere         Euclidean point-box distance; slack r 2^-17 plus the underflow allowance
//                 sqrt(19 * 2^-149) (predicates.h: d2 error 6u + 3 * 2^-150, r2 bound + 16 * 2^-149)
//  capsule_ray    Chebyshev distance from the segment to p's box; slack 2^-19 |d|_inf (the t range
//                 widening) plus 2 float ulps of the inflated box
//  capsule_exact  Euclidean segment-box distance D; slack 2^-17 (r + |d|_1) + 2^-18 (D + |d|_1)
//                 plus 2^-22 of the threshold (its square rounded up)
//  leaf_exact     primitive distance (oracle); slack 2^-19 S (S: predicates.h's operand size)
void measure_excess(const ref::Mesh& m, bool vt, int32_t q, int32_t p, LD r, Metric metric, Excess& ex) {
  P q0, q1;
  if (vt) q0 = q1 = at(m, q);
  else q0 = at(m, m.edges[2 * size_t(q)]), q1 = at(m, m.edges[2 * size_t(q) + 1]);
  P a, b, c;
  BoxL pb;
  if (vt) {
    a = at(m, m.tris[3 * size_t(p)]), b = at(m, m.tris[3 * size_t(p) + 1]), c = at(m, m.tris[3 * size_t(p) + 2]);
    pb = box_of({a, b, c});
  } else {
    a = at(m, m.edges[2 * size_t(p)]), b = at(m, m.edges[2 * size_t(p) + 1]);
    pb = box_of({a, b});
  }
  LD d = 0, slack = 0, big = 0, dinf = 0, d1 = 0;
  for (int k = 0; k < 3; ++k) {
    big = std::max({big, std::fabs(q0.x[k]) + r, std::fabs(q1.x[k]) + r});
    const LD dk = std::fabs(q1.x[k] - q0.x[k]);
    dinf = std::max(dinf, dk), d1 += dk;
  }
  switch (metric) {
    case Metric::kBox: {
      const BoxL qb = box_of({q0, q1});
      for (int k = 0; k < 3; ++k) d = std::max({d, qb.lo[k] - pb.hi[k], pb.lo[k] - qb.hi[k]});
      slack = float_ulp(r) / 2;
      break;
    }
    case Metric::kSphere: {
      LD s = 0;
      for (int k = 0; k < 3; ++k) s += excess_of(q0.x[k], pb.lo[k], pb.hi[k]) * excess_of(q0.x[k], pb.lo[k], pb.hi[k]);
      d = std::sqrt(s);
      slack = r * std::ldexp(LD(1), -17) + std::sqrt(19 * std::ldexp(LD(1), -149));
      break;
    }
    case Metric::kRay:
      d = segment_box(q0, q1, pb, true);
      slack = std::ldexp(LD(1), -19) * dinf + 2 * float_ulp(big);
      break;
    case Metric::kCapsuleExact:
      d = segment_box(q0, q1, pb, false);
      slack = std::ldexp(LD(1), -17) * (r + d1) + std::ldexp(LD(1), -18) * (d + d1) + std::ldexp(LD(1), -22) * r +
              std::sqrt(19 * std::ldexp(LD(1), -149));
      break;
    case Metric::kLeaf: {
      double qa[3], pa[3], pb2[3], pc[3], qe[3];
      for (int k = 0; k < 3; ++k) qa[k] = double(q0.x[k]), qe[k] = double(q1.x[k]), pa[k] = double(a.x[k]), pb2[k] = double(b.x[k]), pc[k] = double(c.x[k]);
      LD S;
      if (vt) {
        d = ref::point_triangle_distance(qa, pa, pb2, pc);
        S = std::max({dist(q0, a), dist(q0, b), dist(q0, c)});
      } else {
        d = ref::segment_segment_distance(qa, qe, pa, pb2);
        S = std::max({dist(q0, q1), dist(q0, a), dist(q0, b), dist(a, b)});
      }
      slack = std::ldexp(LD(1), -19) * S;
      break;
    }
  }
  const LD e = d - r;
  if (e <= 0) return;
  ex.worst_abs = std::max(ex.worst_abs, e);
  const LD ratio = slack > 0 ? e / slack : INFINITY;
  ex.worst_ratio = std::max(ex.worst_ratio, ratio);
  if (ratio > 1) ++ex.over;
}

NonFinite non_finite(const ref::Mesh& m, float r, const PairSet& vt_box, const PairSet& ee_box) {
  NonFinite nf;
  if (!std::isfinite(minkq::square_upper_bound(r))) ++nf.r2;
  for (size_t e = 0; e < m.edge_count(); ++e) {
    const minkq::Vec3 p0 = vf(m, m.edges[2 * e]), p1 = vf(m, m.edges[2 * e + 1]);
    if (!std::isfinite(minkq::capsule_exact_threshold2(p0, p1, r))) ++nf.threshold;
  }
  // box_gap_within's six differences (query box to primitive box).
  auto gaps_finite = [](minkq::Vec3 lo, minkq::Vec3 hi, const minkq::Box& b) {
    return finite_box({b.lo - hi, lo - b.hi});
  };
  for (uint64_t pr : vt_box) {
    const auto [v, t] = minkq::unpack_pair(pr);
    const minkq::Box b = minkq::box_expand(minkq::box_expand(minkq::Box::of_point(vf(m, m.tris[3 * size_t(t)])), vf(m, m.tris[3 * size_t(t) + 1])),
                                           vf(m, m.tris[3 * size_t(t) + 2]));
    if (!std::isfinite(minkq::point_box_distance2(vf(m, v), b))) ++nf.point_box;
    if (!gaps_finite(vf(m, v), vf(m, v), b)) ++nf.box_gap;
  }
  for (uint64_t pr : ee_box) {
    const auto [e, f] = minkq::unpack_pair(pr);
    const minkq::Vec3 p0 = vf(m, m.edges[2 * size_t(e)]), p1 = vf(m, m.edges[2 * size_t(e) + 1]);
    const minkq::Box b = minkq::box_expand(minkq::Box::of_point(vf(m, m.edges[2 * size_t(f)])), vf(m, m.edges[2 * size_t(f) + 1]));
    if (!gaps_finite(minkq::vmin(p0, p1), minkq::vmax(p0, p1), b)) ++nf.box_gap;
    const minkq::Vec3 d = p1 - p0, rl = b.lo - p0, rh = b.hi - p0;
    // segment_box_distance2 maps a NaN g to 0 ("may overlap"); count where that happens.
    if (!std::isfinite(minkq::segment_box_g(0.0f, d, rl, rh)) || !std::isfinite(minkq::segment_box_g(1.0f, d, rl, rh)) ||
        !std::isfinite(minkq::segment_box_slope(1.0f, d, rl, rh)))
      ++nf.segment_box;
    for (int axis = 0; axis < 3; ++axis) {
      const float dk = minkq::component(d, axis);
      if (dk == 0.0f) continue;
      const float lo = minkq::next_down(minkq::component(b.lo, axis) - r), hi = minkq::next_up(minkq::component(b.hi, axis) + r);
      const float o = minkq::component(p0, axis);
      if (!std::isfinite((lo - o) / dk) || !std::isfinite((hi - o) / dk)) { ++nf.ray_t; break; }
    }
  }
  return nf;
}

}  // namespace minkq::test::stability
