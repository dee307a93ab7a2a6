// Query shapes: each is a box test (BoxShape, its `box`) and finer(b), the test a finer mode
// adds to it: overlaps(b) = box.overlaps(b) && finer(b) is the mode's test, may_overlap(b) the
// box test alone, applied to internal and leaf-range boxes, and may_overlap_group(g, lanes)
// the box test on leaf boxes four at a time; traversal (bvh.h) is written once for all.
// Finer modes are the coarser test AND a tighter one, so the candidate sets nest by
// construction in float: capsule_exact <= capsule_ray <= box, sphere <= box.
// The finer tests run only on primitive boxes: on the cloth scenes they pruned 0-4% of the
// internal nodes the box test visits, at 2-5x its cost (bench/results/ablation.md), so inside
// the tree every shape uses its box test. The candidate set is the same either way: a
// primitive is a candidate when overlaps(its box), and may_overlap accepts every box that
// contains one overlaps accepts.
#pragma once

#include "minkq/predicates.h"

namespace minkq {

// Node-test modes, numbered as the C API's minkq_mode.
enum class Mode : int { kBox = 0, kSphere = 1, kCapsuleRay = 2, kCapsuleExact = 3 };

// A query is a segment p0-p1 (p0 == p1 for points) grown by radius r, or a plain box.
struct QueryGeometry {
  Vec3 p0, p1;
  float r;
};

// may_overlap box by box over the lanes asked for: BoxShape's lane test in CUDA code, and
// shapes without a lane test (bench studies).
template <class Shape>
MINKQ_HD unsigned may_overlap_each(const Shape& shape, const BoxGroup& g, unsigned lanes) {
  unsigned bits = 0;
  for (unsigned rest = lanes; rest != 0; rest &= rest - 1u) {
    const int k = lowest_bit(rest);
    bits |= unsigned(shape.may_overlap(group_box(g, k))) << k;
  }
  return bits;
}

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
  // The bits k of `lanes` where box k of the group passes overlaps. On the host (g++) all four
  // in 4-float vector lanes; in CUDA code only the lanes asked for, box by box (a thread reads
  // no more than it tests). The same float subtractions and comparisons either way.
  MINKQ_HD unsigned overlaps_group(const BoxGroup& g, unsigned lanes) const {
#if defined(__CUDACC__)
    return may_overlap_each(*this, g, lanes);  // may_overlap is overlaps here
#else
    typedef float Lanes __attribute__((vector_size(16)));
    typedef int32_t Masks __attribute__((vector_size(16)));
    Lanes v[6];
    memcpy(&v[0], g.lo[0], 16), memcpy(&v[1], g.lo[1], 16), memcpy(&v[2], g.lo[2], 16);
    memcpy(&v[3], g.hi[0], 16), memcpy(&v[4], g.hi[1], 16), memcpy(&v[5], g.hi[2], 16);
    const Masks pass = (v[0] - hi.x <= r) & (lo.x - v[3] <= r) & (v[1] - hi.y <= r) & (lo.y - v[4] <= r) &
                       (v[2] - hi.z <= r) & (lo.z - v[5] <= r);
    return lanes & (unsigned(pass[0] & 1) | unsigned(pass[1] & 1) << 1 | unsigned(pass[2] & 1) << 2 |
                    unsigned(pass[3] & 1) << 3);
#endif
  }
  MINKQ_HD unsigned may_overlap_group(const BoxGroup& g, unsigned lanes) const { return overlaps_group(g, lanes); }
};

struct SphereShape {  // p0 is the centre; p1 is ignored
  BoxShape box;       // of the centre: lo == hi == centre
  float r2_upper;
  MINKQ_HD static SphereShape from(const QueryGeometry& q) {
    return {BoxShape::from({q.p0, q.p0, q.r}), square_upper_bound(q.r)};
  }
  MINKQ_HD bool finer(const Box& b) const { return sphere_overlaps_box(box.lo, r2_upper, b); }
  MINKQ_HD bool overlaps(const Box& b) const { return box.overlaps(b) && finer(b); }
  MINKQ_HD bool may_overlap(const Box& b) const { return box.overlaps(b); }
  MINKQ_HD unsigned may_overlap_group(const BoxGroup& g, unsigned lanes) const { return box.overlaps_group(g, lanes); }
};

struct CapsuleRayShape {
  BoxShape box;
  Vec3 p0, d;
  MINKQ_HD static CapsuleRayShape from(const QueryGeometry& q) { return {BoxShape::from(q), q.p0, q.p1 - q.p0}; }
  MINKQ_HD bool finer(const Box& b) const { return capsule_ray_overlaps_box(p0, d, box.r, b); }
  MINKQ_HD bool overlaps(const Box& b) const { return box.overlaps(b) && finer(b); }
  MINKQ_HD bool may_overlap(const Box& b) const { return box.overlaps(b); }
  MINKQ_HD unsigned may_overlap_group(const BoxGroup& g, unsigned lanes) const { return box.overlaps_group(g, lanes); }
};

struct CapsuleExactShape {
  CapsuleRayShape ray;
  Vec3 p1;
  float threshold2;
  MINKQ_HD static CapsuleExactShape from(const QueryGeometry& q) {
    return {CapsuleRayShape::from(q), q.p1, capsule_exact_threshold2(q.p0, q.p1, q.r)};
  }
  MINKQ_HD bool finer(const Box& b) const {
    return ray.finer(b) && segment_box_distance2(ray.p0, p1, b) <= threshold2;
  }
  MINKQ_HD bool overlaps(const Box& b) const { return ray.box.overlaps(b) && finer(b); }
  MINKQ_HD bool may_overlap(const Box& b) const { return ray.box.overlaps(b); }
  MINKQ_HD unsigned may_overlap_group(const BoxGroup& g, unsigned lanes) const {
    return ray.box.overlaps_group(g, lanes);
  }
};

}  // namespace minkq
