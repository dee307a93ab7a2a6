// Every predicate against a long-double oracle on fresh random inputs, in both directions:
// no rejection within r (the contract) and no acceptance beyond the bound the code states.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <type_traits>

#include "minkq/predicates.h"
#include "minkq_reference.h"
#include "test_util.h"

namespace minkq {
namespace {

using LD = long double;

template <class T>
auto bits_of(T v) {
  using U = std::conditional_t<sizeof(T) == 4, uint32_t, uint64_t>;
  U u;
  std::memcpy(&u, &v, sizeof u);
  return u;
}

// min_num / max_num (hd.h) are fmin / fmax with the second operand on ties: a NaN operand
// yields the other one, equal operands (+0 and -0 among them) yield b. Bit for bit, over every
// pair of special values, in float and double (the boxes, trees and predicates rely on it, and
// the host's branch-free selects must keep it).
template <class T>
void expect_min_max_num_semantics() {
  const T inf = std::numeric_limits<T>::infinity(), nan = std::numeric_limits<T>::quiet_NaN();
  const T values[] = {T(0),  -T(0), std::numeric_limits<T>::denorm_min(), std::numeric_limits<T>::min(), T(1),
                      T(-1), T(2.5), std::numeric_limits<T>::max(), -std::numeric_limits<T>::max(), inf, -inf, nan,
                      -nan};
  for (T a : values)
    for (T b : values) {
      const T lo = std::isnan(b) || (!std::isnan(a) && a < b) ? a : b;
      const T hi = std::isnan(b) || (!std::isnan(a) && a > b) ? a : b;
      EXPECT_EQ(bits_of(min_num(a, b)), bits_of(lo)) << "min_num(" << a << ", " << b << ")";
      EXPECT_EQ(bits_of(max_num(a, b)), bits_of(hi)) << "max_num(" << a << ", " << b << ")";
      if (!std::isnan(a) && !std::isnan(b) && a != b) {
        EXPECT_EQ(min_num(a, b), std::fmin(a, b));
        EXPECT_EQ(max_num(a, b), std::fmax(a, b));
      }
    }
}

TEST(PredicateEdgeCases, min_num_and_max_num_are_fmin_and_fmax_keeping_b_on_ties) {
  expect_min_max_num_semantics<float>();
  expect_min_max_num_semantics<double>();
}

LD exact_point_box_distance(Vec3 p, const Box& b) {
  LD d2 = 0;
  for (int k = 0; k < 3; ++k) {
    const LD x = component(p, k), lo = component(b.lo, k), hi = component(b.hi, k);
    const LD e = x < lo ? lo - x : (x > hi ? x - hi : 0);
    d2 += e * e;
  }
  return std::sqrt(d2);
}

LD point_at_distance(Vec3 p0, Vec3 p1, LD s, const Box& b) {
  LD d2 = 0;
  for (int k = 0; k < 3; ++k) {
    const LD x = LD(component(p0, k)) + s * (LD(component(p1, k)) - LD(component(p0, k)));
    const LD lo = component(b.lo, k), hi = component(b.hi, k);
    const LD e = x < lo ? lo - x : (x > hi ? x - hi : 0);
    d2 += e * e;
  }
  return std::sqrt(d2);
}

// Segment-box distance by golden-section search on the convex distance along the segment.
LD exact_segment_box_distance(Vec3 p0, Vec3 p1, const Box& b) {
  LD lo = 0, hi = 1;
  const LD phi = (std::sqrt(LD(5)) - 1) / 2;
  for (int it = 0; it < 200; ++it) {
    const LD a = hi - phi * (hi - lo), c = lo + phi * (hi - lo);
    if (point_at_distance(p0, p1, a, b) <= point_at_distance(p0, p1, c, b)) hi = c; else lo = a;
  }
  return std::min({point_at_distance(p0, p1, (lo + hi) / 2, b), point_at_distance(p0, p1, 0, b),
                   point_at_distance(p0, p1, 1, b)});
}

LD norm1(Vec3 a, Vec3 b) { return std::fabs(LD(a.x) - b.x) + std::fabs(LD(a.y) - b.y) + std::fabs(LD(a.z) - b.z); }

class Predicates : public ::testing::Test {
 protected:
  test::Random rng{test::fresh_seed()};
};

TEST_F(Predicates, sphere_test_accepts_every_box_within_r_and_none_beyond_stated_bound) {
  for (int i = 0; i < 200000; ++i) {
    const float scale = rng.log_uniform(1e-6f, 1e6f);
    const Vec3 offset = rng.vec3(-1e4f * scale, 1e4f * scale);
    const Box b = rng.box(offset, scale);
    const Vec3 p = offset + rng.vec3(-3 * scale, 3 * scale);
    const LD d = exact_point_box_distance(p, b);
    // r just above, at, or just below the exact distance (a few ulps either way).
    float r = float(d);
    for (int k = rng.integer(-3, 3); k != 0; k += (k > 0 ? -1 : 1)) r = k > 0 ? next_up(r) : next_down(r);
    if (r < 0) r = 0;
    const bool accepted = sphere_overlaps_box(p, square_upper_bound(r), b);
    if (d <= LD(r)) ASSERT_TRUE(accepted) << "rejected a box within r: d=" << double(d) << " r=" << r;
    if (accepted) ASSERT_LE(d, LD(r) * (1 + std::ldexp(LD(1), -17)) + 1e-44L);
  }
}

// Chebyshev gap between two boxes (0 when they overlap).
LD exact_box_gap(const Box& a, const Box& b) {
  LD gap = 0;
  for (int k = 0; k < 3; ++k)
    gap = std::max({gap, LD(component(b.lo, k)) - component(a.hi, k), LD(component(a.lo, k)) - component(b.hi, k)});
  return gap;
}

TEST_F(Predicates, box_test_accepts_every_box_within_r_and_none_beyond_half_an_ulp_of_r) {
  for (int i = 0; i < 200000; ++i) {
    const float scale = rng.log_uniform(1e-6f, 1e6f);
    const Vec3 offset = rng.vec3(-1e5f * scale, 1e5f * scale);
    const Box a = rng.box(offset, scale);
    const Box b = rng.box(offset + rng.vec3(-3 * scale, 3 * scale), scale);
    const LD gap = exact_box_gap(a, b);
    float r = float(gap);  // a few ulps either side of the exact gap
    for (int k = rng.integer(-3, 3); k != 0; k += (k > 0 ? -1 : 1)) r = k > 0 ? next_up(r) : next_down(r);
    if (r < 0) r = 0;
    const bool accepted = box_gap_within(a.lo, a.hi, r, b);
    ASSERT_EQ(accepted, box_gap_within(b.lo, b.hi, r, a)) << "not symmetric";
    if (gap <= LD(r)) ASSERT_TRUE(accepted) << "rejected a box within r: gap=" << double(gap) << " r=" << r;
    if (accepted) {
      ASSERT_LE(gap, LD(r) + (LD(next_up(r)) - LD(r)) / 2) << "r=" << r;
      ASSERT_TRUE(boxes_overlap(box_gap_bound(a.lo, a.hi, r), b)) << "the prefilter box misses an accepted box";
    }
    // Exact for touching and disjoint boxes at r = 0.
    if (r == 0.0f) ASSERT_EQ(accepted, boxes_overlap(a, b));
  }
}

TEST_F(Predicates, capsule_ray_accepts_every_box_within_r) {
  for (int i = 0; i < 100000; ++i) {
    const float scale = rng.log_uniform(1e-5f, 1e5f);
    const Vec3 offset = rng.vec3(-1e3f * scale, 1e3f * scale);
    const Box b = rng.box(offset, scale);
    Vec3 p0 = offset + rng.vec3(-3 * scale, 3 * scale), p1 = p0 + rng.vec3(-2 * scale, 2 * scale);
    if (rng.integer(0, 4) == 0) p1 = p0;                            // zero-length
    if (rng.integer(0, 4) == 0) p1.y = p0.y;                        // axis-parallel
    const LD d = exact_segment_box_distance(p0, p1, b);
    const float r = std::max(0.0f, rng.integer(0, 1) ? float(d) : next_up(float(d)));
    if (d <= LD(r)) ASSERT_TRUE(capsule_ray_overlaps_box(p0, p1 - p0, r, b)) << "d=" << double(d) << " r=" << r;
  }
}

TEST_F(Predicates, segment_box_distance_is_within_stated_bound) {
  for (int i = 0; i < 100000; ++i) {
    const float scale = rng.log_uniform(1e-5f, 1e5f);
    const Vec3 offset = rng.vec3(-1e4f * scale, 1e4f * scale);
    const Box b = rng.box(offset, scale);
    Vec3 p0 = offset + rng.vec3(-3 * scale, 3 * scale), p1 = p0 + rng.vec3(-4 * scale, 4 * scale);
    if (rng.integer(0, 5) == 0) p1 = p0;
    if (rng.integer(0, 5) == 0) p1.z = p0.z;
    const LD d = exact_segment_box_distance(p0, p1, b);
    const LD computed = std::sqrt(LD(segment_box_distance2(p0, p1, b)));
    ASSERT_LE(std::fabs(computed - d), std::ldexp(LD(1), -18) * (d + norm1(p0, p1)) + 1e-40L)
        << "d=" << double(d) << " computed=" << double(computed);
    // The node test with its threshold accepts every box within r (r at the exact distance).
    const float r = float(d);
    if (d <= LD(r)) ASSERT_LE(segment_box_distance2(p0, p1, b), capsule_exact_threshold2(p0, p1, r));
  }
}

TEST_F(Predicates, segment_box_distance_handles_segments_grazing_faces_and_edges) {
  // Segments parallel to a face at distance r, and crossing near a box edge.
  const Box b{{0, 0, 0}, {1, 1, 1}};
  for (int i = 0; i < 20000; ++i) {
    const float r = rng.log_uniform(1e-7f, 1.0f);
    const float t = rng.uniform(-0.5f, 1.5f);
    const Vec3 p0{t, 1 + r, -2}, p1{t, 1 + r, 3};
    const LD d = exact_segment_box_distance(p0, p1, b);
    if (d <= LD(r)) ASSERT_LE(segment_box_distance2(p0, p1, b), capsule_exact_threshold2(p0, p1, r));
    const Vec3 q0{1 + r * 0.7f, -1, 1 + r * 0.7f}, q1{1 + r * 0.7f, 2, 1 + r * 0.7f};
    const LD e = exact_segment_box_distance(q0, q1, b);
    if (e <= LD(r)) ASSERT_LE(segment_box_distance2(q0, q1, b), capsule_exact_threshold2(q0, q1, r));
  }
}

LD reference_point_triangle(Vec3 p, Vec3 a, Vec3 b, Vec3 c) {
  const double P[3] = {p.x, p.y, p.z}, A[3] = {a.x, a.y, a.z}, B[3] = {b.x, b.y, b.z}, C[3] = {c.x, c.y, c.z};
  return reference::point_triangle_distance(P, A, B, C);
}
LD reference_segment_segment(Vec3 p0, Vec3 p1, Vec3 q0, Vec3 q1) {
  const double A[3] = {p0.x, p0.y, p0.z}, B[3] = {p1.x, p1.y, p1.z}, C[3] = {q0.x, q0.y, q0.z},
               D[3] = {q1.x, q1.y, q1.z};
  return reference::segment_segment_distance(A, B, C, D);
}

// A random triangle, sometimes degenerate: collinear, repeated vertex, sliver or a point.
void random_triangle(test::Random& rng, Vec3 origin, float scale, Vec3& a, Vec3& b, Vec3& c) {
  a = origin + rng.vec3(-scale, scale);
  b = origin + rng.vec3(-scale, scale);
  c = origin + rng.vec3(-scale, scale);
  switch (rng.integer(0, 7)) {
    case 0: c = b; break;                                      // repeated vertex
    case 1: c = a + rng.uniform(-2.0f, 2.0f) * (b - a); break; // collinear
    case 2: b = a; c = a; break;                               // a point
    case 3: c = a + 0.5f * (b - a) + 1e-6f * rng.vec3(-scale, scale); break;  // sliver
    default: break;
  }
}

TEST_F(Predicates, point_triangle_distance_is_within_stated_bound) {
  for (int i = 0; i < 200000; ++i) {
    const float scale = rng.log_uniform(1e-5f, 1e5f);
    const Vec3 origin = rng.vec3(-1e4f * scale, 1e4f * scale);
    Vec3 a, b, c;
    random_triangle(rng, origin, scale, a, b, c);
    Vec3 p = origin + rng.vec3(-2 * scale, 2 * scale);
    if (rng.integer(0, 3) == 0) p = a + 0.3f * (b - a) + 0.3f * (c - a) + rng.uniform(-1e-3f, 1e-3f) * scale * Vec3{0, 0, 1};
    const LD truth = reference_point_triangle(p, a, b, c);
    const Vec3d pd = to_double(p), ad = to_double(a), bd = to_double(b), cd = to_double(c);
    const double S = triangle_scale(pd, ad, bd, cd);
    const LD computed = std::sqrt(LD(point_triangle_distance2(pd, ad, bd, cd, S)));
    ASSERT_LE(std::fabs(computed - truth), std::ldexp(LD(S), -21) + 1e-300L)
        << "truth=" << double(truth) << " computed=" << double(computed) << " S=" << S;
    const float r = float(truth);
    if (truth <= LD(r)) ASSERT_TRUE(point_triangle_within(p, a, b, c, r));
    if (point_triangle_within(p, a, b, c, r)) ASSERT_LE(truth, LD(r) + std::ldexp(LD(S), -19));
  }
}

TEST_F(Predicates, segment_segment_distance_is_within_stated_bound) {
  for (int i = 0; i < 200000; ++i) {
    const float scale = rng.log_uniform(1e-5f, 1e5f);
    const Vec3 origin = rng.vec3(-1e4f * scale, 1e4f * scale);
    Vec3 p0 = origin + rng.vec3(-scale, scale), p1 = origin + rng.vec3(-scale, scale);
    Vec3 q0 = origin + rng.vec3(-scale, scale), q1 = origin + rng.vec3(-scale, scale);
    switch (rng.integer(0, 7)) {
      case 0: q1 = q0 + rng.uniform(-2.0f, 2.0f) * (p1 - p0); break;                      // parallel
      case 1: q0 = p0 + rng.uniform(-1.0f, 2.0f) * (p1 - p0); q1 = q0 + 0.7f * (p1 - p0); break;  // collinear
      case 2: p1 = p0; break;                                                               // zero-length
      case 3: q1 = q0 + (p1 - p0) + 1e-5f * rng.vec3(-scale, scale); break;               // near-parallel
      case 4: p1 = p0; q1 = q0; break;
      default: break;
    }
    const LD truth = reference_segment_segment(p0, p1, q0, q1);
    const Vec3d a = to_double(p0), b = to_double(p1), c = to_double(q0), d = to_double(q1);
    const double S = segments_scale(a, b, c, d);
    const LD computed = std::sqrt(LD(segment_segment_distance2(a, b, c, d)));
    ASSERT_LE(std::fabs(computed - truth), std::ldexp(LD(S), -21) + 1e-300L)
        << "truth=" << double(truth) << " computed=" << double(computed) << " S=" << S;
    const float r = float(truth);
    if (truth <= LD(r)) ASSERT_TRUE(segment_segment_within(p0, p1, q0, q1, r));
    if (segment_segment_within(p0, p1, q0, q1, r)) ASSERT_LE(truth, LD(r) + std::ldexp(LD(S), -19));
  }
}

// The EE separation screen only settles pairs the full distance test rejects: every pair it
// calls apart lies beyond r + 2^-19 S (so no contact is lost, whatever the full test does),
// and the screened test returns exactly the full test's verdict. Radii are drawn just below
// the true distance too, where a screen with too thin a margin would fire wrongly.
TEST_F(Predicates, segment_screen_settles_only_pairs_the_distance_test_rejects) {
  int apart = 0;
  const int cases = 300000;
  for (int i = 0; i < cases; ++i) {
    const float scale = rng.log_uniform(1e-5f, 1e5f);
    const Vec3 origin = rng.vec3(-1e4f * scale, 1e4f * scale);
    Vec3 p0 = origin + rng.vec3(-scale, scale), p1 = origin + rng.vec3(-scale, scale);
    Vec3 q0 = origin + rng.vec3(-scale, scale), q1 = origin + rng.vec3(-scale, scale);
    const Vec3 shift = rng.vec3(-3 * scale, 3 * scale);
    switch (rng.integer(0, 7)) {
      case 0: q0 = p0 + shift; q1 = p1 + shift; break;                     // parallel, side by side
      case 1: q0 = p1 + rng.uniform(0.0f, 0.5f) * (p1 - p0); q1 = q0 + 0.7f * (p1 - p0); break;  // collinear, apart
      case 2: p1 = p0; break;                                               // a point
      case 3: p1 = p0; q1 = q0; break;                                      // two points
      case 4: q0 = p0 + 0.5f * (p1 - p0) + shift; q1 = q0; break;           // a point beside the middle
      default: break;
    }
    const LD truth = reference_segment_segment(p0, p1, q0, q1);
    const double S = segments_scale(to_double(p0), to_double(p1), to_double(q0), to_double(q1));
    float r = 0.0f;
    switch (rng.integer(0, 3)) {
      case 0: r = float(truth); break;
      case 1: r = float(truth * (1 - std::ldexp(LD(1), -rng.integer(8, 30)))); break;
      case 2: r = float(truth) * rng.uniform(0.0f, 1.0f); break;
      default: r = rng.uniform(0.0f, 2.0f) * scale; break;
    }
    const bool full = segment_segment_distance_within(p0, p1, q0, q1, r);
    if (segments_apart(p0, p1, q0, q1, r)) {
      ++apart;
      ASSERT_GT(truth, LD(r) + std::ldexp(LD(S), -19)) << "i=" << i << " r=" << r << " S=" << S;
      ASSERT_FALSE(full) << "i=" << i;
    }
    ASSERT_EQ(segment_segment_within(p0, p1, q0, q1, r), full) << "i=" << i;
  }
  EXPECT_GT(apart, cases / 10);  // the screen does settle pairs
  // Side by side at distance 5: apart at r = 4.99, never at r = 5 (the distance itself).
  const Vec3 a{0, 0, 0}, b{1, 0, 0}, c{0, 5, 0}, d{1, 5, 0};
  EXPECT_TRUE(segments_apart(a, b, c, d, 4.99f));
  EXPECT_FALSE(segments_apart(a, b, c, d, 5.0f));
  EXPECT_FALSE(segments_apart(a, b, a, b, 0.0f));  // coinciding centres: no axis
}

TEST(PredicateEdgeCases, outward_rounding_helpers_step_one_ulp) {
  EXPECT_LT(next_down(1.0f), 1.0f);
  EXPECT_GT(next_up(1.0f), 1.0f);
  EXPECT_LT(next_down(0.0f), 0.0f);
  EXPECT_GT(next_up(-0.0f), 0.0f);
  EXPECT_EQ(next_up(next_down(3.5f)), 3.5f);
  EXPECT_GT(square_upper_bound(1e-30f), 0.0f);  // r * r underflows to 0; the bound stays positive
  EXPECT_GT(square_upper_bound(1e-23f), 0.0f);
}

}  // namespace
}  // namespace minkq
