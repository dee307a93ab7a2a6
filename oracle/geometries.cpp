// Contacts of scenes of many geometries (minkq_reference.h, "Scenes of many geometries"): the
// geometries flattened into the global numbering, then every pair of a kind tested against the
// rules of which pairs are looked for and against its reach r + t(a) + t(b).
#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <string>

#include "reference_grid.h"
#include "minkq_reference.h"

namespace minkq::reference {
namespace {

using detail::LD;

constexpr uint32_t kAllKinds = kKindVT | kKindEE | kKindVV | kKindEV;
constexpr uint32_t kAllFlags = kSelf | kDropIncident | kFloat64 | kStatic;

uint32_t kind_bit(Kind kind) {
  switch (kind) {
    case Kind::VT: return kKindVT;
    case Kind::EE: return kKindEE;
    case Kind::VV: return kKindVV;
    case Kind::EV: return kKindEV;
  }
  throw std::invalid_argument("reference: unknown kind");
}

size_t vertex_count(const Geometry& g) { return g.mesh.xyz64.empty() ? g.mesh.xyz.size() / 3 : g.mesh.xyz64.size() / 3; }

// Throws for what minkq_scene_create_geometries refuses, naming the geometry.
void check(const Geometry& g, size_t index, const std::vector<int32_t>& edges) {
  const std::string name = "reference: geometry " + std::to_string(index) + ": ";
  const Mesh& m = g.mesh;
  const size_t nv = vertex_count(g);
  if ((m.xyz64.empty() ? m.xyz.size() : m.xyz64.size()) % 3 || m.tris.size() % 3 || edges.size() % 2)
    throw std::invalid_argument(name + "xyz, tris or edges size is not a multiple of 3, 3, 2");
  if (!m.xyz64.empty() && m.xyz.size() != m.xyz64.size()) throw std::invalid_argument(name + "xyz and xyz64 differ in size");
  if (nv == 0) throw std::invalid_argument(name + "no vertices");
  if (g.kinds == 0 || (g.kinds & ~kAllKinds)) throw std::invalid_argument(name + "kinds must be VT, EE, VV or EV bits");
  if (g.flags & ~kAllFlags) throw std::invalid_argument(name + "unknown flag bits");
  if (g.world < -1) throw std::invalid_argument(name + "world must be >= 0 or -1");
  if (!g.thickness.empty() && g.thickness.size() != nv) throw std::invalid_argument(name + "thickness count is not the vertex count");
  for (double t : g.thickness)
    if (!(t >= 0) || !std::isfinite(t)) throw std::invalid_argument(name + "thickness must be finite and >= 0");
  for (const auto* list : {&m.tris, &edges})
    for (int32_t i : *list)
      if (i < 0 || size_t(i) >= nv) throw std::invalid_argument(name + "vertex index " + std::to_string(i) + " out of range");
}

// The scene in global ids, checked: positions in double, topology, each element's geometry
// and thickness. Vertices are elements of one point (their own id).
struct Flat {
  const std::vector<Geometry>& geometries;
  LD r;
  std::vector<double> xyz;
  std::vector<int32_t> points, tris, edges;
  std::vector<uint32_t> geometry_of[3];  // per vertex, triangle, edge
  std::vector<double> thickness_of[3];

  Flat(const std::vector<Geometry>& gs, double radius) : geometries(gs), r(radius) {
    if (!(radius >= 0) || !std::isfinite(radius)) throw std::invalid_argument("reference: radius must be finite and >= 0");
    if (gs.empty()) throw std::invalid_argument("reference: a scene needs at least one geometry");
    for (size_t g = 0; g < gs.size(); ++g) {
      const Mesh& m = gs[g].mesh;
      const std::vector<int32_t> local_edges = geometry_edges(gs[g]);
      check(gs[g], g, local_edges);
      const int32_t base = int32_t(xyz.size() / 3);
      const size_t nv = vertex_count(gs[g]);
      if (m.xyz64.empty()) xyz.insert(xyz.end(), m.xyz.begin(), m.xyz.end());
      else xyz.insert(xyz.end(), m.xyz64.begin(), m.xyz64.end());
      for (size_t v = 0; v < nv; ++v) {
        geometry_of[0].push_back(uint32_t(g));
        thickness_of[0].push_back(gs[g].thickness.empty() ? 0.0 : gs[g].thickness[v]);
      }
      add(m.tris, 3, base, g, tris, 1);
      add(local_edges, 2, base, g, edges, 2);
    }
    for (double x : xyz)
      if (!std::isfinite(x)) throw std::invalid_argument("reference: non-finite vertex coordinate");
    points.resize(xyz.size() / 3);
    std::iota(points.begin(), points.end(), 0);
  }

  // Appends elements of k local vertex ids, offset to global ones, with their thickness (the
  // largest of their vertices').
  void add(const std::vector<int32_t>& local, int k, int32_t base, size_t g, std::vector<int32_t>& out, int element) {
    for (size_t i = 0; i < local.size(); i += size_t(k)) {
      double t = 0;
      for (int j = 0; j < k; ++j) {
        out.push_back(local[i + j] + base);
        t = std::max(t, thickness_of[0][size_t(local[i + j] + base)]);
      }
      geometry_of[element].push_back(uint32_t(g));
      thickness_of[element].push_back(t);
    }
  }

  // The two sides of a kind: (element type, vertex ids, points per element).
  struct Side {
    int element;
    const std::vector<int32_t>* ids;
    int k;
    size_t count() const { return ids->size() / size_t(k); }
    const int32_t* of(int32_t i) const { return &(*ids)[size_t(k) * size_t(i)]; }
  };
  Side side(Kind kind, bool second) const {
    if ((kind == Kind::VT && second)) return {1, &tris, 3};
    if (kind == Kind::EE || (kind == Kind::EV && second)) return {2, &edges, 2};
    return {0, &points, 1};
  }
  const double* v(int32_t i) const { return &xyz[3 * size_t(i)]; }

  bool allowed(Kind kind, int32_t a, int32_t b) const {
    const Side sa = side(kind, false), sb = side(kind, true);
    if (a < 0 || b < 0 || size_t(a) >= sa.count() || size_t(b) >= sb.count()) return false;
    const uint32_t ga = geometry_of[sa.element][size_t(a)], gb = geometry_of[sb.element][size_t(b)];
    const Geometry &x = geometries[ga], &y = geometries[gb];
    const uint32_t bit = kind_bit(kind);
    if (!(x.kinds & bit) || !(y.kinds & bit)) return false;
    if (ga != gb) return (x.world == y.world || x.world == -1 || y.world == -1) && (x.group & y.mask) && (y.group & x.mask);
    if (!(x.flags & kSelf)) return false;
    if (!(x.flags & kDropIncident)) return true;
    for (int i = 0; i < sa.k; ++i)
      for (int j = 0; j < sb.k; ++j)
        if (sa.of(a)[i] == sb.of(b)[j]) return false;
    return true;
  }

  LD distance_sq(Kind kind, int32_t a, int32_t b) const {
    const int32_t *p = side(kind, false).of(a), *q = side(kind, true).of(b);
    switch (kind) {
      case Kind::VT: return detail::point_triangle_sq(v(p[0]), v(q[0]), v(q[1]), v(q[2]));
      case Kind::EE: return detail::segment_segment_sq(v(p[0]), v(p[1]), v(q[0]), v(q[1]));
      case Kind::VV: return detail::point_segment_sq(v(p[0]), v(q[0]), v(q[0]));
      case Kind::EV: return detail::point_segment_sq(v(p[0]), v(q[0]), v(q[1]));
    }
    return 0;
  }
  double thickness(Kind kind, bool second, int32_t i) const { return thickness_of[side(kind, second).element][size_t(i)]; }
  LD reach(Kind kind, int32_t a, int32_t b) const { return r + LD(thickness(kind, false, a)) + LD(thickness(kind, true, b)); }

  bool accept(Kind kind, int32_t a, int32_t b) const {
    if (!allowed(kind, a, b)) return false;
    const LD reach_ab = reach(kind, a, b);
    return distance_sq(kind, a, b) <= reach_ab * reach_ab;
  }
};

bool unordered(Kind kind) { return kind == Kind::EE || kind == Kind::VV; }

}  // namespace

std::vector<int32_t> geometry_edges(const Geometry& g) {
  if (!g.mesh.edges.empty()) return g.mesh.edges;
  if (g.kinds & (kKindEE | kKindEV)) return derive_edges(g.mesh.tris);
  return {};
}

Mesh concatenate(const std::vector<Geometry>& geometries) {
  Mesh out;
  bool any64 = false;
  for (const Geometry& g : geometries) any64 = any64 || !g.mesh.xyz64.empty();
  std::vector<double> xyz64;
  for (const Geometry& g : geometries) {
    const int32_t base = int32_t(out.xyz.size() / 3);
    out.xyz.insert(out.xyz.end(), g.mesh.xyz.begin(), g.mesh.xyz.end());
    if (g.mesh.xyz64.empty()) xyz64.insert(xyz64.end(), g.mesh.xyz.begin(), g.mesh.xyz.end());
    else xyz64.insert(xyz64.end(), g.mesh.xyz64.begin(), g.mesh.xyz64.end());
    for (int32_t v : g.mesh.tris) out.tris.push_back(v + base);
    for (int32_t v : geometry_edges(g)) out.edges.push_back(v + base);
  }
  if (any64) out.xyz64 = std::move(xyz64);
  return out;
}

std::pair<size_t, size_t> geometry_range(const std::vector<Geometry>& geometries, size_t g, int k) {
  if (g >= geometries.size() || k < 0 || k > 2) throw std::invalid_argument("reference: geometry or element out of range");
  auto count = [k](const Geometry& x) {
    return k == 0 ? vertex_count(x) : k == 1 ? x.mesh.tris.size() / 3 : geometry_edges(x).size() / 2;
  };
  size_t first = 0;
  for (size_t i = 0; i < g; ++i) first += count(geometries[i]);
  return {first, count(geometries[g])};
}

Pairs not_allowed(const std::vector<Geometry>& geometries, Kind kind, const Pairs& pairs) {
  const Flat flat(geometries, 0.0);
  Pairs out;
  for (const auto& [a, b] : pairs)
    if ((unordered(kind) && a >= b) || !flat.allowed(kind, a, b)) out.emplace_back(a, b);
  return out;
}

std::vector<PairMeasure> measure_pairs(const std::vector<Geometry>& geometries, Kind kind, const Pairs& pairs, double r) {
  const Flat flat(geometries, r);
  const auto sa = flat.side(kind, false), sb = flat.side(kind, true);
  std::vector<PairMeasure> out;
  for (const auto& [a, b] : pairs) {
    if (a < 0 || b < 0 || size_t(a) >= sa.count() || size_t(b) >= sb.count())
      throw std::invalid_argument("reference: pair (" + std::to_string(a) + ", " + std::to_string(b) + ") out of range");
    std::vector<const double*> pts;
    for (int i = 0; i < sa.k; ++i) pts.push_back(flat.v(sa.of(a)[i]));
    for (int i = 0; i < sb.k; ++i) pts.push_back(flat.v(sb.of(b)[i]));
    double scale = 0;
    for (const double* p : pts)
      for (const double* q : pts) scale = std::max(scale, double(point_segment_distance(p, q, q)));
    out.push_back({std::sqrt(flat.distance_sq(kind, a, b)),
                   r + flat.thickness(kind, false, a) + flat.thickness(kind, true, b), scale});
  }
  return out;
}

Pairs geometry_contacts(const std::vector<Geometry>& geometries, Kind kind, double r) {
  const Flat flat(geometries, r);
  const auto sa = flat.side(kind, false), sb = flat.side(kind, true);
  // Elements padded by r + their thickness, queries by theirs: together the pair's reach.
  std::vector<detail::Box> elements(sb.count()), queries(sa.count());
  for (size_t e = 0; e < elements.size(); ++e)
    elements[e] = detail::box_of(flat.xyz, sb.of(int32_t(e)), sb.k, r + flat.thickness(kind, true, int32_t(e)), true);
  for (size_t q = 0; q < queries.size(); ++q)
    queries[q] = detail::box_of(flat.xyz, sa.of(int32_t(q)), sa.k, flat.thickness(kind, false, int32_t(q)), true);
  return detail::grid_pairs(elements, queries, unordered(kind),
                            [&](int32_t a, int32_t b) { return flat.accept(kind, a, b); });
}

Pairs geometry_contacts_brute(const std::vector<Geometry>& geometries, Kind kind, double r) {
  const Flat flat(geometries, r);
  const int32_t queries = int32_t(flat.side(kind, false).count()), elements = int32_t(flat.side(kind, true).count());
  return detail::collect(queries, [&](int32_t a, Pairs& out) {
    for (int32_t b = unordered(kind) ? a + 1 : 0; b < elements; ++b)
      if (flat.accept(kind, a, b)) out.emplace_back(a, b);
  });
}

}  // namespace minkq::reference
