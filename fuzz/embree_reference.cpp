// The Embree reference (see embree_reference.h and fuzz/README.md).
#include "embree_reference.h"

#include <cstdio>
#include <cstdlib>
#include <functional>
#include <mutex>
#include <stdexcept>

namespace minkq::fuzz {
namespace {

void check_device(RTCDevice device, const char* what) {
  const RTCError error = rtcGetDeviceError(device);
  if (error != RTC_ERROR_NONE) {
    std::fprintf(stderr, "embree error %d after %s\n", int(error), what);
    std::abort();  // a broken reference must never pass for agreement
  }
}

// One float step outward on every side: Embree's culling then contains minkq's closed boxes
// whatever Embree does with touching faces (its overlap test is closed, but this keeps the
// argument independent of that detail).
Box widened(const Box& b) {
  return {{next_down(b.lo.x), next_down(b.lo.y), next_down(b.lo.z)},
          {next_up(b.hi.x), next_up(b.hi.y), next_up(b.hi.z)}};
}

// Collects decided pairs from Embree callbacks, which may run on several threads at once.
struct Collector {
  std::mutex mutex;
  std::function<void(int32_t, int32_t)> decide;  // called under the mutex
  void operator()(int32_t q, int32_t p) {
    std::lock_guard<std::mutex> lock(mutex);
    decide(q, p);
  }
};

void collide_callback(void* user, RTCCollision* collisions, unsigned int count) {
  Collector& collector = *static_cast<Collector*>(user);
  for (unsigned int i = 0; i < count; ++i) collector(int32_t(collisions[i].primID0), int32_t(collisions[i].primID1));
}

struct PointQueryUser {
  Collector* collector;
  int32_t query;
};

bool point_query_callback(RTCPointQueryFunctionArguments* args) {
  const PointQueryUser& user = *static_cast<const PointQueryUser*>(args->userPtr);
  (*user.collector)(user.query, int32_t(args->primID));
  return false;  // the radius is never shrunk
}

void finish(Pairs& pairs) {
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());  // Embree may repeat a pair; minkq may not
}

}  // namespace

// A scene holding one user geometry whose primitive i has bounds boxes[i] (already widened).
struct EmbreeReference::BoxList {
  RTCScene scene = nullptr;
  RTCGeometry geometry = nullptr;
  std::vector<Box> boxes;

  static void bounds(const RTCBoundsFunctionArguments* args) {
    const BoxList& list = *static_cast<const BoxList*>(args->geometryUserPtr);
    const Box& b = list.boxes[args->primID];
    args->bounds_o->lower_x = b.lo.x;
    args->bounds_o->lower_y = b.lo.y;
    args->bounds_o->lower_z = b.lo.z;
    args->bounds_o->upper_x = b.hi.x;
    args->bounds_o->upper_y = b.hi.y;
    args->bounds_o->upper_z = b.hi.z;
  }

  BoxList(RTCDevice device, std::vector<Box> list) : boxes(std::move(list)) {
    scene = rtcNewScene(device);
    // MEDIUM: HIGH uses spatial splits, which can report one primitive twice.
    rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_MEDIUM);
    geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryBuildQuality(geometry, RTC_BUILD_QUALITY_MEDIUM);
    rtcSetGeometryUserPrimitiveCount(geometry, unsigned(boxes.size()));
    rtcSetGeometryUserData(geometry, this);
    rtcSetGeometryBoundsFunction(geometry, &BoxList::bounds, this);
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(scene, geometry);
    rtcCommitScene(scene);
    check_device(device, "building a user-geometry scene");
  }
  // New boxes for the same primitives: commit the geometry, then the scene (Embree's refit).
  void update(RTCDevice device, std::vector<Box> list) {
    boxes = std::move(list);
    rtcCommitGeometry(geometry);
    rtcCommitScene(scene);
    check_device(device, "recommitting a user-geometry scene");
  }
  ~BoxList() {
    rtcReleaseGeometry(geometry);
    rtcReleaseScene(scene);
  }
  BoxList(const BoxList&) = delete;
  BoxList& operator=(const BoxList&) = delete;
};

namespace {

using BoxList = EmbreeReference::BoxList;

// Builds a BoxList, or on a refit updates the previous one (same primitive count).
void prepare(RTCDevice device, std::unique_ptr<BoxList>& slot, std::vector<Box> boxes, bool moved) {
  for (Box& b : boxes) b = widened(b);
  if (moved && slot && slot->boxes.size() == boxes.size()) {
    slot->update(device, std::move(boxes));
  } else {
    slot.reset();
    if (!boxes.empty()) slot = std::make_unique<BoxList>(device, std::move(boxes));
  }
}

// rtcCollide of a query scene (padded query boxes) with a primitive scene: Embree reports
// every pair of leaves whose node boxes overlap; the callback decides.
void collide(RTCDevice device, BoxList* queries, BoxList* prims, Collector& collector) {
  if (!queries || !prims) return;
  rtcCollide(queries->scene, prims->scene, &collide_callback, &collector);
  check_device(device, "rtcCollide");
}

// rtcPointQuery of every query point with the pruning radius; the callback decides.
void point_queries(RTCDevice device, BoxList* prims, const std::vector<Vec3>& points, float r, Collector& collector) {
  if (!prims) return;
  const float radius = EmbreeReference::pruning_radius(r);
  for (int32_t q = 0; q < int32_t(points.size()); ++q) {
    RTCPointQuery query;  // fields set by name: the documented order differs between pages
    query.x = points[q].x;
    query.y = points[q].y;
    query.z = points[q].z;
    query.time = 0.0f;
    query.radius = radius;
    RTCPointQueryContext context;
    rtcInitPointQueryContext(&context);
    PointQueryUser user{&collector, q};
    rtcPointQuery(prims->scene, &query, &context, &point_query_callback, &user);
  }
  check_device(device, "rtcPointQuery");
}

template <class Queries>
std::vector<Box> padded_query_boxes(const Queries& queries, int32_t count) {
  std::vector<Box> boxes(size_t(std::max(count, 0)));
  for (int32_t q = 0; q < count; ++q) {
    const QueryGeometry g = queries.geometry(q);
    boxes[q] = box_gap_bound(vmin(g.p0, g.p1), vmax(g.p0, g.p1), g.r);  // holds every box the box test accepts
  }
  return boxes;
}

template <class Boxes>
std::vector<Box> primitive_boxes(const Boxes& of, int32_t count) {
  std::vector<Box> boxes(size_t(std::max(count, 0)));
  for (int32_t p = 0; p < count; ++p) boxes[p] = of(p);
  return boxes;
}

}  // namespace

EmbreeReference::EmbreeReference() {
  device_ = rtcNewDevice("isa=sse2");
  if (!device_) {
    std::fprintf(stderr, "rtcNewDevice failed (error %d)\n", int(rtcGetDeviceError(nullptr)));
    std::abort();
  }
}

EmbreeReference::~EmbreeReference() {
  reset();
  rtcReleaseDevice(device_);
}

void EmbreeReference::reset() {
  triangles_.reset();
  edges_.reset();
  vertex_queries_.reset();
  edge_queries_.reset();
  user_boxes_.reset();
  user_queries_.reset();
}

float EmbreeReference::pruning_radius(float r) {
  // Embree's node test is vX^2 + vY^2 + vZ^2 <= radius^2 in float (vX = clamp(p, lo, hi) - p,
  // exact or rounded relative to itself): a few u of relative error, plus underflow. minkq's
  // sphere test accepts up to r * (1 + 2^-17) plus ~1.5e-22 from underflow; 2^-8 relative and
  // 2^-60 (~8.7e-19) absolute cover both by orders of magnitude. A larger radius only makes
  // Embree call back for more pairs, which the callback then decides.
  return next_up(r * 1.00390625f + 8.67361737988403547e-19f);
}

bool EmbreeReference::accepts(const std::vector<float>& coordinates, float r) const {
  // Padded query boxes reach |x| + r (+1 ulp); Embree's limit is about 1.8e18.
  for (float x : coordinates)
    if (!(std::fabs(x) + r < 1e17f)) return false;
  return r < 1e17f;
}

MeshSets EmbreeReference::mesh_sets(const MeshGeometry& g, float r, uint32_t filters, bool moved) {
  MeshSets sets;
  const VertexTriangleById vt = g.vt(r, filters), vt_leaf = g.vt(r, filters | kLeafExact);
  const EdgeEdgeById ee = g.ee(r, filters), ee_leaf = g.ee(r, filters | kLeafExact);
  const TriangleBoxes triangle_boxes = g.triangle_boxes();
  const EdgeBoxes edge_boxes = g.edge_boxes();

  prepare(device_, triangles_, primitive_boxes(triangle_boxes, g.nt()), moved);
  prepare(device_, edges_, primitive_boxes(edge_boxes, g.ne()), moved);
  prepare(device_, vertex_queries_, padded_query_boxes(vt, g.nv()), moved);
  prepare(device_, edge_queries_, padded_query_boxes(ee, g.ne()), moved);

  // VT box (and capsule_ray, the box test for points): rtcCollide of padded vertex boxes with
  // triangle boxes.
  Collector vt_boxes;
  vt_boxes.decide = [&](int32_t v, int32_t t) {
    if (!BoxShape::from(vt.geometry(v)).overlaps(triangle_boxes(t))) return;
    for (int mode : {MINKQ_MODE_BOX, MINKQ_MODE_CAPSULE_RAY}) {
      if (vt.accept<BoxShape>(v, t)) sets.vt[mode][0].push_back({v, t});
      if (vt_leaf.accept<BoxShape>(v, t)) sets.vt[mode][1].push_back({v, t});
    }
  };
  collide(device_, vertex_queries_.get(), triangles_.get(), vt_boxes);

  // VT sphere (and capsule_exact, the sphere test for points): rtcPointQuery around each vertex.
  Collector vt_spheres;
  vt_spheres.decide = [&](int32_t v, int32_t t) {
    if (!SphereShape::from(vt.geometry(v)).overlaps(triangle_boxes(t))) return;
    for (int mode : {MINKQ_MODE_SPHERE, MINKQ_MODE_CAPSULE_EXACT}) {
      if (vt.accept<SphereShape>(v, t)) sets.vt[mode][0].push_back({v, t});
      if (vt_leaf.accept<SphereShape>(v, t)) sets.vt[mode][1].push_back({v, t});
    }
  };
  point_queries(device_, triangles_.get(), g.vertices, r, vt_spheres);

  // EE box, capsule_ray, capsule_exact: rtcCollide of padded edge boxes with edge boxes; the
  // callback applies each mode's shape to the edge box, and the leaf filter (with the same
  // test the other way round) to pairs e < f.
  Collector ee_all;
  ee_all.decide = [&](int32_t e, int32_t f) {
    if (f <= e) return;
    const Box fb = edge_boxes(f);
    const QueryGeometry q = ee.geometry(e);
    auto add = [&](int mode, auto shape) {
      if (!decltype(shape)::from(q).overlaps(fb)) return;
      if (ee.accept<decltype(shape)>(e, f)) sets.ee[mode][0].push_back({e, f});
      if (ee_leaf.accept<decltype(shape)>(e, f)) sets.ee[mode][1].push_back({e, f});
    };
    add(MINKQ_MODE_BOX, BoxShape{});
    add(MINKQ_MODE_CAPSULE_RAY, CapsuleRayShape{});
    add(MINKQ_MODE_CAPSULE_EXACT, CapsuleExactShape{});
  };
  collide(device_, edge_queries_.get(), edges_.get(), ee_all);

  for (auto& by_leaf : sets.vt)
    for (Pairs& p : by_leaf) finish(p);
  for (auto& by_leaf : sets.ee)
    for (Pairs& p : by_leaf) finish(p);
  return sets;
}

SweptSets EmbreeReference::swept_sets(const MeshGeometry& g, float r, uint32_t filters, bool moved) {
  SweptSets sets;
  const VertexTriangleById vt = g.vt(r, filters);
  const EdgeEdgeById ee = g.ee(r, filters);
  const TriangleBoxes triangle_boxes = g.triangle_boxes();  // swept: over both positions
  const EdgeBoxes edge_boxes = g.edge_boxes();

  prepare(device_, triangles_, primitive_boxes(triangle_boxes, g.nt()), moved);
  prepare(device_, edges_, primitive_boxes(edge_boxes, g.ne()), moved);
  prepare(device_, vertex_queries_, padded_query_boxes(vt, g.nv()), moved);  // the paths' padded boxes
  prepare(device_, edge_queries_, padded_query_boxes(ee, g.ne()), moved);

  // VT, every mode a segment shape (the vertex's path): rtcCollide of the paths' padded boxes
  // with the triangles' swept boxes; every shape includes the padded-box overlap.
  Collector vt_all;
  vt_all.decide = [&](int32_t v, int32_t t) {
    const Box tb = triangle_boxes(t);
    const QueryGeometry q = vt.geometry(v);
    for (int mode = 0; mode < 4; ++mode)
      swept_vt_shape_of_mode(mode, [&](auto shape) {
        if (decltype(shape)::from(q).overlaps(tb) && vt.accept<decltype(shape)>(v, t)) sets.vt[mode].push_back({v, t});
      });
  };
  collide(device_, vertex_queries_.get(), triangles_.get(), vt_all);

  // EE box: the edges' padded swept boxes with their swept boxes, pairs e < f.
  Collector ee_box;
  ee_box.decide = [&](int32_t e, int32_t f) {
    if (f <= e) return;
    if (BoxShape::from(ee.geometry(e)).overlaps(edge_boxes(f)) && ee.accept<BoxShape>(e, f)) sets.ee_box.push_back({e, f});
  };
  collide(device_, edge_queries_.get(), edges_.get(), ee_box);

  for (Pairs& p : sets.vt) finish(p);
  finish(sets.ee_box);
  return sets;
}

BoxSets EmbreeReference::box_sets(const BoxGeometry& g, minkq_shape shape, float r, bool moved) {
  BoxSets sets;
  const UserById queries = g.queries(r);
  const GivenBoxes boxes = g.given_boxes();
  prepare(device_, user_boxes_, primitive_boxes(boxes, g.nb()), moved);
  if (shape == MINKQ_SHAPE_SPHERE) {
    // Box (= capsule_ray for points) by rtcCollide, sphere (= capsule_exact) by rtcPointQuery.
    prepare(device_, user_queries_, padded_query_boxes(queries, g.nq()), false);
    Collector by_box;
    by_box.decide = [&](int32_t q, int32_t b) {
      if (BoxShape::from(queries.geometry(q)).overlaps(boxes(b)))
        for (int mode : {MINKQ_MODE_BOX, MINKQ_MODE_CAPSULE_RAY}) sets.by_mode[mode].push_back({q, b});
    };
    collide(device_, user_queries_.get(), user_boxes_.get(), by_box);
    Collector by_sphere;
    by_sphere.decide = [&](int32_t q, int32_t b) {
      if (SphereShape::from(queries.geometry(q)).overlaps(boxes(b)))
        for (int mode : {MINKQ_MODE_SPHERE, MINKQ_MODE_CAPSULE_EXACT}) sets.by_mode[mode].push_back({q, b});
    };
    point_queries(device_, user_boxes_.get(), g.first, r, by_sphere);
  } else {
    // Capsules and boxes: rtcCollide of the padded query boxes with the user boxes.
    prepare(device_, user_queries_, padded_query_boxes(queries, g.nq()), false);
    Collector all;
    all.decide = [&](int32_t q, int32_t b) {
      const QueryGeometry geometry = queries.geometry(q);
      const Box& box = boxes(b);
      if (!BoxShape::from(geometry).overlaps(box)) return;
      sets.by_mode[MINKQ_MODE_BOX].push_back({q, b});
      if (shape != MINKQ_SHAPE_CAPSULE) return;
      if (CapsuleRayShape::from(geometry).overlaps(box)) sets.by_mode[MINKQ_MODE_CAPSULE_RAY].push_back({q, b});
      if (CapsuleExactShape::from(geometry).overlaps(box)) sets.by_mode[MINKQ_MODE_CAPSULE_EXACT].push_back({q, b});
    };
    collide(device_, user_queries_.get(), user_boxes_.get(), all);
  }
  for (Pairs& p : sets.by_mode) finish(p);
  return sets;
}

}  // namespace minkq::fuzz
