// Long double distances and the brute-force and grid-accelerated contact oracles.
#include "minkq_reference.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "reference_grid.h"

namespace minkq::reference {
namespace {

using LD = long double;
struct V {
  LD x, y, z;
};
V sub(const double a[3], const double b[3]) { return {LD(a[0]) - b[0], LD(a[1]) - b[1], LD(a[2]) - b[2]}; }
LD dot(const V& a, const V& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
V cross(const V& a, const V& b) { return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }

}  // namespace

// ---- Distances -----------------------------------------------------------------------------
// A distance function is convex over the feature's parameter domain, so its minimum is either
// the unconstrained (interior) minimum, when that lies strictly inside, or on the boundary.
// Evaluating the boundary features and, only when strictly inside, the interior formula gives
// the exact minimum without any tolerance, for degenerate features too. The work is done on
// squared distances (no square roots in the contact tests, which dominate the oracle's time).
namespace detail {

LD point_segment_sq(const double p[3], const double a[3], const double b[3]) {
  const V d = sub(b, a), w = sub(p, a);
  LD best = std::min(dot(w, w), dot(sub(p, b), sub(p, b)));
  const LD dd = dot(d, d), t = dd > 0 ? dot(w, d) / dd : 0;
  if (t > 0 && t < 1) {  // line distance |w x d| / |d|
    const V c = cross(w, d);
    best = std::min(best, dot(c, c) / dd);
  }
  return best;
}

LD point_triangle_sq(const double p[3], const double a[3], const double b[3], const double c[3]) {
  LD best = std::min({point_segment_sq(p, a, b), point_segment_sq(p, b, c), point_segment_sq(p, c, a)});
  const V n = cross(sub(b, a), sub(c, a));
  const LD nn = dot(n, n);
  if (nn > 0) {
    // p projects strictly inside when it lies strictly left of all three edges (seen along n).
    const bool inside = dot(n, cross(sub(b, a), sub(p, a))) > 0 && dot(n, cross(sub(c, b), sub(p, b))) > 0 &&
                        dot(n, cross(sub(a, c), sub(p, c))) > 0;
    const LD h = dot(n, sub(p, a));
    if (inside) best = std::min(best, h * h / nn);
  }
  return best;
}

LD segment_segment_sq(const double p0[3], const double p1[3], const double q0[3], const double q1[3]) {
  LD best = std::min({point_segment_sq(p0, q0, q1), point_segment_sq(p1, q0, q1), point_segment_sq(q0, p0, p1),
                      point_segment_sq(q1, p0, p1)});
  const V d1 = sub(p1, p0), d2 = sub(q1, q0), r = sub(p0, q0);
  const V n = cross(d1, d2);
  const LD nn = dot(n, n);  // = |d1|^2 |d2|^2 - (d1.d2)^2, without the cancellation
  if (nn > 0) {             // not parallel: the closest points of the two lines are unique
    // The lines' closest points at p0 + s d1 and q0 + t d2, with s = r.(n x d2) / nn and
    // t = r.(n x d1) / nn. The textbook (bf - ce) / nn cancels catastrophically for nearly
    // parallel lines: at 2^97 with an angle of 2^-20 it put s = 0.007 for a true -1.5e-6, and
    // the line distance (0: the lines cross just outside both segments) was taken for the
    // segments' (3.3e23). Found by fuzz_differential (grid oracle vs brute force, RESULTS.md).
    const LD s = dot(r, cross(n, d2)) / nn, t = dot(r, cross(n, d1)) / nn, h = dot(r, n);
    if (s > 0 && s < 1 && t > 0 && t < 1) best = std::min(best, h * h / nn);
  }
  return best;
}

}  // namespace detail

using detail::point_segment_sq;
using detail::point_triangle_sq;
using detail::segment_segment_sq;

long double point_segment_distance(const double p[3], const double a[3], const double b[3]) {
  return std::sqrt(point_segment_sq(p, a, b));
}
long double point_triangle_distance(const double p[3], const double a[3], const double b[3], const double c[3]) {
  return std::sqrt(point_triangle_sq(p, a, b, c));
}
long double segment_segment_distance(const double p0[3], const double p1[3], const double q0[3], const double q1[3]) {
  return std::sqrt(segment_segment_sq(p0, p1, q0, q1));
}

// ---- Contacts ------------------------------------------------------------------------------
namespace {

using detail::Box;
using detail::collect;
using detail::grid_pairs;

// The mesh checked and widened to double once (float -> double is exact; double input as
// given), with its edges.
struct MeshInput {
  std::vector<double> xyz;
  const std::vector<int32_t>& tris;
  std::vector<int32_t> edges;
  double r;
  LD r2;  // contact: squared distance <= r^2, both in long double
  const double* v(int32_t i) const { return &xyz[3 * size_t(i)]; }

  MeshInput(const Mesh& m, double radius, bool need_edges)
      : xyz(m.xyz64.empty() ? std::vector<double>(m.xyz.begin(), m.xyz.end()) : m.xyz64), tris(m.tris), r(radius),
        r2(LD(radius) * radius) {
    if (need_edges) edges = m.edges.empty() ? derive_edges(m.tris) : m.edges;
    if (!(r >= 0) || !std::isfinite(r)) throw std::invalid_argument("reference: radius must be finite and >= 0");
    if (xyz.size() % 3 || m.tris.size() % 3 || edges.size() % 2)
      throw std::invalid_argument("reference: xyz, tris or edges size is not a multiple of 3, 3, 2");
    for (double x : xyz)
      if (!std::isfinite(x)) throw std::invalid_argument("reference: non-finite vertex coordinate");
    const int64_t nv = int64_t(xyz.size() / 3);
    const std::vector<int32_t>& edge_list = edges;
    for (const auto* list : {&tris, &edge_list})
      for (int32_t i : *list)
        if (i < 0 || i >= nv) throw std::invalid_argument("reference: vertex index " + std::to_string(i) + " out of range");
  }
  int32_t vertex_count() const { return int32_t(xyz.size() / 3); }
  int32_t triangle_count() const { return int32_t(tris.size() / 3); }
  int32_t edge_count() const { return int32_t(edges.size() / 2); }

  bool vt(int32_t p, int32_t t, bool drop) const {
    const int32_t* a = &tris[3 * size_t(t)];
    if (drop && (a[0] == p || a[1] == p || a[2] == p)) return false;
    return point_triangle_sq(v(p), v(a[0]), v(a[1]), v(a[2])) <= r2;
  }
  bool ee(int32_t e, int32_t f, bool drop) const {
    const int32_t *a = &edges[2 * size_t(e)], *b = &edges[2 * size_t(f)];
    if (drop && (a[0] == b[0] || a[0] == b[1] || a[1] == b[0] || a[1] == b[1])) return false;
    return segment_segment_sq(v(a[0]), v(a[1]), v(b[0]), v(b[1])) <= r2;
  }
};

// The box of k of the mesh's vertices, padded by r when widened (detail::box_of).
Box box_of(const MeshInput& g, const int32_t* ids, int k, bool widen) { return detail::box_of(g.xyz, ids, k, g.r, widen); }

}  // namespace

Pairs vt_contacts(const Mesh& mesh, double r, bool drop_incident) {
  const MeshInput g(mesh, r, false);
  std::vector<Box> tris(g.triangle_count()), points(g.vertex_count());
  for (int32_t t = 0; t < g.triangle_count(); ++t) tris[t] = box_of(g, &g.tris[3 * size_t(t)], 3, true);
  for (int32_t v = 0; v < g.vertex_count(); ++v) points[v] = box_of(g, &v, 1, false);
  return grid_pairs(tris, points, false, [&](int32_t v, int32_t t) { return g.vt(v, t, drop_incident); });
}

Pairs ee_contacts(const Mesh& mesh, double r, bool drop_incident) {
  const MeshInput g(mesh, r, true);
  std::vector<Box> padded(g.edge_count()), plain(g.edge_count());
  for (int32_t e = 0; e < g.edge_count(); ++e) {
    padded[e] = box_of(g, &g.edges[2 * size_t(e)], 2, true);
    plain[e] = box_of(g, &g.edges[2 * size_t(e)], 2, false);
  }
  return grid_pairs(padded, plain, true, [&](int32_t e, int32_t f) { return g.ee(e, f, drop_incident); });
}

Pairs vt_contacts_brute(const Mesh& mesh, double r, bool drop_incident) {
  const MeshInput g(mesh, r, false);
  return collect(g.vertex_count(), [&](int32_t v, Pairs& out) {
    for (int32_t t = 0; t < g.triangle_count(); ++t)
      if (g.vt(v, t, drop_incident)) out.emplace_back(v, t);
  });
}

Pairs ee_contacts_brute(const Mesh& mesh, double r, bool drop_incident) {
  const MeshInput g(mesh, r, true);
  return collect(g.edge_count(), [&](int32_t e, Pairs& out) {
    for (int32_t f = e + 1; f < g.edge_count(); ++f)
      if (g.ee(e, f, drop_incident)) out.emplace_back(e, f);
  });
}

}  // namespace minkq::reference
