// The oracle's side of the scene checks: the leaf-exact extras' bound (r + 2^-19 S, S the
// pair's size) against the long-double distances of oracle/, and long-double point-box
// and segment-box distances for user-box queries. Part of the scene checks (scene_checks.h
// includes every part).
#pragma once

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <utility>
#include <vector>

#include "minkq/query_sources.h"
#include "minkq_reference.h"
#include "scene_types.h"

namespace minkq::fuzz {

// ---- The oracle's side ----------------------------------------------------------------------

inline void point_of(const std::vector<float>& xyz, int32_t v, double out[3]) {
  for (int k = 0; k < 3; ++k) out[k] = xyz[3 * size_t(v) + k];
}

// Largest distance between the points of a pair (the S of the leaf-exact bound, as in tests/).
inline LD pair_scale(const double (*points)[3], int n) {
  LD s = 0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const LD dx = LD(points[i][0]) - points[j][0], dy = LD(points[i][1]) - points[j][1],
               dz = LD(points[i][2]) - points[j][2];
      s = std::max(s, std::sqrt(dx * dx + dy * dy + dz * dz));
    }
  return s;
}

// Leaf-exact pairs beyond the true contacts must lie within r + 2^-19 * S: whether the extra
// (a, b), at oracle distance d between its points p, does; a failure is reported.
inline bool extra_within_bound(Report& report, int32_t a, int32_t b, LD d, const double (*p)[3], float r,
                               const std::string& what) {
  const LD bound = LD(r) + std::ldexp(pair_scale(p, 4), -19);
  if (d <= bound) return true;
  char text[160];
  std::snprintf(text, sizeof text, ": leaf-exact extra (%d,%d) at distance %.9Lg beyond r + 2^-19 S = %.9Lg", a, b, d,
                bound);
  report.fail(what + text);
  return false;
}

inline void check_vt_extras(Report& report, const Pairs& extras, const std::vector<float>& xyz,
                            const std::vector<int32_t>& tris, float r, const std::string& what) {
  for (const auto& [v, t] : extras) {
    double p[4][3];
    point_of(xyz, v, p[0]);
    for (int k = 0; k < 3; ++k) point_of(xyz, tris[3 * size_t(t) + k], p[k + 1]);
    if (!extra_within_bound(report, v, t, reference::point_triangle_distance(p[0], p[1], p[2], p[3]), p, r, what)) return;
  }
}

inline void check_ee_extras(Report& report, const Pairs& extras, const std::vector<float>& xyz,
                            const std::vector<int32_t>& edges, float r, const std::string& what) {
  for (const auto& [e, f] : extras) {
    double p[4][3];
    point_of(xyz, edges[2 * size_t(e)], p[0]);
    point_of(xyz, edges[2 * size_t(e) + 1], p[1]);
    point_of(xyz, edges[2 * size_t(f)], p[2]);
    point_of(xyz, edges[2 * size_t(f) + 1], p[3]);
    if (!extra_within_bound(report, e, f, reference::segment_segment_distance(p[0], p[1], p[2], p[3]), p, r, what))
      return;
  }
}

// ---- Float64 input ---------------------------------------------------------------------------

// The radius a float64 scene queries with must cover r + 2 rho, rho the exact farthest rounding
// distance (long double, from the doubles and their rounding), and stay close to it:
// widen_radius rounds up twice and rounding_distance once (relative 2^-21 in all), plus a
// float step where rho or r is subnormal (and infinity where r + 2 rho passes FLT_MAX).
inline void check_widened_radius(Report& report, float r, float radius, const Positions& p, const std::string& what) {
  LD rho = 0;
  for (size_t i = 0; p.float64() && i < p.count(); ++i) {
    LD d2 = 0;
    for (int k = 0; k < 3; ++k) {
      const LD d = LD(p.xyz64[3 * i + k]) - LD(p.xyz[3 * i + k]);
      d2 += d * d;
    }
    rho = std::max(rho, std::sqrt(d2));
  }
  const LD want = LD(r) + 2 * rho;
  LD most = want * (1 + std::ldexp(LD(1), -20)) + std::ldexp(LD(1), -140);
  if (most > LD(FLT_MAX)) most = INFINITY;  // rounded up past the float range: infinity
  if (!(LD(radius) >= want) || !(LD(radius) <= most)) {
    char text[200];
    std::snprintf(text, sizeof text, ": the widened radius %.9g is not r + 2 rho = %.12Lg (r %.9g, rho %.9Lg)",
                  double(radius), want, double(r), rho);
    report.fail(what + text);
  }
}

// ---- Swept steps: the static oracle at sampled times -------------------------------------------

// A coordinate at time t of a step from a to b, a + t (b - a) in double, and whether that is
// its exact value (error-free transforms: TwoSum for the difference and the sum, an FMA for the
// product's residual).
inline double lerp_coordinate(double a, double b, double t, bool& exact) {
  auto two_sum_error = [](double x, double y, double s) {
    const double y1 = s - x, x1 = s - y1;
    return (x - x1) + (y - y1);
  };
  const double d = b - a;
  const double p = t * d;
  const double s = a + p;
  exact = exact && two_sum_error(b, -a, d) == 0 && std::fma(t, d, -p) == 0 && two_sum_error(a, p, s) == 0;
  return s;
}

// The oracle's contacts of a swept step sampled at the times t = k / samples (k = 0..samples),
// united: each is a pair whose elements come within r during the step (in double: the float64
// input's motion, or the float input's exact values), so every swept mode must report it. Where
// the positions at a time are not exact in double, the contacts there are taken at r less the
// bound of that rounding (none when it is below 0): a sampled contact is one of the exact motion,
// never an artefact of rounding the positions between.
struct SampledContacts {
  Pairs vt, ee;
  int rounded_times = 0;  // times whose positions were rounded (their radius shrunk)
};
inline SampledContacts sampled_contacts(const Positions& x0, const Positions& x1, const std::vector<int32_t>& tris,
                                        const std::vector<int32_t>& edges, float r, bool drop_incident, int samples) {
  const size_t n = 3 * x0.count();
  auto at = [](const Positions& p, size_t i) { return p.float64() ? p.xyz64[i] : double(p.xyz[i]); };
  double magnitude = 0;  // max |a| + |b| over every coordinate
  for (size_t i = 0; i < n; ++i) magnitude = std::max(magnitude, std::fabs(at(x0, i)) + std::fabs(at(x1, i)));
  SampledContacts out;
  for (int k = 0; k <= samples; ++k) {
    const double t = double(k) / samples;
    std::vector<double> xyz(n);
    bool exact = true;
    for (size_t i = 0; i < n; ++i) xyz[i] = lerp_coordinate(at(x0, i), at(x1, i), t, exact);
    // Each coordinate is off by at most 3 * 2^-53 * (|a| + |b|); a pair's distance by twice the
    // Euclidean norm of that: below 2^-48 * magnitude.
    double radius = r;
    if (!exact) {
      out.rounded_times++;
      radius = std::nextafter(double(r) - std::ldexp(magnitude, -48), 0.0);
      if (!(radius >= 0)) continue;
    }
    reference::Mesh mesh;
    reference::set_float64(mesh, std::move(xyz));
    mesh.tris = tris;
    mesh.edges = edges;
    for (auto [all, found] : {std::pair{&out.vt, reference::vt_contacts(mesh, radius, drop_incident)},
                              std::pair{&out.ee, reference::ee_contacts(mesh, radius, drop_incident)}}) {
      Pairs merged;
      std::set_union(all->begin(), all->end(), found.begin(), found.end(), std::back_inserter(merged));
      *all = std::move(merged);
    }
  }
  return out;
}

// Point-box and segment-box distances in long double, for user-box queries. The segment case
// minimises the convex piecewise quadratic exactly: between consecutive face crossings the set
// of axes outside the box is fixed and the minimiser is closed-form.
inline LD excess_ld(LD x, LD lo, LD hi) { return x < lo ? lo - x : (x > hi ? x - hi : 0); }
inline LD point_box_distance_ld(const float* p, const Box& b) {
  const float lo[3] = {b.lo.x, b.lo.y, b.lo.z}, hi[3] = {b.hi.x, b.hi.y, b.hi.z};
  LD d2 = 0;
  for (int k = 0; k < 3; ++k) {
    const LD e = excess_ld(p[k], lo[k], hi[k]);
    d2 += e * e;
  }
  return std::sqrt(d2);
}
inline LD segment_box_distance_ld(const float* a, const float* b, const Box& box) {
  const float lo[3] = {box.lo.x, box.lo.y, box.lo.z}, hi[3] = {box.hi.x, box.hi.y, box.hi.z};
  LD d[3], o[3];
  for (int k = 0; k < 3; ++k) o[k] = a[k], d[k] = LD(b[k]) - LD(a[k]);
  auto dist2 = [&](LD t) {
    LD s = 0;
    for (int k = 0; k < 3; ++k) {
      const LD e = excess_ld(o[k] + t * d[k], lo[k], hi[k]);
      s += e * e;
    }
    return s;
  };
  std::vector<LD> ts = {0, 1};
  for (int k = 0; k < 3; ++k)
    if (d[k] != 0)
      for (LD face : {LD(lo[k]), LD(hi[k])}) {
        const LD t = (face - o[k]) / d[k];
        if (t > 0 && t < 1) ts.push_back(t);
      }
  std::sort(ts.begin(), ts.end());
  LD best = std::min(dist2(0), dist2(1));
  for (size_t i = 0; i + 1 < ts.size(); ++i) {
    const LD t0 = ts[i], t1 = ts[i + 1], mid = (t0 + t1) / 2;
    LD num = 0, den = 0;
    for (int k = 0; k < 3; ++k) {
      const LD x = o[k] + mid * d[k];
      if (x < lo[k] || x > hi[k]) {
        const LD face = x < lo[k] ? lo[k] : hi[k];
        num -= (o[k] - face) * d[k];
        den += d[k] * d[k];
      }
    }
    const LD t = den > 0 ? std::min(std::max(num / den, t0), t1) : t0;
    best = std::min({best, dist2(t), dist2(t0), dist2(t1)});
  }
  return std::sqrt(best);
}

}  // namespace minkq::fuzz
