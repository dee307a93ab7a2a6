// Long double distances and the brute-force and grid-accelerated contact oracles.
#include "minkq_reference.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

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
namespace {

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

}  // namespace

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

// The mesh checked and widened to double once (float -> double is exact; double input as
// given), with its edges.
struct Geometry {
  std::vector<double> xyz;
  const std::vector<int32_t>& tris;
  std::vector<int32_t> edges;
  double r;
  LD r2;  // contact: squared distance <= r^2, both in long double
  const double* v(int32_t i) const { return &xyz[3 * size_t(i)]; }

  Geometry(const Mesh& m, double radius, bool need_edges)
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

struct Box {
  double lo[3], hi[3];
  bool overlaps(const Box& b) const {
    for (int k = 0; k < 3; ++k)
      if (lo[k] > b.hi[k] || b.lo[k] > hi[k]) return false;
    return true;
  }
};

// The box of k vertices; an element box (widen) is padded by r and stepped outward past
// rounding (two ulps, plus 2^-30 r for the long double error of the distances), so every pair
// the distance test accepts survives the box prefilter and the grid, r = 0 included.
Box box_of(const Geometry& g, const int32_t* ids, int k, bool widen) {
  const double pad = widen ? g.r : 0.0;
  Box b;
  const double inf = std::numeric_limits<double>::infinity(), p = pad + pad * 0x1p-30;
  for (int a = 0; a < 3; ++a) {
    double lo = g.v(ids[0])[a], hi = lo;
    for (int i = 1; i < k; ++i) lo = std::min(lo, g.v(ids[i])[a]), hi = std::max(hi, g.v(ids[i])[a]);
    b.lo[a] = widen ? std::nextafter(std::nextafter(lo - p, -inf), -inf) : lo;
    b.hi[a] = widen ? std::nextafter(std::nextafter(hi + p, inf), inf) : hi;
  }
  return b;
}

// Sparse uniform grid over padded element boxes: (cell key, element) entries sorted by key,
// so memory follows the number of entries, not of cells. The cell edge is the mean padded box
// size (mean element size + 2r; an element then covers ~8 cells or fewer), raised where
// needed so that no axis has more than 2^20 cells. Elements covering more than kBigCells
// cells go to a list every query scans, so one huge element cannot blow up the entry count.
class Grid {
 public:
  static constexpr int64_t kMaxDim = int64_t(1) << 20;
  static constexpr int64_t kBigCells = 512;

  Grid(const std::vector<Box>& boxes, const std::vector<Box>& queries) {
    double lo[3], hi[3], mean = 0, extent = 0;
    for (int k = 0; k < 3; ++k) lo[k] = std::numeric_limits<double>::infinity(), hi[k] = -lo[k];
    for (const auto* list : {&boxes, &queries})
      for (const Box& b : *list)
        for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], b.lo[k]), hi[k] = std::max(hi[k], b.hi[k]);
    for (const Box& b : boxes) mean += std::max({b.hi[0] - b.lo[0], b.hi[1] - b.lo[1], b.hi[2] - b.lo[2]});
    mean = boxes.empty() ? 1.0 : mean / double(boxes.size());
    for (int k = 0; k < 3; ++k) origin_[k] = lo[k], extent = std::max(extent, hi[k] - lo[k]);
    if (boxes.empty() || queries.empty()) extent = 0, origin_[0] = origin_[1] = origin_[2] = 0;
    cell_ = std::max({mean, extent / double(kMaxDim - 1), std::numeric_limits<double>::min()});
    if (!std::isfinite(cell_)) throw std::runtime_error("reference grid: non-finite extent");
    for (int k = 0; k < 3; ++k) dim_[k] = extent == 0 ? 1 : std::min<int64_t>(int64_t((hi[k] - lo[k]) / cell_) + 1, kMaxDim);

    int64_t a[3], b[3];
    std::vector<std::pair<uint64_t, int32_t>> entries;
    for (int32_t e = 0; e < int32_t(boxes.size()); ++e) {
      if (range(boxes[e], a, b) > kBigCells) {
        big_.push_back(e);
        continue;
      }
      for (int64_t x = a[0]; x <= b[0]; ++x)
        for (int64_t y = a[1]; y <= b[1]; ++y)
          for (int64_t z = a[2]; z <= b[2]; ++z) entries.push_back({key(x, y, z), e});
    }
    // Sorted by cell, then as CSR: keys_[c] owns elements_[starts_[c] .. starts_[c + 1]).
    tbb::parallel_sort(entries.begin(), entries.end());
    elements_.resize(entries.size());
    for (size_t i = 0; i < entries.size(); ++i) {
      if (i == 0 || entries[i].first != entries[i - 1].first) keys_.push_back(entries[i].first), starts_.push_back(i);
      elements_[i] = entries[i].second;
    }
    starts_.push_back(entries.size());
  }

  // Sets out to every element >= first sharing a cell with the query box, each once, sorted.
  // A query covering many cells scans all `count` elements instead.
  void candidates(const Box& q, int32_t first, int32_t count, std::vector<int32_t>& out) const {
    out.clear();
    int64_t a[3], b[3];
    const int64_t cells = range(q, a, b);
    if (cells > kBigCells) {
      for (int32_t e = first; e < count; ++e) out.push_back(e);
      return;
    }
    for (int64_t x = a[0]; x <= b[0]; ++x)
      for (int64_t y = a[1]; y <= b[1]; ++y)
        for (int64_t z = a[2]; z <= b[2]; ++z) {
          auto cell = std::lower_bound(keys_.begin(), keys_.end(), key(x, y, z));
          if (cell == keys_.end() || *cell != key(x, y, z)) continue;
          const size_t c = size_t(cell - keys_.begin());
          for (size_t i = starts_[c]; i < starts_[c + 1]; ++i)
            if (elements_[i] >= first) out.push_back(elements_[i]);
        }
    for (int32_t e : big_)
      if (e >= first) out.push_back(e);
    if (cells > 1 || !big_.empty()) {  // one cell holds each element once: no duplicates
      std::sort(out.begin(), out.end());
      out.erase(std::unique(out.begin(), out.end()), out.end());
    }
  }

 private:
  // floor((x - origin) / cell) is monotone in x whatever the rounding, so a point inside a box
  // lands inside the box's cell range; clamping keeps that.
  int64_t index(double x, int k) const {
    const double c = std::floor((x - origin_[k]) / cell_);
    return c <= 0 ? 0 : c >= double(dim_[k] - 1) ? dim_[k] - 1 : int64_t(c);
  }
  int64_t range(const Box& bx, int64_t a[3], int64_t b[3]) const {
    int64_t n = 1;
    for (int k = 0; k < 3; ++k) a[k] = index(bx.lo[k], k), b[k] = index(bx.hi[k], k), n *= b[k] - a[k] + 1;
    return n;
  }
  static uint64_t key(int64_t x, int64_t y, int64_t z) { return uint64_t(x) << 42 | uint64_t(y) << 21 | uint64_t(z); }

  double origin_[3], cell_;
  int64_t dim_[3];
  std::vector<uint64_t> keys_;  // occupied cells, sorted
  std::vector<size_t> starts_;
  std::vector<int32_t> elements_, big_;
};

// Runs body(q, out) for every query q in parallel; returns the sorted union of the pairs.
template <class Body>
Pairs collect(int32_t queries, Body body) {
  tbb::enumerable_thread_specific<Pairs> local;
  tbb::parallel_for(tbb::blocked_range<int32_t>(0, queries, 64), [&](const tbb::blocked_range<int32_t>& range) {
    Pairs& out = local.local();
    for (int32_t q = range.begin(); q < range.end(); ++q) body(q, out);
  });
  Pairs all;
  for (Pairs& p : local) all.insert(all.end(), p.begin(), p.end());
  tbb::parallel_sort(all.begin(), all.end());
  return all;
}

// Grid-accelerated pairs (q, e) with accept(q, e): elements padded by r in the grid, queries
// unpadded; the padded-box overlap is a cheap conservative prefilter before the distance.
// `after` (EE) keeps only e > q, each unordered pair once.
template <class Accept>
Pairs grid_pairs(const std::vector<Box>& elements, const std::vector<Box>& queries, bool after, Accept accept) {
  const Grid grid(elements, queries);
  tbb::enumerable_thread_specific<std::vector<int32_t>> scratch;
  return collect(int32_t(queries.size()), [&](int32_t q, Pairs& out) {
    std::vector<int32_t>& cand = scratch.local();
    grid.candidates(queries[q], after ? q + 1 : 0, int32_t(elements.size()), cand);
    for (int32_t e : cand)
      if (elements[e].overlaps(queries[q]) && accept(q, e)) out.emplace_back(q, e);
  });
}

}  // namespace

Pairs vt_contacts(const Mesh& mesh, double r, bool drop_incident) {
  const Geometry g(mesh, r, false);
  std::vector<Box> tris(g.triangle_count()), points(g.vertex_count());
  for (int32_t t = 0; t < g.triangle_count(); ++t) tris[t] = box_of(g, &g.tris[3 * size_t(t)], 3, true);
  for (int32_t v = 0; v < g.vertex_count(); ++v) points[v] = box_of(g, &v, 1, false);
  return grid_pairs(tris, points, false, [&](int32_t v, int32_t t) { return g.vt(v, t, drop_incident); });
}

Pairs ee_contacts(const Mesh& mesh, double r, bool drop_incident) {
  const Geometry g(mesh, r, true);
  std::vector<Box> padded(g.edge_count()), plain(g.edge_count());
  for (int32_t e = 0; e < g.edge_count(); ++e) {
    padded[e] = box_of(g, &g.edges[2 * size_t(e)], 2, true);
    plain[e] = box_of(g, &g.edges[2 * size_t(e)], 2, false);
  }
  return grid_pairs(padded, plain, true, [&](int32_t e, int32_t f) { return g.ee(e, f, drop_incident); });
}

Pairs vt_contacts_brute(const Mesh& mesh, double r, bool drop_incident) {
  const Geometry g(mesh, r, false);
  return collect(g.vertex_count(), [&](int32_t v, Pairs& out) {
    for (int32_t t = 0; t < g.triangle_count(); ++t)
      if (g.vt(v, t, drop_incident)) out.emplace_back(v, t);
  });
}

Pairs ee_contacts_brute(const Mesh& mesh, double r, bool drop_incident) {
  const Geometry g(mesh, r, true);
  return collect(g.edge_count(), [&](int32_t e, Pairs& out) {
    for (int32_t f = e + 1; f < g.edge_count(); ++f)
      if (g.ee(e, f, drop_incident)) out.emplace_back(e, f);
  });
}

}  // namespace minkq::reference
