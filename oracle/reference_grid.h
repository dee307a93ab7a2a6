// minkq::reference internals shared by the oracle's sources (not installed, not for its
// users): the squared long double distances, element boxes, and the sparse grid that the
// contact queries, one mesh or many geometries, prefilter with.
#pragma once

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <vector>

#include "minkq_reference.h"

namespace minkq::reference::detail {

using LD = long double;

// Squared distances in long double (distances_contacts.cpp); the public *_distance functions
// are their square roots.
LD point_segment_sq(const double p[3], const double a[3], const double b[3]);
LD point_triangle_sq(const double p[3], const double a[3], const double b[3], const double c[3]);
LD segment_segment_sq(const double p0[3], const double p1[3], const double q0[3], const double q1[3]);

struct Box {
  double lo[3], hi[3];
  bool overlaps(const Box& b) const {
    for (int k = 0; k < 3; ++k)
      if (lo[k] > b.hi[k] || b.lo[k] > hi[k]) return false;
    return true;
  }
};

// The box of k vertices ids[0..k) of xyz (3 doubles each). Widened, it is padded by `pad` and
// stepped outward past rounding (two ulps, plus 2^-30 pad for the long double error of the
// distances), so that every pair whose distance test accepts it at a reach up to the two
// boxes' pads together survives the box prefilter and the grid, a reach of 0 included. Every
// box, padded or not, also grows by 2^-50 of its largest coordinate magnitude: the distances'
// rounding, relative to the coordinates of the pair, can accept two elements whose exact boxes
// miss each other by that much (a gap of 2^-151 beside coordinates of 1/4 rounds to 0).
inline Box box_of(const std::vector<double>& xyz, const int32_t* ids, int k, double pad, bool widen) {
  Box b;
  const double inf = std::numeric_limits<double>::infinity();
  double magnitude = 0;
  for (int i = 0; i < k; ++i)
    for (int a = 0; a < 3; ++a) magnitude = std::max(magnitude, std::abs(xyz[3 * size_t(ids[i]) + a]));
  const double p = (widen ? pad + pad * 0x1p-30 : 0.0) + magnitude * 0x1p-50;
  for (int a = 0; a < 3; ++a) {
    double lo = xyz[3 * size_t(ids[0]) + a], hi = lo;
    for (int i = 1; i < k; ++i) lo = std::min(lo, xyz[3 * size_t(ids[i]) + a]), hi = std::max(hi, xyz[3 * size_t(ids[i]) + a]);
    b.lo[a] = std::nextafter(std::nextafter(lo - p, -inf), -inf);
    b.hi[a] = std::nextafter(std::nextafter(hi + p, inf), inf);
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

}  // namespace minkq::reference::detail
