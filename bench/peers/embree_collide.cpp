#include "peers/embree_collide.h"

#include <embree3/rtcore.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_sort.h>

#include <stdexcept>
#include <string>

#include "minkq/predicates.h"
#include "peers/embree_errors.h"

namespace minkq::bench {
namespace {

struct CollideUser {
  const EmbreeBoxes* query;
  const EmbreeBoxes* tree;
  tbb::enumerable_thread_specific<std::vector<uint64_t>>* found;
};

void on_collisions(void* user_ptr, RTCCollision* collisions, unsigned int count) {
  const CollideUser& u = *static_cast<const CollideUser*>(user_ptr);
  std::vector<uint64_t>& out = u.found->local();
  const float r = u.query->radius();
  for (unsigned int i = 0; i < count; ++i) {
    const Box& q = u.query->boxes()[collisions[i].primID0];
    const Box& t = u.tree->boxes()[collisions[i].primID1];
    if (box_gap_within(q.lo, q.hi, r, t)) out.push_back(uint64_t(collisions[i].primID0) << 32 | collisions[i].primID1);
  }
}

}  // namespace

RTCDevice EmbreeBoxes::device() {
  static RTCDevice shared = [] {
    RTCDevice d = rtcNewDevice(nullptr);
    if (!d) throw std::runtime_error("embree: rtcNewDevice failed");
    return d;
  }();
  return shared;
}

EmbreeBoxes::EmbreeBoxes(bool refit) : refit_(refit) {
  scene_ = rtcNewScene(device());
  rtcSetSceneFlags(scene_, RTC_SCENE_FLAG_DYNAMIC);
  rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_MEDIUM);
  check_device(device(), "rtcNewScene");
}

EmbreeBoxes::~EmbreeBoxes() {
  if (scene_) rtcReleaseScene(scene_);
}

void EmbreeBoxes::bounds(const RTCBoundsFunctionArguments* args) {
  const EmbreeBoxes& self = *static_cast<const EmbreeBoxes*>(args->geometryUserPtr);
  const Box& b = self.boxes_[args->primID];
  // The box Embree overlaps holds every box minkq's test accepts (predicates.h's box_gap_bound).
  const Box g = self.r_ > 0.0f ? box_gap_bound(b.lo, b.hi, self.r_) : b;
  RTCBounds* o = args->bounds_o;
  o->lower_x = g.lo.x;
  o->lower_y = g.lo.y;
  o->lower_z = g.lo.z;
  o->upper_x = g.hi.x;
  o->upper_y = g.hi.y;
  o->upper_z = g.hi.z;
}

void EmbreeBoxes::set(std::vector<Box> boxes, float r) {
  if (geometry_ && boxes.size() != boxes_.size()) throw std::invalid_argument("EmbreeBoxes::set: another box count");
  boxes_ = std::move(boxes);
  r_ = r;
  if (!geometry_) {
    geometry_ = rtcNewGeometry(device(), RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserPrimitiveCount(geometry_, unsigned(boxes_.size()));
    rtcSetGeometryUserData(geometry_, this);
    rtcSetGeometryBoundsFunction(geometry_, &EmbreeBoxes::bounds, nullptr);
    rtcSetGeometryBuildQuality(geometry_, refit_ ? RTC_BUILD_QUALITY_REFIT : RTC_BUILD_QUALITY_MEDIUM);
    rtcCommitGeometry(geometry_);
    rtcAttachGeometry(scene_, geometry_);
    rtcReleaseGeometry(geometry_);
  } else {
    rtcCommitGeometry(geometry_);
  }
  rtcCommitScene(scene_);
  check_device(device(), "rtcCommitScene");
}

std::vector<uint64_t> embree_collide(const EmbreeBoxes& query, const EmbreeBoxes& tree) {
  tbb::enumerable_thread_specific<std::vector<uint64_t>> found;
  CollideUser user{&query, &tree, &found};
  rtcCollide(query.scene(), tree.scene(), &on_collisions, &user);
  check_device(EmbreeBoxes::device(), "rtcCollide");
  std::vector<uint64_t> pairs;
  for (const auto& part : found) pairs.insert(pairs.end(), part.begin(), part.end());
  tbb::parallel_sort(pairs.begin(), pairs.end());
  return pairs;
}

}  // namespace minkq::bench
