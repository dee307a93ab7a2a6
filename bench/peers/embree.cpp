// The Embree 3 peers (embree.h): EmbreeVT's point queries and EmbreeBoxes' rtcCollide.
#include "peers/embree.h"

#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
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
  bool drop_incident;
  tbb::enumerable_thread_specific<std::vector<uint64_t>>* found;
};

// Vertex i of element e of scene s (a vertex scene's elements are the vertices).
int32_t corner(const EmbreeBoxes& s, uint32_t e, int i) {
  return s.elements() ? s.elements()[size_t(e) * size_t(s.corners()) + size_t(i)] : int32_t(e);
}

// Whether element a of `query` and element b of `tree` share a vertex.
bool incident(const EmbreeBoxes& query, uint32_t a, const EmbreeBoxes& tree, uint32_t b) {
  for (int i = 0; i < query.corners(); ++i)
    for (int j = 0; j < tree.corners(); ++j)
      if (corner(query, a, i) == corner(tree, b, j)) return true;
  return false;
}

void on_collisions(void* user_ptr, RTCCollision* collisions, unsigned int count) {
  const CollideUser& u = *static_cast<const CollideUser*>(user_ptr);
  std::vector<uint64_t>& out = u.found->local();
  const float r = u.query->radius();
  const bool self = u.query == u.tree;
  for (unsigned int i = 0; i < count; ++i) {
    const uint32_t a = collisions[i].primID0, b = collisions[i].primID1;
    if (self && a > b) continue;  // reported both ways: kept once, as (lower, higher)
    if (u.drop_incident && incident(*u.query, a, *u.tree, b)) continue;
    const Box& q = u.query->boxes()[a];
    if (box_gap_within(q.lo, q.hi, r, u.tree->boxes()[b])) out.push_back(uint64_t(a) << 32 | b);
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
  rtcSetGeometryBuildQuality(geometry_, RTC_BUILD_QUALITY_MEDIUM);
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

void EmbreeVT::rebuild(const std::vector<float>& xyz) {
  if (xyz.size() + 1 != xyz_.size()) throw std::invalid_argument("embree rebuild: vertex count changed");
  std::memcpy(xyz_.data(), xyz.data(), xyz.size() * sizeof(float));
  rtcUpdateGeometryBuffer(geometry_, RTC_BUFFER_TYPE_VERTEX, 0);
  rtcCommitGeometry(geometry_);
  rtcCommitScene(scene_);
  check_device(device_, "rebuild");
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
  // Embree 3.13 refits a REFIT geometry only in a dynamic scene of LOW quality; at MEDIUM its
  // commit rebuilds (20k boxes: 0.16 ms against 7.8 ms), so a refit scene is LOW, a rebuilt MEDIUM.
  rtcSetSceneBuildQuality(scene_, refit ? RTC_BUILD_QUALITY_LOW : RTC_BUILD_QUALITY_MEDIUM);
  check_device(device(), "rtcNewScene");
}

EmbreeBoxes::~EmbreeBoxes() {
  if (scene_) rtcReleaseScene(scene_);
}

void EmbreeBoxes::bounds(const RTCBoundsFunctionArguments* args) {
  const EmbreeBoxes& self = *static_cast<const EmbreeBoxes*>(args->geometryUserPtr);
  const Box& b = self.boxes_[args->primID];
  // The box Embree overlaps holds every box minkq's test accepts (predicates.h's box_gap_bound);
  // two boxes grown by r/2 (rounded outward) overlap when the gap is below next_up(r).
  const Box g = self.grow_ > 0.0f ? box_gap_bound(b.lo, b.hi, self.grow_) : b;
  RTCBounds* o = args->bounds_o;
  o->lower_x = g.lo.x;
  o->lower_y = g.lo.y;
  o->lower_z = g.lo.z;
  o->upper_x = g.hi.x;
  o->upper_y = g.hi.y;
  o->upper_z = g.hi.z;
}

void EmbreeBoxes::set(const std::vector<float>& xyz, const std::vector<int32_t>& elements, int corners, float r, Side side) {
  if (corners < 1 || corners > 3) throw std::invalid_argument("EmbreeBoxes::set: corners must be 1, 2 or 3");
  const size_t n = corners == 1 ? xyz.size() / 3 : elements.size() / size_t(corners);
  if (geometry_ && n != boxes_.size()) throw std::invalid_argument("EmbreeBoxes::set: another box count");
  boxes_.resize(n);
  elements_ = corners == 1 ? nullptr : elements.data();
  corners_ = corners;
  r_ = r;
  grow_ = side == Side::query ? r : side == Side::self ? 0.5f * r : 0.0f;
  const auto* v = reinterpret_cast<const Vec3*>(xyz.data());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& range) {
    for (size_t i = range.begin(); i != range.end(); ++i)
      boxes_[i] = corners == 1 ? PointBoxes{v}(int32_t(i))
                  : corners == 2 ? EdgeBoxes{v, reinterpret_cast<const Edge*>(elements_)}(int32_t(i))
                                 : TriangleBoxes{v, reinterpret_cast<const Triangle*>(elements_)}(int32_t(i));
  });
  if (!geometry_) {
    geometry_ = rtcNewGeometry(device(), RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserPrimitiveCount(geometry_, unsigned(n));
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

void embree_collide(const EmbreeBoxes& query, const EmbreeBoxes& tree, std::vector<uint64_t>& out, bool drop_incident,
                    bool sorted) {
  static tbb::enumerable_thread_specific<std::vector<uint64_t>> found;  // kept: no regrowth per call
  for (auto& part : found) part.clear();
  CollideUser user{&query, &tree, drop_incident, &found};
  rtcCollide(query.scene(), tree.scene(), &on_collisions, &user);
  check_device(EmbreeBoxes::device(), "rtcCollide");
  size_t total = 0;
  for (const auto& part : found) total += part.size();
  out.clear();
  out.reserve(total);
  for (const auto& part : found) out.insert(out.end(), part.begin(), part.end());
  if (sorted) tbb::parallel_sort(out.begin(), out.end());
}

}  // namespace minkq::bench
