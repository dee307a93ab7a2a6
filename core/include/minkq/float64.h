// float64 input. A scene created from double-precision vertices keeps them rounded to nearest
// float, the precision of its trees and tests, and keeps rho: the farthest the rounding moved
// any vertex (a Euclidean distance, rounded up). Rounding moves every point of a triangle or an
// edge by at most rho (each is a convex combination of its vertices), so a pair within r in
// double is within r + 2 rho after rounding: every query of such a scene runs with that radius
// (widen_radius), and so reports every pair within r of the double input, in every mode. Float
// input has rho = 0 and keeps r exactly.
#pragma once

#include <cmath>

#include "minkq/hd.h"

namespace minkq {

// The float at or above d (d >= 0 finite; +inf past the float range).
MINKQ_HD float float_at_or_above(double d) {
  float f = float(d);  // to nearest
  if (double(f) < d) f = next_up(f);
  return f;
}

// A float64 vertex rounded to nearest, and how far that moved it: at least the exact distance
// (the differences are exact in double; the factor covers the rounding of the sum and the root).
MINKQ_HD Vec3 round_to_float(const double p[3]) { return {float(p[0]), float(p[1]), float(p[2])}; }
MINKQ_HD float rounding_distance(const double p[3], Vec3 rounded) {
  const double dx = p[0] - double(rounded.x), dy = p[1] - double(rounded.y), dz = p[2] - double(rounded.z);
  const double squared = dx * dx + dy * dy + dz * dz;
  return float_at_or_above(sqrt(squared) * (1.0 + 0x1p-40));
}

// The radius of a query on vertices rounded by at most rho: r + 2 rho, rounded up (one step
// more covers the rounding of the double sum); r itself when nothing moved.
MINKQ_HD float widen_radius(float r, float rho) {
  if (rho == 0.0f) return r;
  return next_up(float_at_or_above(double(r) + 2.0 * double(rho)));
}

// Where query sources find rho: nullptr for float input (then r is used as given).
MINKQ_HD float query_radius(float r, const float* rho) { return rho ? widen_radius(r, *rho) : r; }

}  // namespace minkq
