// Embree 3 point-query VT baseline; see embree_vt.h.
#include "peers/embree_vt.h"

#include <embree3/rtcore.h>
#include <tbb/parallel_for.h>

#include <cstring>
#include <stdexcept>

#include "minkq/predicates.h"
#include "peers/embree_errors.h"
#include "minkq/elements.h"

namespace minkq::bench {

namespace {

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

}  // namespace minkq::bench
