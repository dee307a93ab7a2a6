// test_stability's cases: the stiff and extreme inputs every mode runs on (offsets, 2^k and
// 1e+-3 scalings, radii from 1e-9 to 1e3 of the scene, near-parallel edge pairs, sheets stacked
// at exactly r and r +- ulps, degenerate elements), each a mesh and a float radius, and the
// meshes made for them here. Kept apart from the runs (test_stability.cpp): what is tested, not how.
#include <cmath>
#include <cstdlib>

#include "minkq/predicates.h"
#include "stability/stability.h"

namespace minkq::test::stability {
namespace {

ref::Mesh base_mesh() { return ref::twisted_sheet(20, 3.0); }

// Pairs of segments, each pair alone in space (centres 10 apart): segment A of length 1 in a
// random direction, B parallel to A tilted by `angle` and offset perpendicular by `gap`, both
// rounded to float. One edge per segment, no triangles.
ref::Mesh near_parallel(double gap, const std::vector<double>& angles, int per_angle, uint64_t seed) {
  uint64_t state = seed;
  auto uniform = [&state] {
    uint64_t z = (state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return double((z ^ (z >> 31)) >> 11) * 0x1p-53;
  };
  ref::Mesh m;
  int k = 0;
  for (double angle : angles)
    for (int i = 0; i < per_angle; ++i, ++k) {
      double a[3], n[3];  // unit direction and a unit normal to it
      const double th = std::acos(2 * uniform() - 1), ph = 2 * 3.14159265358979323846 * uniform();
      a[0] = std::sin(th) * std::cos(ph), a[1] = std::sin(th) * std::sin(ph), a[2] = std::cos(th);
      const double h[3] = {std::fabs(a[0]) < 0.9 ? 1.0 : 0.0, std::fabs(a[0]) < 0.9 ? 0.0 : 1.0, 0.0};
      n[0] = a[1] * h[2] - a[2] * h[1], n[1] = a[2] * h[0] - a[0] * h[2], n[2] = a[0] * h[1] - a[1] * h[0];
      const double nl = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
      for (double& x : n) x /= nl;
      const double c[3] = {10.0 * (k % 16), 10.0 * (k / 16 % 16), 10.0 * (k / 256)};
      const int32_t base = int32_t(m.vertex_count());
      // A from c - a/2 to c + a/2; B centred at c + gap n, direction a cos(angle) + n sin(angle).
      for (int s = -1; s <= 1; s += 2)
        for (int j = 0; j < 3; ++j) m.xyz.push_back(float(c[j] + 0.5 * s * a[j]));
      for (int s = -1; s <= 1; s += 2)
        for (int j = 0; j < 3; ++j)
          m.xyz.push_back(float(c[j] + gap * n[j] + 0.5 * s * (a[j] * std::cos(angle) + n[j] * std::sin(angle))));
      m.edges.insert(m.edges.end(), {base, base + 1, base + 2, base + 3});
    }
  return m;
}

// A grid with every kind of degenerate element mixed in: collapsed vertices (repeated
// positions), zero-area triangles (collinear vertices), triangles with a repeated index
// (a, a, b) and (a, a, a), zero-length edges, needle triangles (aspect 1e7).
ref::Mesh degenerate_mesh() {
  ref::Mesh m = ref::grid_sheet(24);
  const int n = 24;
  for (int j = 0; j < n; j += 5)  // collapse every 5th column pair: repeated positions
    for (int i = 0; i + 1 < n; i += 7) {
      const size_t a = 3 * size_t(j * n + i), b = 3 * size_t(j * n + i + 1);
      for (int k = 0; k < 3; ++k) m.xyz[b + k] = m.xyz[a + k];
    }
  auto add_vertex = [&](double x, double y, double z) {
    m.xyz.insert(m.xyz.end(), {float(x), float(y), float(z)});
    return int32_t(m.vertex_count() - 1);
  };
  for (int i = 0; i < 40; ++i) {
    const double x = 0.02 + 0.024 * i, y = 0.5 + 0.01 * std::sin(i), z = 0.003 * (i % 3);
    const int32_t a = add_vertex(x, y, z), b = add_vertex(x + 0.01, y, z), c = add_vertex(x + 0.02, y, z);  // collinear
    m.tris.insert(m.tris.end(), {a, b, c, a, a, b, a, a, a});
    const int32_t d = add_vertex(x, y + 0.2, z + 0.004), e = add_vertex(x + 0.05, y + 0.2, z + 0.004),
                  f = add_vertex(x + 0.025, y + 0.2 + 0.05e-7, z + 0.004);  // needle
    m.tris.insert(m.tris.end(), {d, e, f});
  }
  m.edges = ref::derive_edges(m.tris);
  return m;
}

}  // namespace

std::vector<Case> cases() {
  std::vector<Case> out;
  const ref::Mesh base = base_mesh();
  const double h = ref::mean_edge_length(base);
  const float r0 = float(0.5 * h);
  out.push_back({"scale", "base", base, r0, ""});
  // Offsets.
  for (double off : {1e3, 1e4, 1e5, 1e6, 1e7}) {
    ref::Mesh m = base;
    ref::transform(m, 1.0, off);
    out.push_back({"offset", "unit sheet + " + fmt(off, 2), m, r0, ""});
  }
  {
    ref::Mesh m = base;
    ref::transform(m, 1e3, 1e7);
    out.push_back({"offset", "1e3-sized sheet + 1e7", m, float(0.5 * ref::mean_edge_length(m)), ""});
  }
  // Scaling: 2^k exactly (sets must be identical while no square over- or underflows), 1e+-3
  // (rounded).
  for (int k : {-100, -70, -40, -10, 10, 40, 70, 100}) {
    ref::Mesh m = base;
    ref::transform(m, std::ldexp(1.0, k), 0.0);
    out.push_back({"scale", "x 2^" + std::to_string(k), m, std::ldexp(r0, k), "base", std::abs(k) > 40});
  }
  for (double s : {1e-3, 1e3}) {
    ref::Mesh m = base;
    ref::transform(m, s, 0.0);
    out.push_back({"scale", "x " + fmt(s, 2), m, float(double(r0) * s), "base"});
  }
  // Radii relative to the scene size (the sheet spans 1).
  for (double f : {1e-9, 1e-7, 1e-5, 1e-3, 1e-1, 1.0, 10.0, 1e3}) {
    out.push_back({"radius", "r = " + fmt(f, 2) + " x size", base, float(f), ""});
  }
  // Near-parallel edges at distance r, r (1 +- 2^-20), r (1 +- 2^-23).
  {
    const std::vector<double> angles = {0.0, 1e-9, 1e-7, 1e-5, 1e-3};
    const float r = 0.01f;
    for (double rel : {0.0, 0x1p-23, -0x1p-23, 0x1p-20, -0x1p-20}) {
      out.push_back({"near-parallel", "gap = r (1 " + std::string(rel < 0 ? "- " : "+ ") + fmt(std::fabs(rel), 3) + ")",
                     near_parallel(double(r) * (1 + rel), angles, 200, 7), r, ""});
    }
  }
  // Sheets stacked at exactly r and r +- k ulp.
  {
    const float g = 0x1p-6f;  // layers at z = k / 64: exact
    const ref::Mesh m = ref::stacked_sheets(12, 4, double(g));
    float r = g;
    for (int k = 0; k < 3; ++k) r = minkq::next_down(r);
    for (int k = -3; k <= 3; ++k, r = minkq::next_up(r)) {
      out.push_back({"stacked", "gap 2^-6, r = gap " + std::string(k < 0 ? "- " : "+ ") + std::to_string(std::abs(k)) + " ulp", m, r, ""});
    }
    // A gap that is not a float: z = k * 0.01 rounded; r = the float nearest to the first gap.
    const ref::Mesh m2 = ref::stacked_sheets(12, 4, 0.01);
    const float g2 = float(double(m2.xyz[3 * 144 + 2]) - double(m2.xyz[2]));
    float r2 = minkq::next_down(g2);
    for (int k = -1; k <= 1; ++k, r2 = minkq::next_up(r2)) {
      out.push_back({"stacked", "gap 0.01 (rounded), r = gap " + std::string(k < 0 ? "- " : "+ ") + std::to_string(std::abs(k)) + " ulp", m2, r2, ""});
    }
  }
  // Degenerate elements.
  {
    const ref::Mesh m = degenerate_mesh();
    out.push_back({"degenerate", "mixed degenerate, r = 0.5 x mean edge", m, float(0.5 / 23), ""});
    out.push_back({"degenerate", "mixed degenerate, r = 0", m, 0.0f, ""});
  }
  return out;
}

}  // namespace minkq::test::stability
