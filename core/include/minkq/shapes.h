// Query shapes: each supplies overlaps(node_box); traversal (bvh.h) is written once for all.
// Finer modes are the coarser test AND a tighter one, so the candidate sets nest by
// construction in float: capsule_exact <= capsule_ray <= box, sphere <= box.
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

struct BoxShape {
  Box box;
  MINKQ_HD static BoxShape from(const QueryGeometry& q) { return {padded_segment_box(q.p0, q.p1, q.r)}; }
  MINKQ_HD bool overlaps(const Box& b) const { return boxes_overlap(box, b); }
};

struct SphereShape {  // p0 is the centre; p1 is ignored
  Box box;
  Vec3 centre;
  float r2_upper;
  MINKQ_HD static SphereShape from(const QueryGeometry& q) {
    return {padded_segment_box(q.p0, q.p0, q.r), q.p0, square_upper_bound(q.r)};
  }
  MINKQ_HD bool overlaps(const Box& b) const {
    return boxes_overlap(box, b) && sphere_overlaps_box(centre, r2_upper, b);
  }
};

struct CapsuleRayShape {
  Box box;
  Vec3 p0, d;
  float r;
  MINKQ_HD static CapsuleRayShape from(const QueryGeometry& q) {
    return {padded_segment_box(q.p0, q.p1, q.r), q.p0, q.p1 - q.p0, q.r};
  }
  MINKQ_HD bool overlaps(const Box& b) const {
    return boxes_overlap(box, b) && capsule_ray_overlaps_box(p0, d, r, b);
  }
};

struct CapsuleExactShape {
  CapsuleRayShape ray;
  Vec3 p1;
  float threshold2;
  MINKQ_HD static CapsuleExactShape from(const QueryGeometry& q) {
    return {CapsuleRayShape::from(q), q.p1, capsule_exact_threshold2(q.p0, q.p1, q.r)};
  }
  MINKQ_HD bool overlaps(const Box& b) const {
    return ray.overlaps(b) && segment_box_distance2(ray.p0, p1, b) <= threshold2;
  }
};

}  // namespace minkq
