// Query shapes: what a query tests a box with. Every shape is one of the C API's node-test
// modes (Mode) over a QueryGeometry (a segment grown by r, a point when p0 == p1, or a box),
// and the one traversal (traversal.h) is written against this contract alone:
//
//   static Shape from(const QueryGeometry&)  the shape of one query.
//   bool may_overlap(const Box& b)           the test of internal-node and leaf-range boxes:
//                                            monotone under box inclusion (if it rejects b,
//                                            it rejects every box inside b) and true wherever
//                                            overlaps is true.
//   bool overlaps(const Box& b)              the mode's whole test of a primitive's box: a
//                                            primitive is a candidate exactly when it holds.
//   bool finer(const Box& b)                 what overlaps adds to may_overlap: overlaps(b) ==
//                                            may_overlap(b) && finer(b). A single-primitive
//                                            leaf range, whose box already passed may_overlap,
//                                            runs only this.
//   unsigned overlaps_group(const BoxGroup& g, unsigned lanes)
//                                            overlaps on the boxes of g in the lanes asked for,
//                                            as a bit mask: bit k set iff lane k is asked for
//                                            and overlaps(group_box(g, k)). Every verdict must
//                                            be overlaps' own, bit for bit.
//
// With these, traversal reports exactly the primitives whose box the shape overlaps, whatever
// the tree (tests/test_queries.cpp checks it against the test applied to every primitive).
// Each finer mode is the box test AND a tighter one (BoxThenFiner), so the candidate sets nest
// by construction in float: capsule_exact <= capsule_ray <= box, sphere <= box. Inside the
// tree every shape uses its box test: the finer tests run only on primitive boxes, where they
// cost less than the candidates they remove (docs/design-notes.md links the study).
#pragma once

#include <utility>

#include "minkq/detect.h"
#include "minkq/predicates.h"
#include "minkq/simd.h"

namespace minkq {

// Node-test modes, numbered as the C API's minkq_mode.
enum class Mode : int { kBox = 0, kSphere = 1, kCapsuleRay = 2, kCapsuleExact = 3 };

// A query is a segment p0-p1 (p0 == p1 for points) grown by radius r, or a plain box.
struct QueryGeometry {
  Vec3 p0, p1;
  float r;
};

// The contract above, member by member, checked where a shape is used (traverse_groups in
// traversal.h; walk, which tests node boxes only, checks may_overlap). What each test decides
// is the tests' to check (test_bvh.cpp, test_queries.cpp); tests/test_contracts.cpp checks the
// shapes here fulfil it.
namespace shape_contract {
template <class S>
using From = decltype(S::from(std::declval<const QueryGeometry&>()));
template <class S>
using MayOverlap = decltype(std::declval<const S&>().may_overlap(std::declval<const Box&>()));
template <class S>
using Overlaps = decltype(std::declval<const S&>().overlaps(std::declval<const Box&>()));
template <class S>
using Finer = decltype(std::declval<const S&>().finer(std::declval<const Box&>()));
template <class S>
using OverlapsGroup = decltype(std::declval<const S&>().overlaps_group(std::declval<const BoxGroup&>(), 0u));
template <class S>
constexpr bool kFrom = detected_as<S, From, S>;
template <class S>
constexpr bool kMayOverlap = detected_as<bool, MayOverlap, S>;
template <class S>
constexpr bool kOverlaps = detected_as<bool, Overlaps, S>;
template <class S>
constexpr bool kFiner = detected_as<bool, Finer, S>;
template <class S>
constexpr bool kOverlapsGroup = detected_as<unsigned, OverlapsGroup, S>;
}  // namespace shape_contract

template <class S>
constexpr bool is_shape = shape_contract::kFrom<S> && shape_contract::kMayOverlap<S> && shape_contract::kOverlaps<S> &&
                          shape_contract::kFiner<S> && shape_contract::kOverlapsGroup<S>;

// Instantiated where a shape is used: one message for each member S lacks.
template <class S>
struct ShapeContract {
  static_assert(shape_contract::kFrom<S>, "Shape: needs static Shape from(const QueryGeometry&)");
  static_assert(shape_contract::kMayOverlap<S>, "Shape: needs bool may_overlap(const Box&) const");
  static_assert(shape_contract::kOverlaps<S>, "Shape: needs bool overlaps(const Box&) const");
  static_assert(shape_contract::kFiner<S>, "Shape: needs bool finer(const Box&) const");
  static_assert(shape_contract::kOverlapsGroup<S>,
                "Shape: needs unsigned overlaps_group(const BoxGroup&, unsigned lanes) const");
  static constexpr bool value = is_shape<S>;
};

// overlaps box by box over the lanes asked for: the shapes' leaf test in CUDA code (a thread
// reads only the boxes it tests).
template <class Shape>
MINKQ_HD unsigned overlaps_each(const Shape& shape, const BoxGroup& g, unsigned lanes) {
  return lanes_where(lanes, [&](int k) { return shape.overlaps(group_box(g, k)); });
}

#if !defined(__CUDACC__)
// The box mode's test (box_gap_within) on a leaf group's four boxes in 4-float lanes, the
// query's faces and radius broadcast once: a scan makes one per leaf range (group_test below),
// so that its loop only loads and compares. The scalar test's subtractions and comparisons,
// lane by lane.
struct BoxLanes {
  simd4::F4 lo[3], hi[3], r;
  static BoxLanes of(Vec3 lo, Vec3 hi, float r) {
    using simd4::splat;
    return {{splat(lo.x), splat(lo.y), splat(lo.z)}, {splat(hi.x), splat(hi.y), splat(hi.z)}, splat(r)};
  }
  // The bits k of `lanes` where box k of g passes.
  unsigned overlaps(const BoxGroup& g, unsigned lanes) const {
    using simd4::load;
    const simd4::M4 pass = (load(g.lo[0]) - hi[0] <= r) & (lo[0] - load(g.hi[0]) <= r) &
                           (load(g.lo[1]) - hi[1] <= r) & (lo[1] - load(g.hi[1]) <= r) &
                           (load(g.lo[2]) - hi[2] <= r) & (lo[2] - load(g.hi[2]) <= r);
    return lanes & simd4::mask_bits(pass);
  }
};
#endif

// The box mode: the query's own box (segment p0-p1, or the user box lo-hi with r = 0) within r
// of b in every axis, as box_gap_within decides it: symmetric, so an EE pair needs it one way
// only, and exact for boxes (r = 0).
struct BoxShape {
  Vec3 lo, hi;
  float r;
  MINKQ_HD static BoxShape from(const QueryGeometry& q) { return {vmin(q.p0, q.p1), vmax(q.p0, q.p1), q.r}; }
  MINKQ_HD bool overlaps(const Box& b) const { return box_gap_within(lo, hi, r, b); }
  MINKQ_HD bool may_overlap(const Box& b) const { return overlaps(b); }
  MINKQ_HD bool finer(const Box&) const { return true; }  // the box test is the whole test
  MINKQ_HD const BoxShape& box_test() const { return *this; }  // as the finer modes name theirs
  // The bits k of `lanes` where box k of the group passes overlaps. On the host (g++) all four
  // in 4-float vector lanes; in CUDA code only the lanes asked for, box by box (a thread reads
  // no more than it tests). The same float subtractions and comparisons either way.
  MINKQ_HD unsigned overlaps_group(const BoxGroup& g, unsigned lanes) const {
#if defined(__CUDACC__)
    return overlaps_each(*this, g, lanes);
#else
    return BoxLanes::of(lo, hi, r).overlaps(g, lanes);
#endif
  }
};

// Whether Shape is the box mode, whose finer test is no test: a filter that would apply it the
// other way round (EE, VV) has nothing to do.
template <class Shape>
struct IsBoxShape {
  static constexpr bool value = false;
};
template <>
struct IsBoxShape<BoxShape> {
  static constexpr bool value = true;
};
template <class Shape>
MINKQ_HD constexpr bool is_box_shape() {
  return IsBoxShape<Shape>::value;
}

// What a leaf scan tests a leaf group with: group_test(shape).overlaps_group(g, lanes), which
// is shape.overlaps_group(g, lanes). On the host, for the library's shapes (those with a
// box_test()), it holds the shape's box test with the query broadcast (BoxLanes) and runs the
// shape's finer_group on what passes; CUDA code, and other shapes, test with the shape itself.
#if defined(__CUDACC__)
template <class Shape>
MINKQ_HD const Shape& group_test(const Shape& shape) {
  return shape;
}
#else
// The lanes of `hits` (boxes of g that passed the shape's box test) that its finer test keeps.
template <class Shape>
unsigned finer_hits(const Shape& shape, const BoxGroup& g, unsigned hits) {
  if constexpr (is_box_shape<Shape>()) return hits; else return shape.finer_group(g, hits);
}
template <class Shape>
struct GroupTest {
  BoxLanes box;
  const Shape& shape;
  unsigned overlaps_group(const BoxGroup& g, unsigned lanes) const { return finer_hits(shape, g, box.overlaps(g, lanes)); }
};
namespace shape_contract {
template <class S>
using BoxTest = decltype(std::declval<const S&>().box_test());
}  // namespace shape_contract
template <class Shape>
decltype(auto) group_test(const Shape& shape) {
  if constexpr (is_detected<shape_contract::BoxTest, Shape>) {
    const BoxShape& b = shape.box_test();
    return GroupTest<Shape>{BoxLanes::of(b.lo, b.hi, b.r), shape};
  } else {
    return (shape);
  }
}
#endif

// What a finer mode's shape (Shape) derives from its two tests: box_test(), its BoxShape, and
// finer(b) with, on the host, finer_group(g, lanes), the same on the lanes asked for. On the
// host a leaf group gets the box test and the finer test four boxes at once; CUDA code tests
// box by box (a thread reads only the boxes it tests), with the same verdicts.
template <class Shape>
struct BoxThenFiner {
  MINKQ_HD bool overlaps(const Box& b) const { return shape().box_test().overlaps(b) && shape().finer(b); }
  MINKQ_HD bool may_overlap(const Box& b) const { return shape().box_test().overlaps(b); }
  MINKQ_HD unsigned overlaps_group(const BoxGroup& g, unsigned lanes) const {
#if defined(__CUDACC__)
    return overlaps_each(shape(), g, lanes);
#else
    return group_test(shape()).overlaps_group(g, lanes);
#endif
  }

 private:
  MINKQ_HD const Shape& shape() const { return static_cast<const Shape&>(*this); }
};

#if !defined(__CUDACC__)
// sphere_overlaps_box(p, r2_upper, .) on the lanes asked for: point_box_distance2 <= r2_upper,
// lane by lane.
inline unsigned sphere_finer_group(Vec3 p, float r2_upper, const BoxGroup& g, unsigned lanes) {
  if (lanes == 0) return 0;
  simd4::F4 d2 = simd4::splat(0.0f);
  for (int axis = 0; axis < 3; ++axis) {
    const float pk = component(p, axis);
    const simd4::F4 gap =
        simd4::max_num(simd4::max_num(simd4::load(g.lo[axis]) - pk, pk - simd4::load(g.hi[axis])), simd4::splat(0.0f));
    d2 = axis == 0 ? gap * gap : d2 + gap * gap;
  }
  return lanes & simd4::mask_bits(d2 <= r2_upper);
}
#endif

struct SphereShape : BoxThenFiner<SphereShape> {  // p0 is the centre; p1 is ignored
  BoxShape box;                                   // of the centre: lo == hi == centre
  float r2_upper;
  MINKQ_HD static SphereShape from(const QueryGeometry& q) {
    return {{}, BoxShape::from({q.p0, q.p0, q.r}), square_upper_bound(q.r)};
  }
  MINKQ_HD const BoxShape& box_test() const { return box; }
  MINKQ_HD bool finer(const Box& b) const { return sphere_overlaps_box(box.lo, r2_upper, b); }
#if !defined(__CUDACC__)
  unsigned finer_group(const BoxGroup& g, unsigned lanes) const { return sphere_finer_group(box.lo, r2_upper, g, lanes); }
#endif
};

struct CapsuleRayShape : BoxThenFiner<CapsuleRayShape> {
  BoxShape box;
  Vec3 p0, d;
  // The box test alone decides: where d overflowed (the segment spans more than FLT_MAX along an
  // axis) the slab test cannot run (fuzz/RESULTS.md, bug 6), and for a point (p0 == p1) the
  // capsule is the box mode's grown point, so a point gets BoxShape's verdicts exactly (a still
  // vertex of a swept scene gives the static pairs; bug 7).
  bool box_decides;
  MINKQ_HD static CapsuleRayShape from(const QueryGeometry& q) {
    const Vec3 d = q.p1 - q.p0;
    const bool unbounded = !(fabsf(d.x) <= FLT_MAX && fabsf(d.y) <= FLT_MAX && fabsf(d.z) <= FLT_MAX);
    const bool point = q.p0.x == q.p1.x && q.p0.y == q.p1.y && q.p0.z == q.p1.z;
    return {{}, BoxShape::from(q), q.p0, d, unbounded || point};
  }
  MINKQ_HD const BoxShape& box_test() const { return box; }
  MINKQ_HD bool finer(const Box& b) const { return box_decides || capsule_ray_overlaps_box(p0, d, box.r, b); }
#if !defined(__CUDACC__)
  // capsule_ray_overlaps_box on the lanes asked for. The swap of the slab's ends is the
  // scalar test's (t0 > t1), a NaN end (inf - inf in the widening) is dropped by
  // max_num / min_num as there, and an axis with d == 0 is the scalar test's early rejection.
  unsigned finer_group(const BoxGroup& g, unsigned lanes) const {
    using simd4::F4;
    using simd4::M4;
    if (lanes == 0 || box_decides) return lanes;
    const float r = box.r;
    F4 t_near = simd4::splat(0.0f), t_far = simd4::splat(1.0f);
    M4 inside = t_near == t_near;  // every lane
    for (int axis = 0; axis < 3; ++axis) {
      const F4 lo = simd4::next_down(simd4::load(g.lo[axis]) - r);
      const F4 hi = simd4::next_up(simd4::load(g.hi[axis]) + r);
      const float o = component(p0, axis), dk = component(d, axis);
      if (dk == 0.0f) {
        inside &= ~((o < lo) | (o > hi));
        continue;
      }
      const F4 a = (lo - o) / dk, b = (hi - o) / dk;
      const M4 swap = a > b;
      F4 t0 = swap ? b : a, t1 = swap ? a : b;
      t0 = t0 - simd4::abs(t0) * kSlabWidening - FLT_MIN;
      t1 = t1 + simd4::abs(t1) * kSlabWidening + FLT_MIN;
      t_near = simd4::max_num(t_near, t0);
      t_far = simd4::min_num(t_far, t1);
    }
    return lanes & simd4::mask_bits(inside & (t_near <= t_far));
  }
#endif
};

// A point (p0 == p1) takes SphereShape's test, threshold and all, so that its verdicts are the
// sphere mode's exactly (a still vertex of a swept scene gives the static sphere pairs; the
// segment distance's threshold keeps more slack; fuzz/RESULTS.md, bug 7).
struct CapsuleExactShape : BoxThenFiner<CapsuleExactShape> {
  CapsuleRayShape ray;
  Vec3 p1;
  float threshold2;  // for segment_box_distance2, or a point's r2_upper
  bool point;
  MINKQ_HD static CapsuleExactShape from(const QueryGeometry& q) {
    const bool point = q.p0.x == q.p1.x && q.p0.y == q.p1.y && q.p0.z == q.p1.z;
    return {{}, CapsuleRayShape::from(q), q.p1,
            point ? square_upper_bound(q.r) : capsule_exact_threshold2(q.p0, q.p1, q.r), point};
  }
  MINKQ_HD const BoxShape& box_test() const { return ray.box; }
  MINKQ_HD bool finer(const Box& b) const {
    if (point) return sphere_overlaps_box(ray.p0, threshold2, b);
    return ray.finer(b) && segment_box_distance2(ray.p0, p1, b) <= threshold2;
  }
#if !defined(__CUDACC__)
  // The ray test on four lanes, then the segment-box distance lane by lane (it branches).
  unsigned finer_group(const BoxGroup& g, unsigned lanes) const {
    if (point) return sphere_finer_group(ray.p0, threshold2, g, lanes);
    return lanes_where(ray.finer_group(g, lanes), [&](int k) {
      return segment_box_distance2(ray.p0, p1, group_box(g, k)) <= threshold2;
    });
  }
#endif
};

#if !defined(__CUDACC__)
// Every mode's leaf scan broadcasts its query once per range (group_test's BoxLanes path).
static_assert(std::is_same<decltype(group_test(std::declval<const BoxShape&>())), GroupTest<BoxShape>>::value &&
                  std::is_same<decltype(group_test(std::declval<const SphereShape&>())), GroupTest<SphereShape>>::value &&
                  std::is_same<decltype(group_test(std::declval<const CapsuleRayShape&>())),
                               GroupTest<CapsuleRayShape>>::value &&
                  std::is_same<decltype(group_test(std::declval<const CapsuleExactShape&>())),
                               GroupTest<CapsuleExactShape>>::value,
              "a mode's leaf scan lost its broadcast box test");
#endif

}  // namespace minkq
