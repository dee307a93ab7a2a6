// The Embree 3 peers (embree.h): EmbreeVT's point queries and EmbreeBoxes' rtcCollide.
#include "peers/embree.h"

#include <embree3/rtcore.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <cstring>
#include <stdexcept>
#include <string>

#include "minkq/elements.h"
#include "minkq/predicates.h"

namespace minkq::bench {
namespace {

// The device's last error as an exception naming the call.
void check_device(RTCDevice device, const char* what) {
  const RTCError e = rtcGetDeviceError(device);
  if (e != RTC_ERROR_NONE) throw std::runtime_error(std::string("embree: ") + what + " failed (error " + std::to_string(int(e)) + ")");
}

struct QueryUser {
  int32_t vertex;
  minkq::Vec3 p;
  float r;
  const float* xyz;
  const uint32_t* tris;
  std::vector<int32_t>* out;
};

bool on_primitive(RTCPointQueryFunctionArguments* args) {
  const QueryUser& u = *static_cast<const QueryUser*>(args->userPtr);
  const uint32_t t = args->primID;
  const uint32_t a = u.tris[3 * t], b = u.tris[3 * t + 1], c = u.tris[3 * t + 2];
  // Incident: dropped, as MINKQ_SCENE_DROP_INCIDENT.
  if (minkq::has_vertex({{int32_t(a), int32_t(b), int32_t(c)}}, u.vertex)) return false;
  auto at = [&](uint32_t i) { return minkq::Vec3{u.xyz[3 * i], u.xyz[3 * i + 1], u.xyz[3 * i + 2]}; };
  if (minkq::point_triangle_within(u.p, at(a), at(b), at(c), u.r)) {
    u.out->push_back(u.vertex);
    u.out->push_back(int32_t(t));
  }
  return false;  // the query radius is never shrunk
}

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

EmbreeVT::EmbreeVT(const std::vector<float>& xyz, const std::vector<int32_t>& tris) {
  device_ = rtcNewDevice(nullptr);
  if (!device_) throw std::runtime_error("embree: rtcNewDevice failed");
  xyz_.assign(xyz.begin(), xyz.end());
  xyz_.push_back(0.0f);  // one float of padding: Embree may read 16 bytes at the last vertex
  tris_.assign(tris.begin(), tris.end());
  scene_ = rtcNewScene(device_);
  rtcSetSceneBuildQuality(scene_, RTC_BUILD_QUALITY_MEDIUM);
  geometry_ = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
  rtcSetGeometryBuildQuality(geometry_, RTC_BUILD_QUALITY_REFIT);
  rtcSetSharedGeometryBuffer(geometry_, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, xyz_.data(), 0,
                             3 * sizeof(float), xyz.size() / 3);
  rtcSetSharedGeometryBuffer(geometry_, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, tris_.data(), 0,
                             3 * sizeof(uint32_t), tris.size() / 3);
  rtcCommitGeometry(geometry_);
  rtcAttachGeometry(scene_, geometry_);
  rtcCommitScene(scene_);
  check_device(device_, "scene build");
}

EmbreeVT::~EmbreeVT() {
  if (geometry_) rtcReleaseGeometry(geometry_);
  if (scene_) rtcReleaseScene(scene_);
  if (device_) rtcReleaseDevice(device_);
}

void EmbreeVT::refit(const std::vector<float>& xyz) {
  if (xyz.size() + 1 != xyz_.size()) throw std::invalid_argument("embree refit: vertex count changed");
  std::memcpy(xyz_.data(), xyz.data(), xyz.size() * sizeof(float));
  rtcUpdateGeometryBuffer(geometry_, RTC_BUFFER_TYPE_VERTEX, 0);
  rtcCommitGeometry(geometry_);
  rtcCommitScene(scene_);
  check_device(device_, "refit");
}

uint64_t EmbreeVT::query(float r, std::vector<int32_t>& out) {
  const int32_t n = int32_t((xyz_.size() - 1) / 3);
  constexpr int32_t kBlock = 256;
  const int32_t blocks = (n + kBlock - 1) / kBlock;
  parts_.resize(size_t(blocks));
  // Embree prunes with r padded by 2^-20 relative (its float sphere-box test is not
  // conservative); the callback's exact test decides. The smallest subnormal keeps r = 0 usable.
  const float padded = minkq::next_up(r * (1.0f + minkq::kSlabWidening)) + 1.40129846e-45f;
  tbb::parallel_for(int32_t(0), blocks, [&](int32_t b) {
    std::vector<int32_t>& part = parts_[size_t(b)];
    part.clear();
    RTCPointQueryContext context;
    const int32_t end = std::min(n, (b + 1) * kBlock);
    for (int32_t v = b * kBlock; v < end; ++v) {
      QueryUser user{v, {xyz_[3 * size_t(v)], xyz_[3 * size_t(v) + 1], xyz_[3 * size_t(v) + 2]}, r, xyz_.data(),
                     tris_.data(), &part};
      RTCPointQuery q;
      q.x = user.p.x;
      q.y = user.p.y;
      q.z = user.p.z;
      q.time = 0.0f;
      q.radius = padded;
      rtcInitPointQueryContext(&context);
      rtcPointQuery(scene_, &q, &context, on_primitive, &user);
    }
  });
  size_t total = 0;
  for (const auto& part : parts_) total += part.size();
  out.clear();
  out.reserve(total);
  for (const auto& part : parts_) out.insert(out.end(), part.begin(), part.end());
  return total / 2;
}

std::string EmbreeVT::version() {
  return std::to_string(RTC_VERSION_MAJOR) + "." + std::to_string(RTC_VERSION_MINOR) + "." +
         std::to_string(RTC_VERSION_PATCH);
}

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
