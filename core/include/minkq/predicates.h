// Geometric predicates for "may lie within r": node tests in float32 and primitive distances
// (float32 inputs, evaluated in double). Every test here is conservative: it may accept a pair
// slightly farther than r (by the bound stated beside it), never reject one within r. The
// bounds are relative to the operands' own size; there is no absolute epsilon anywhere.
// tests/test_predicates.cpp checks each stated bound in both directions against a long-double
// oracle. The "accepts only within ..." (tightness) bounds hold while the squares stay finite
// and normal (distances and r between about 1e-19 and 1e19); beyond, a squared distance
// overflows or underflows and the tests accept more (never less): tests/test_stability.cpp.
#pragma once

#include "minkq/hd.h"

namespace minkq {

// The relative widening of the capsule slab test's t-interval (2^-20): covers the 3u error of
// (bound - o) / d with d itself rounded.
constexpr float kSlabWidening = 9.5367431640625e-07f;
// The leaf tests' slack relative to the operands' size S (2^-20): they accept distances up to
// r + kLeafSlack * S (see leaf_within).
constexpr double kLeafSlack = 0x1p-20;

// ---- Node tests (float32) -------------------------------------------------------------------

// Squared distance from p to box b (0 inside). Computed value d2f satisfies
// d2f <= d2 * (1 + 6u) + 3 * 2^-150 (u = 2^-24): three exact-input subtractions, squares and
// two additions of non-negative terms, each one rounding.
MINKQ_HD float point_box_distance2(Vec3 p, const Box& b) {
  const float dx = max_num(max_num(b.lo.x - p.x, p.x - b.hi.x), 0.0f);
  const float dy = max_num(max_num(b.lo.y - p.y, p.y - b.hi.y), 0.0f);
  const float dz = max_num(max_num(b.lo.z - p.z, p.z - b.hi.z), 0.0f);
  return dx * dx + dy * dy + dz * dz;
}

// Sphere node test. r2_upper = square_upper_bound(r). Accepts every box within r of p;
// accepts only boxes within r * (1 + 2^-17).
MINKQ_HD bool sphere_overlaps_box(Vec3 p, float r2_upper, const Box& b) {
  return point_box_distance2(p, b) <= r2_upper;
}

// The box test: per axis, the gap from box [lo, hi] to box b, computed in float, is at most r.
// A rounded difference of floats is never pushed past r when the exact one is within it
// (rounding is monotone and r is a float), so every box within r in every axis is accepted;
// an accepted gap is at most r + half an ulp of r. The expressions are symmetric in the two
// boxes (the same two differences either way round), grow no larger when b grows (an ancestor
// box accepts whenever a box inside it does), and need no padding or outward rounding.
// Coordinates are finite: a difference overflows only to -inf (accept) or +inf (reject),
// both exact verdicts.
MINKQ_HD bool box_gap_within(Vec3 lo, Vec3 hi, float r, const Box& b) {
  return b.lo.x - hi.x <= r && lo.x - b.hi.x <= r && b.lo.y - hi.y <= r && lo.y - b.hi.y <= r &&
         b.lo.z - hi.z <= r && lo.z - b.hi.z <= r;
}

// Box of a capsule (segment p0-p1 grown by r), rounded outward so it contains the exact one.
MINKQ_HD Box padded_segment_box(Vec3 p0, Vec3 p1, float r) {
  const Vec3 lo = vmin(p0, p1), hi = vmax(p0, p1);
  if (r == 0.0f) return {lo, hi};  // exact: nothing to round
  return {{next_down(lo.x - r), next_down(lo.y - r), next_down(lo.z - r)},
          {next_up(hi.x + r), next_up(hi.y + r), next_up(hi.z + r)}};
}

// A box containing every box b that box_gap_within(lo, hi, r, b) accepts (for prefilters that
// take a box, such as Embree's): an accepted gap is below next_up(r), and padding by that with
// outward rounding covers it.
MINKQ_HD Box box_gap_bound(Vec3 lo, Vec3 hi, float r) { return padded_segment_box(lo, hi, next_up(r)); }

// The slab test of a ray p0 + t*d, t in [0, t_end], against the box b inflated by r: each
// axis's t-interval, with the rounding and widening stated below, intersected.
MINKQ_HD bool segment_slabs_overlap(Vec3 p0, Vec3 d, float t_end, float r, const Box& b) {
  float t_near = 0.0f, t_far = t_end;
  for (int axis = 0; axis < 3; ++axis) {
    const float lo = next_down(component(b.lo, axis) - r);
    const float hi = next_up(component(b.hi, axis) + r);
    const float o = component(p0, axis), dk = component(d, axis);
    if (dk == 0.0f) {  // d is exactly 0 only when both end coordinates are equal
      if (o < lo || o > hi) return false;
      continue;
    }
    float t0 = (lo - o) / dk, t1 = (hi - o) / dk;
    if (t0 > t1) { const float t = t0; t0 = t1; t1 = t; }
    t0 = t0 - fabsf(t0) * kSlabWidening - FLT_MIN;
    t1 = t1 + fabsf(t1) * kSlabWidening + FLT_MIN;
    t_near = max_num(t_near, t0);
    t_far = min_num(t_far, t1);
  }
  return t_near <= t_far;
}

// The prototype's capsule node test: the segment p0 + t*d, t in [0, 1] (d = p1 - p0), against
// the box inflated by r in every axis (a superset of the capsule's Minkowski region).
// The inflated box is rounded outward; each slab's t-interval is widened by 2^-20 relative
// (covering the 3u error of (bound - o) / d with d itself rounded) plus FLT_MIN absolute
// (t is dimensionless, so this is not a length tolerance). Accepts every box within r of the
// segment; accepts only boxes whose r-inflation the segment reaches within t in
// [-2^-19, 1 + 2^-19].
MINKQ_HD bool capsule_ray_overlaps_box(Vec3 p0, Vec3 d, float r, const Box& b) {
  return segment_slabs_overlap(p0, d, 1.0f, r, b);
}

// Signed excess of coordinate x beyond [lo, hi]: negative below, positive above, 0 inside.
MINKQ_HD float excess(float x, float lo, float hi) {
  return x < lo ? x - lo : (x > hi ? x - hi : 0.0f);
}

// g(s) = squared distance from p0 + s*d to the box, with lo/hi given relative to p0.
MINKQ_HD float segment_box_g(float s, Vec3 d, Vec3 rel_lo, Vec3 rel_hi) {
  const float ex = excess(s * d.x, rel_lo.x, rel_hi.x);
  const float ey = excess(s * d.y, rel_lo.y, rel_hi.y);
  const float ez = excess(s * d.z, rel_lo.z, rel_hi.z);
  return ex * ex + ey * ey + ez * ez;
}
// g'(s) / 2, the sign of which brackets the minimiser (g is convex).
MINKQ_HD float segment_box_slope(float s, Vec3 d, Vec3 rel_lo, Vec3 rel_hi) {
  return excess(s * d.x, rel_lo.x, rel_hi.x) * d.x + excess(s * d.y, rel_lo.y, rel_hi.y) * d.y +
         excess(s * d.z, rel_lo.z, rel_hi.z) * d.z;
}

// Squared distance between segment p0-p1 and box b (the exact capsule node test).
// g is convex and piecewise quadratic with breakpoints where a coordinate crosses a face; the
// slope's sign at the breakpoints brackets one quadratic piece, whose minimiser is closed-form.
// The value returned is g evaluated at an actual parameter, within 2^-18 * (D + |d|_1) of the
// true distance D (each excess is off by at most a few u of (D + |d_k|)). Where a component
// of d, b.lo - p0 or b.hi - p0 reaches 2^62, the slopes, squares and the minimiser's sums can
// overflow (inf / inf would pick a wrong piece): that returns 0, unknown meaning "may overlap".
// Below 2^62 no product, square or sum here can reach FLT_MAX.
MINKQ_HD float segment_box_distance2(Vec3 p0, Vec3 p1, const Box& b) {
  const Vec3 d = p1 - p0;
  const Vec3 rl = b.lo - p0, rh = b.hi - p0;
  const float limit = 4611686018427387904.0f;  // 2^62
  if (!(fabsf(d.x) < limit && fabsf(d.y) < limit && fabsf(d.z) < limit && fabsf(rl.x) < limit &&
        fabsf(rl.y) < limit && fabsf(rl.z) < limit && fabsf(rh.x) < limit && fabsf(rh.y) < limit &&
        fabsf(rh.z) < limit))
    return 0.0f;
  if (segment_box_slope(0.0f, d, rl, rh) > 0.0f) return segment_box_g(0.0f, d, rl, rh);
  if (segment_box_slope(1.0f, d, rl, rh) <= 0.0f) {
    const float g1 = segment_box_g(1.0f, d, rl, rh);
    return g1 == g1 ? g1 : 0.0f;
  }
  float s_lo = 0.0f, s_hi = 1.0f;  // slope(s_lo) <= 0 < slope(s_hi)
  for (int axis = 0; axis < 3; ++axis) {
    const float dk = component(d, axis);
    if (dk == 0.0f) continue;
    const float candidates[2] = {component(rl, axis) / dk, component(rh, axis) / dk};
    for (float c : candidates) {
      if (!(c > s_lo && c < s_hi)) continue;
      if (segment_box_slope(c, d, rl, rh) <= 0.0f) s_lo = c; else s_hi = c;
    }
  }
  // No breakpoint lies inside (s_lo, s_hi): one quadratic piece, active axes read at its middle.
  const float mid = 0.5f * (s_lo + s_hi);
  float num = 0.0f, den = 0.0f;
  for (int axis = 0; axis < 3; ++axis) {
    const float dk = component(d, axis);
    const float x = mid * dk, lo = component(rl, axis), hi = component(rh, axis);
    const float face = x < lo ? lo : (x > hi ? hi : 0.0f);
    if (x < lo || x > hi) { num += face * dk; den += dk * dk; }
  }
  float s = den > 0.0f ? num / den : mid;
  s = min_num(max_num(s, s_lo), s_hi);
  const float g = segment_box_g(s, d, rl, rh);
  return g == g ? g : 0.0f;
}

// Threshold for segment_box_distance2 so that no box within r is rejected: the square of
// r + 2^-17 * (r + |d|_1), rounded up.
MINKQ_HD float capsule_exact_threshold2(Vec3 p0, Vec3 p1, float r) {
  const Vec3 d = p1 - p0;
  const float length1 = fabsf(d.x) + fabsf(d.y) + fabsf(d.z);
  return square_upper_bound(next_up(r + 7.62939453125e-06f * next_up(r + length1)));  // 2^-17
}

// ---- Primitive distances (float32 inputs, double arithmetic) ------------------------------
// Double keeps the error of the sliver-triangle plane term far below the float-scale slack, so
// one bound holds without special cases: with S the operands' size (largest distance between
// the query's first point and the primitive's points, or edge length), the computed distance
// is within 2^-21 * S of the true one. Leaf tests accept distances <= r + 2^-20 * S, so they
// accept every pair within r, and only pairs within r + 2^-19 * S.

struct Vec3d {
  double x, y, z;
};
MINKQ_HD Vec3d to_double(Vec3 v) { return {double(v.x), double(v.y), double(v.z)}; }
MINKQ_HD Vec3d operator-(Vec3d a, Vec3d b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
MINKQ_HD Vec3d operator+(Vec3d a, Vec3d b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
MINKQ_HD Vec3d operator*(double s, Vec3d a) { return {s * a.x, s * a.y, s * a.z}; }
MINKQ_HD double dot(Vec3d a, Vec3d b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
MINKQ_HD Vec3d cross(Vec3d a, Vec3d b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
MINKQ_HD double clamp01(double t) { return t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t); }

// Squared distance from p to segment a + t*(b - a), t in [0, 1]; zero-length segments are points.
MINKQ_HD double point_segment_distance2(Vec3d p, Vec3d a, Vec3d b) {
  const Vec3d d = b - a, v = p - a;
  const double dd = dot(d, d);
  const double t = dd > 0.0 ? clamp01(dot(v, d) / dd) : 0.0;
  const Vec3d e = v - t * d;
  return dot(e, e);
}

// Squared distance between segments p0-p1 and q0-q1. The minimum lies at an endpoint of one
// segment (four point-segment distances) or at an interior pair; for the latter, points
// P(s) whose projection onto line Q falls inside Q are scanned by minimising the distance to
// line Q, |m + s*n| / |d2| (m = w x d2, n = d1 x d2): a one-dimensional least squares whose
// error stays O(u * S) even for near-parallel segments (unlike the 2x2 normal equations).
MINKQ_HD double segment_segment_distance2(Vec3d p0, Vec3d p1, Vec3d q0, Vec3d q1) {
  double best = point_segment_distance2(p0, q0, q1);
  best = min_num(best, point_segment_distance2(p1, q0, q1));
  best = min_num(best, point_segment_distance2(q0, p0, p1));
  best = min_num(best, point_segment_distance2(q1, p0, p1));
  const Vec3d d1 = p1 - p0, d2 = q1 - q0, w = p0 - q0;
  const double l2 = dot(d2, d2);
  if (!(l2 > 0.0) || !(dot(d1, d1) > 0.0)) return best;
  // s-range where t(s) = (w + s d1).d2 / l2 lies in [0, 1].
  const double a = dot(w, d2), b = dot(d1, d2);
  double s_lo = 0.0, s_hi = 1.0;
  if (b == 0.0) {
    if (a < 0.0 || a > l2) return best;
  } else {
    double s0 = -a / b, s1 = (l2 - a) / b;
    if (s0 > s1) { const double t = s0; s0 = s1; s1 = t; }
    s_lo = max_num(s_lo, s0);
    s_hi = min_num(s_hi, s1);
    if (s_lo > s_hi) return best;
  }
  const Vec3d n = cross(d1, d2), m = cross(w, d2);
  const double nn = dot(n, n);
  double s = nn > 0.0 ? -dot(m, n) / nn : s_lo;
  s = min_num(max_num(s, s_lo), s_hi);
  const Vec3d e = m + s * n;
  return min_num(best, dot(e, e) / l2);
}

// Squared distance from p to triangle abc, robust to zero-area and repeated-vertex triangles:
// the minimum of the three edge distances and, where p projects inside, the plane distance.
// The plane term is used only when the inradius |n| / perimeter exceeds 2^-22 * S; for
// thinner triangles the edges alone are within that inradius of the true distance. The
// inside test accepts projections up to 2^-24 * S outside (the plane distance never exceeds
// the true distance, so that widening only errs towards "may be within r").
MINKQ_HD double point_triangle_distance2(Vec3d p, Vec3d a, Vec3d b, Vec3d c, double scale) {
  double best = point_segment_distance2(p, a, b);
  best = min_num(best, point_segment_distance2(p, b, c));
  best = min_num(best, point_segment_distance2(p, c, a));
  const Vec3d ab = b - a, bc = c - b, ca = a - c;
  const Vec3d n = cross(ab, c - a);
  const double nn = dot(n, n);
  const double perimeter = sqrt(dot(ab, ab)) + sqrt(dot(bc, bc)) + sqrt(dot(ca, ca));
  const double norm_n = sqrt(nn);
  if (!(norm_n > 0x1p-22 * scale * perimeter)) return best;
  const double band = 0x1p-24 * scale * norm_n;  // |n| * (in-plane distance slack)
  const Vec3d pa = p - a, pb = p - b, pc = p - c;
  if (dot(n, cross(ab, pa)) < -band * sqrt(dot(ab, ab))) return best;
  if (dot(n, cross(bc, pb)) < -band * sqrt(dot(bc, bc))) return best;
  if (dot(n, cross(ca, pc)) < -band * sqrt(dot(ca, ca))) return best;
  const double h = dot(pa, n);
  return min_num(best, h * h / nn);
}

MINKQ_HD double max3(double a, double b, double c) { return max_num(a, max_num(b, c)); }

// Operand size S for the leaf tests: the largest distance from the query's first point to a
// point of the primitive, or between the query's own points.
MINKQ_HD double triangle_scale(Vec3d p, Vec3d a, Vec3d b, Vec3d c) {
  return sqrt(max3(dot(a - p, a - p), dot(b - p, b - p), dot(c - p, c - p)));
}
MINKQ_HD double segments_scale(Vec3d p0, Vec3d p1, Vec3d q0, Vec3d q1) {
  return sqrt(max_num(dot(p1 - p0, p1 - p0),
                      max3(dot(q0 - p0, q0 - p0), dot(q1 - p0, q1 - p0), dot(q1 - q0, q1 - q0))));
}

// Leaf acceptance: distance2 <= (r + 2^-20 * S)^2, the square taken with a relative margin of
// 2^-40 that covers double rounding of the threshold itself.
MINKQ_HD bool leaf_within(double distance2, float r, double scale) {
  const double limit = double(r) + kLeafSlack * scale;
  return distance2 <= limit * limit * (1.0 + 0x1p-40);
}

MINKQ_HD bool point_triangle_within(Vec3 p, Vec3 a, Vec3 b, Vec3 c, float r) {
  const Vec3d pd = to_double(p), ad = to_double(a), bd = to_double(b), cd = to_double(c);
  const double scale = triangle_scale(pd, ad, bd, cd);
  return leaf_within(point_triangle_distance2(pd, ad, bd, cd, scale), r, scale);
}
// The EE leaf test proper: the distance, evaluated in full (segment_segment_within below
// screens first).
MINKQ_HD bool segment_segment_distance_within(Vec3 p0, Vec3 p1, Vec3 q0, Vec3 q1, float r) {
  const Vec3d a = to_double(p0), b = to_double(p1), c = to_double(q0), d = to_double(q1);
  const double scale = segments_scale(a, b, c, d);
  return leaf_within(segment_segment_distance2(a, b, c, d), r, scale);
}

// The EV and VV leaf tests: a point against a segment or a point, with the EE test's operand
// size (a point is a zero-length segment).
MINKQ_HD bool point_segment_within(Vec3 p, Vec3 a, Vec3 b, float r) {
  const Vec3d pd = to_double(p), ad = to_double(a), bd = to_double(b);
  return leaf_within(point_segment_distance2(pd, ad, bd), r, segments_scale(pd, pd, ad, bd));
}
MINKQ_HD bool point_point_within(Vec3 p, Vec3 q, float r) { return point_segment_within(p, q, q, r); }

// ---- Separation screen for EE: a cheap proof that the leaf test rejects ------------------
// Two sets whose projections onto an axis lie a gap g apart are at least g apart. Along the
// axis v joining the two segments' centres (any axis serves, so the computed v is as good as
// the exact one) the gap costs three dot products, a root and a division, far less than the
// full distance, and on cloth it settles many of the box candidates that are not contacts
// (docs/design-notes.md links the contacts study, which also tried the same screen for VT and did
// not keep it). It answers "apart" only when the computed gap exceeds r + 2^-18 * T, T >= S a bound on the
// operands' size (S as above): the computed gap is off by at most about 2^-49 * T (a few
// roundings of terms no larger than T), so the true distance then exceeds r + 2^-19 * S,
// beyond every pair the full test accepts. The leaf set is therefore exactly the full test's,
// and no pair within r is ever screened out, whatever the full test's error
// (tests/test_predicates.cpp checks both).
MINKQ_HD double abs_sum(Vec3d v) { return fabs(v.x) + fabs(v.y) + fabs(v.z); }

// Segments p0-p1 and q0-q1 along v = 2 (centre of q - centre of p): each segment's projection
// spans |v.d| / |v| about its centre's, so twice the gap is |v| - (|v.d1| + |v.d2|) / |v|.
// T = |v| + |d1|_1 + |d2|_1 >= S: an endpoint distance is at most T / 2, a length at most T.
MINKQ_HD bool segments_apart(Vec3 p0, Vec3 p1, Vec3 q0, Vec3 q1, float r) {
  const Vec3d a = to_double(p0), b = to_double(p1), c = to_double(q0), d = to_double(q1);
  const Vec3d v = (c - a) + (d - b), d1 = b - a, d2 = d - c;
  const double vv = dot(v, v);
  if (!(vv > 0.0)) return false;  // the centres coincide: no axis
  const double length = sqrt(vv);
  const double twice_gap = length - (fabs(dot(v, d1)) + fabs(dot(v, d2))) / length;
  return twice_gap > 2.0 * (double(r) + 0x1p-18 * (length + abs_sum(d1) + abs_sum(d2)));
}

// The EE leaf test: the screen, then the distance (the same set as the distance alone).
MINKQ_HD bool segment_segment_within(Vec3 p0, Vec3 p1, Vec3 q0, Vec3 q1, float r) {
  return !segments_apart(p0, p1, q0, q1, r) && segment_segment_distance_within(p0, p1, q0, q1, r);
}

}  // namespace minkq
