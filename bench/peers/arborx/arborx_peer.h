// arborx_bench's ArborX side: the Kokkos/ArborX types, the query boxes that decide as minkq's
// float gap test, the predicates and callbacks of the ArborX contestants, and the helpers that
// build its trees, reduce its counts and store EE pairs by the half traversal (arborx_peer.cpp).
#pragma once

#include <ArborX.hpp>
#include <ArborX_Version.hpp>
#include <detail/ArborX_HalfTraversal.hpp>  // ArborX::Details::HalfTraversal: internal, used by its DBSCAN

#include <Kokkos_Core.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "arborx_bench.h"

namespace peer {

using Mem = Kokkos::HostSpace;
using AxPoint = ArborX::Point<3, float>;
using AxBox = ArborX::Box<3, float>;
using AxSphere = ArborX::Sphere<3, float>;
using AxValue = ArborX::PairValueIndex<AxBox, int>;
using AxBvh = ArborX::BoundingVolumeHierarchy<Mem, AxValue>;
template <class T>
using View = Kokkos::View<T*, Mem>;
template <class T>
using Borrowed = Kokkos::View<const T*, Mem, Kokkos::MemoryTraits<Kokkos::Unmanaged>>;

struct Tri {
  int v[3];
};
struct Seg {
  int v[2];
};
static_assert(sizeof(AxPoint) == 3 * sizeof(float) && sizeof(Tri) == 12 && sizeof(Seg) == 8);

// ---- Query boxes that decide as minkq's float gap test ------------------------------------

// The largest float x with fl(x - hi) <= r: a box b then passes ArborX's `b.lo <= x` exactly
// when minkq's `b.lo - hi <= r` holds (the rounded difference grows with b.lo). A float
// difference rounds to at most r when the exact one lies below m, the midpoint between r and the
// next float (at m itself, ties to even decide), so x is the float at or next to hi + m,
// computed in double (m is exact there, the sum off by far less than a float step) and settled
// by the float test itself. Stepping from fl(hi + r) instead can take billions of steps where
// hi + r is near 0 and the floats are dense.
KOKKOS_INLINE_FUNCTION float gap_upper(float hi, float r) {
  const double m = 0.5 * (double(r) + double(std::nextafter(r, INFINITY)));
  float x = float(double(hi) + m);
  while (!(x - hi <= r)) x = std::nextafter(x, -INFINITY);
  while (std::nextafter(x, INFINITY) - hi <= r) x = std::nextafter(x, INFINITY);
  return x;
}
// The smallest float x with fl(lo - x) <= r (the mirror image).
KOKKOS_INLINE_FUNCTION float gap_lower(float lo, float r) {
  const double m = 0.5 * (double(r) + double(std::nextafter(r, INFINITY)));
  float x = float(double(lo) - m);
  while (!(lo - x <= r)) x = std::nextafter(x, INFINITY);
  while (lo - std::nextafter(x, -INFINITY) <= r) x = std::nextafter(x, -INFINITY);
  return x;
}
// The box [lo, hi] grown by r: exact (as minkq decides) or plain (round to nearest).
template <bool kExact>
KOKKOS_INLINE_FUNCTION AxBox grown(const AxPoint& lo, const AxPoint& hi, float r) {
  if constexpr (kExact)
    return AxBox{AxPoint{gap_lower(lo[0], r), gap_lower(lo[1], r), gap_lower(lo[2], r)},
                 AxPoint{gap_upper(hi[0], r), gap_upper(hi[1], r), gap_upper(hi[2], r)}};
  else
    return AxBox{AxPoint{lo[0] - r, lo[1] - r, lo[2] - r}, AxPoint{hi[0] + r, hi[1] + r, hi[2] + r}};
}
KOKKOS_INLINE_FUNCTION AxPoint pmin(const AxPoint& a, const AxPoint& b) {
  return {std::min(a[0], b[0]), std::min(a[1], b[1]), std::min(a[2], b[2])};
}
KOKKOS_INLINE_FUNCTION AxPoint pmax(const AxPoint& a, const AxPoint& b) {
  return {std::max(a[0], b[0]), std::max(a[1], b[1]), std::max(a[2], b[2])};
}

// The mesh as ArborX sees it: views over the bench's own arrays (no copy).
struct AxMesh {
  Kokkos::View<AxPoint*, Mem, Kokkos::MemoryTraits<Kokkos::Unmanaged>> points;  // non-const: ArborX's geometry traits want AxPoint
  Borrowed<Tri> tris;
  Borrowed<Seg> edges;
};

}  // namespace peer

// ---- Predicates, computed on the fly from the vertices (as minkq derives its query shapes) --
namespace peer {
template <bool kExact>
struct VertexBoxQueries {  // intersects(Box(v +- r)), data = v
  decltype(AxMesh::points) points;
  float r;
};
template <bool kExact>
struct EdgeBoxQueries {  // intersects(box of e grown by r), data = e
  AxMesh mesh;
  float r;
};
}  // namespace peer

template <bool kExact>
struct ArborX::AccessTraits<peer::VertexBoxQueries<kExact>> {
  using memory_space = peer::Mem;
  static KOKKOS_FUNCTION std::size_t size(const peer::VertexBoxQueries<kExact>& q) { return q.points.extent(0); }
  static KOKKOS_FUNCTION auto get(const peer::VertexBoxQueries<kExact>& q, std::size_t i) {
    const peer::AxPoint& p = q.points(i);
    return ArborX::attach(ArborX::intersects(peer::grown<kExact>(p, p, q.r)), int(i));
  }
};
template <bool kExact>
struct ArborX::AccessTraits<peer::EdgeBoxQueries<kExact>> {
  using memory_space = peer::Mem;
  static KOKKOS_FUNCTION std::size_t size(const peer::EdgeBoxQueries<kExact>& q) { return q.mesh.edges.extent(0); }
  static KOKKOS_FUNCTION auto get(const peer::EdgeBoxQueries<kExact>& q, std::size_t i) {
    const peer::Seg s = q.mesh.edges(i);
    const peer::AxPoint &a = q.mesh.points(s.v[0]), &b = q.mesh.points(s.v[1]);
    return ArborX::attach(ArborX::intersects(peer::grown<kExact>(peer::pmin(a, b), peer::pmax(a, b), q.r)), int(i));
  }
};

namespace peer {

// ---- Callbacks ------------------------------------------------------------------------------
// Counts go to one slot per query: ArborX traverses each predicate (and, in the half traversal,
// each leaf) on one thread, so the slots need no atomics.

KOKKOS_INLINE_FUNCTION bool incident(const Tri& t, int v) { return t.v[0] == v || t.v[1] == v || t.v[2] == v; }
KOKKOS_INLINE_FUNCTION bool share_vertex(const Seg& a, const Seg& b) {
  return a.v[0] == b.v[0] || a.v[0] == b.v[1] || a.v[1] == b.v[0] || a.v[1] == b.v[1];
}

struct VtCount {
  Borrowed<Tri> tris;
  View<int> counts;
  template <class Predicate>
  KOKKOS_FUNCTION void operator()(const Predicate& p, const AxValue& t) const {
    const int v = ArborX::getData(p);
    if (!incident(tris(t.index), v)) ++counts(v);
  }
};
struct VtStore {  // CSR output: values of query v are its triangles
  Borrowed<Tri> tris;
  template <class Predicate, class Out>
  KOKKOS_FUNCTION void operator()(const Predicate& p, const AxValue& t, const Out& out) const {
    if (!incident(tris(t.index), ArborX::getData(p))) out(t.index);
  }
};
// Public API EE: every pair is met from both edges; keep f > e (minkq's (e, f) with e < f).
struct EeCount {
  Borrowed<Seg> edges;
  View<int> counts;
  template <class Predicate>
  KOKKOS_FUNCTION void operator()(const Predicate& p, const AxValue& f) const {
    const int e = ArborX::getData(p);
    if (f.index > e && !share_vertex(edges(e), edges(f.index))) ++counts(e);
  }
};
struct EeStore {
  Borrowed<Seg> edges;
  template <class Predicate, class Out>
  KOKKOS_FUNCTION void operator()(const Predicate& p, const AxValue& f, const Out& out) const {
    const int e = ArborX::getData(p);
    if (f.index > e && !share_vertex(edges(e), edges(f.index))) out(f.index);
  }
};
// Half traversal: the predicate of a leaf is its box grown by r; each unordered pair is met once,
// from the leaf that comes first in the tree's order.
struct GrownBoxGetter {
  float r;
  KOKKOS_FUNCTION auto operator()(const AxValue& v) const {
    return ArborX::intersects(grown<true>(v.value.minCorner(), v.value.maxCorner(), r));
  }
};
struct HalfCount {
  Borrowed<Seg> edges;
  View<int> counts;
  KOKKOS_FUNCTION void operator()(const AxValue& a, const AxValue& b) const {
    if (!share_vertex(edges(a.index), edges(b.index))) ++counts(a.index);
  }
};
struct HalfFill {  // second pass: values[cursor[a]++] = b, cursor starting at a's offset
  Borrowed<Seg> edges;
  View<int> cursor, values;
  KOKKOS_FUNCTION void operator()(const AxValue& a, const AxValue& b) const {
    if (!share_vertex(edges(a.index), edges(b.index))) values(cursor(a.index)++) = b.index;
  }
};

// ---- ArborX side of one scene (arborx_peer.cpp) ---------------------------------------------

View<AxBox> triangle_boxes(const Exec& space, const AxMesh& m);
View<AxBox> edge_boxes(const Exec& space, const AxMesh& m);
AxBvh build_tree(const Exec& space, const View<AxBox>& boxes);
uint64_t sum(const Exec& space, const View<int>& counts);
int max_count(const Exec& space, const View<int>& offsets);
// CSR (offsets, values) -> sorted pairs (query, value), or (min, max) for symmetric output.
mb::PairSet csr_set(const View<int>& offsets, const View<int>& values, bool symmetric);
// EE by the half traversal, stored: count per leaf, scan, fill. Leaves offsets/values in CSR.
void half_traversal_store(const Exec& space, const AxBvh& tree, const AxMesh& m, float r, View<int>& counts,
                          View<int>& offsets, View<int>& values);

}  // namespace peer
