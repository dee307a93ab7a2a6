// The traversal variants the library replaced, kept for the ablation study
// (minkq_ablation, bench/results/ablation.md) to measure the kept habits against: query
// sources that meet each EE pair twice or run in edge id order, the r-padded box test, and
// shapes that test boxes one at a time or run the mode's finer test at every node.
#pragma once

#include "minkq/queries.h"
#include "studies/box_tests.h"

namespace minkq::bench {

// The EE source before issue 8: query i is edge i over the whole tree; pairs with f <= e are
// dropped at the leaf, so each unordered pair is reached twice and kept once.
// (The whole filter pair by pair: accept_rest, nothing dropped four at a time.)
struct EdgeEdgeTwice {
  EdgeEdgeQueries base;
  QueryTarget target(int32_t i) const { return {i, -1}; }
  QueryGeometry geometry(QueryTarget t) const { return base.geometry(t.q); }
  unsigned dropped_lanes(QueryTarget, int64_t, unsigned, const int32_t*) const { return 0; }
  template <class Shape>
  bool tests_rest() const {
    return true;
  }
  template <class Shape>
  bool accept_rest(QueryTarget t, int32_t f, int64_t) const {
    const int32_t e = t.q;
    if (f <= e) return false;
    const Edge a = base.edges[e], b = base.edges[f];
    if ((base.filters & kDropIncident) && share_vertex(a, b)) return false;
    if (base.filters & kLeafExact)
      return segment_segment_within(base.vertices[a.v[0]], base.vertices[a.v[1]], base.vertices[b.v[0]],
                                    base.vertices[b.v[1]], base.r);
    return true;
  }
  Pair pair(int32_t e, int32_t f) const { return {e, f}; }
};

// Each pair once, queries in edge id order: query i is edge i, pruned at its own leaf position.
struct EdgeEdgeOnceByIdOrder {
  EdgeEdgeQueries base;
  const int32_t* position;  // sorted leaf position of each edge
  QueryTarget target(int32_t i) const { return {i, position[i]}; }
  QueryGeometry geometry(QueryTarget t) const { return base.geometry(t.q); }
  unsigned dropped_lanes(QueryTarget, int64_t, unsigned, const int32_t*) const { return 0; }
  template <class Shape>
  bool tests_rest() const {
    return true;
  }
  template <class Shape>
  bool accept_rest(QueryTarget t, int32_t f, int64_t) const { return base.accept<Shape>(t.q, f); }
  Pair pair(int32_t e, int32_t f) const { return base.pair(e, f); }
};

// The box test before box_gap_within: the query's box padded by r, rounded outward, against
// each box. Not symmetric, so an EE pair also needs it the other way round (the leaf filter
// does that for every shape but the library's BoxShape).
struct PaddedBoxShape {
  Box box;
  static PaddedBoxShape from(const QueryGeometry& q) { return {padded_segment_box(q.p0, q.p1, q.r)}; }
  bool overlaps(const Box& b) const { return boxes_overlap(box, b); }
  bool may_overlap(const Box& b) const { return boxes_overlap(box, b); }
  // Not symmetric: the other edge's padded box against this box is the reverse test.
  bool finer(const Box& b) const { return boxes_overlap(box, b); }
  unsigned overlaps_group(const BoxGroup& g, unsigned lanes) const { return overlaps_each(*this, g, lanes); }
};

// A shape whose box tests run box by box: at leaf groups one box at a time (may_overlap_each)
// instead of four at once, and, with kFineAtEveryNode, the mode's own test (overlaps) at every
// node instead of only at primitive boxes. Same pairs as Shape.
template <class Shape, bool kFineAtEveryNode>
struct BoxByBox {
  Shape shape;
  static BoxByBox from(const QueryGeometry& q) { return {Shape::from(q)}; }
  bool overlaps(const Box& b) const { return shape.overlaps(b); }
  bool may_overlap(const Box& b) const { return kFineAtEveryNode ? shape.overlaps(b) : shape.may_overlap(b); }
  bool finer(const Box& b) const { return shape.finer(b); }
  unsigned overlaps_group(const BoxGroup& g, unsigned lanes) const { return overlaps_each(*this, g, lanes); }
};
// The node tests before: the mode's own test at every node, not only at primitive boxes.
template <class Shape>
using FineAtEveryNode = BoxByBox<Shape, true>;
// The leaf scan before: each leaf box tested alone, against four at a time in vector lanes
// (overlaps_group; kept).
template <class Shape>
using LeafBoxByBox = BoxByBox<Shape, false>;
// The leaf scan between the two: the box test on four leaf boxes at once, then the mode's
// finer test box by box on those that passed (before the finer tests had vector lanes too).
template <class Shape>
struct FinerBoxByBox {
  Shape shape;
  static FinerBoxByBox from(const QueryGeometry& q) { return {Shape::from(q)}; }
  bool overlaps(const Box& b) const { return shape.overlaps(b); }
  bool may_overlap(const Box& b) const { return shape.may_overlap(b); }
  bool finer(const Box& b) const { return shape.finer(b); }
  unsigned overlaps_group(const BoxGroup& g, unsigned lanes) const {
    unsigned bits = may_overlap_group(shape, g, lanes);
    for (unsigned rest = bits; rest != 0; rest &= rest - 1u)
      if (!shape.finer(group_box(g, lowest_bit(rest)))) bits &= ~(1u << lowest_bit(rest));
    return bits;
  }
};

}  // namespace minkq::bench
