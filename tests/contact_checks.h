// Distances of reported pairs by the reference oracle, with the operand size S of
// predicates.h, for checking that leaf-exact extras lie within r + 2^-19 * S; the pair files
// the CLI writes.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>
#include <vector>

#include "minkq_reference.h"

namespace minkq::test {

using reference::Mesh;

// Largest distance between the points of a pair (the operand size S of predicates.h).
inline double pair_scale(const std::vector<const float*>& points) {
  double s = 0;
  for (const float* a : points)
    for (const float* b : points) {
      const double dx = double(a[0]) - b[0], dy = double(a[1]) - b[1], dz = double(a[2]) - b[2];
      s = std::max(s, std::sqrt(dx * dx + dy * dy + dz * dz));
    }
  return s;
}

inline const float* vertex(const Mesh& mesh, int32_t v) { return &mesh.xyz[3 * size_t(v)]; }

inline long double vt_distance(const Mesh& mesh, int32_t v, int32_t t, double* scale) {
  double p[3], a[3], b[3], c[3];
  const float* pts[4] = {vertex(mesh, v), vertex(mesh, mesh.tris[3 * t]), vertex(mesh, mesh.tris[3 * t + 1]),
                         vertex(mesh, mesh.tris[3 * t + 2])};
  for (int k = 0; k < 3; ++k) { p[k] = pts[0][k]; a[k] = pts[1][k]; b[k] = pts[2][k]; c[k] = pts[3][k]; }
  *scale = pair_scale({pts[0], pts[1], pts[2], pts[3]});
  return reference::point_triangle_distance(p, a, b, c);
}

inline long double ee_distance(const Mesh& mesh, const std::vector<int32_t>& edges, int32_t e, int32_t f, double* scale) {
  const float* pts[4] = {vertex(mesh, edges[2 * e]), vertex(mesh, edges[2 * e + 1]), vertex(mesh, edges[2 * f]),
                         vertex(mesh, edges[2 * f + 1])};
  double d[4][3];
  for (int i = 0; i < 4; ++i)
    for (int k = 0; k < 3; ++k) d[i][k] = pts[i][k];
  *scale = pair_scale({pts[0], pts[1], pts[2], pts[3]});
  return reference::segment_segment_distance(d[0], d[1], d[2], d[3]);
}

// The pairs `minkq query --out` wrote to a file: little-endian int32 (a, b) pairs.
inline reference::Pairs read_pairs(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw std::runtime_error("cannot read " + path);
  std::vector<char> bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  if (bytes.size() % 8) throw std::runtime_error(path + ": size is not a multiple of 8 bytes");
  reference::Pairs pairs(bytes.size() / 8);
  for (size_t i = 0; i < pairs.size(); ++i) {
    int32_t ab[2];
    std::memcpy(ab, bytes.data() + 8 * i, 8);  // little-endian int32, as the host
    pairs[i] = {ab[0], ab[1]};
  }
  return pairs;
}

// Compares the pairs a run reported (`kind` names it in the messages) with the true ones:
// every true pair must be reported, in canonical order, and with `leaf_exact` every other pair
// must lie within its reach plus the leaf test's slack: distance(a, b, &S) <= reach(a, b) +
// 2^-19 * S. Prints a summary line and the first failures; returns the number of failures.
template <class Distance, class Reach>
int compare_pairs(const std::string& kind, const reference::Pairs& reported, const reference::Pairs& truth,
                  bool leaf_exact, Distance distance, Reach reach) {
  reference::Pairs missing, extra;
  std::set_difference(truth.begin(), truth.end(), reported.begin(), reported.end(), std::back_inserter(missing));
  std::set_difference(reported.begin(), reported.end(), truth.begin(), truth.end(), std::back_inserter(extra));
  int failures = 0;
  for (const auto& [a, b] : missing)
    if (++failures <= 5) std::printf("%s MISSING true contact (%d, %d)\n", kind.c_str(), a, b);
  double worst = 0;
  for (const auto& [a, b] : extra) {
    if (!leaf_exact) break;
    double s;
    const long double d = distance(a, b, &s), within = reach(a, b);
    worst = std::max(worst, double((d - within) / s));
    if (d > within + std::ldexp(s, -19) && ++failures <= 10)
      std::printf("%s extra pair (%d, %d) at distance %.17Lg beyond its reach %.17Lg + 2^-19 S\n", kind.c_str(), a, b,
                  d, within);
  }
  std::printf("%s: %zu reported, %zu true, %zu missing, %zu extra", kind.c_str(), reported.size(), truth.size(),
              missing.size(), extra.size());
  if (leaf_exact) std::printf(" (worst excess %.3g S)", worst);
  std::printf("\n");
  if (!std::is_sorted(reported.begin(), reported.end())) {
    std::printf("%s pairs are not in canonical order\n", kind.c_str());
    ++failures;
  }
  return failures;
}

}  // namespace minkq::test
