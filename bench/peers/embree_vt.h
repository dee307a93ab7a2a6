// Embree 3's point query as the CPU baseline for VT queries (vertex within r of triangle),
// set up the way ../shared/REFERENCES.md says a fair comparison needs:
//  - Embree culls nodes with a float sphere-box test that has no robust variant, so it prunes
//    with the radius padded by 2^-20 relative (16 ulp) and the pairs are decided in the
//    callback with an exact test: minkq's own leaf predicate (point_triangle_within from
//    core/include/minkq/predicates.h, double precision with the stated 2^-20 S slack), so the
//    pair set is the one minkq's leaf_exact query returns;
//  - RTCPointQuery fields are set by name; scene build quality MEDIUM (HIGH's spatial splits may
//    call back twice for one primitive); geometry quality REFIT so moved vertices refit;
//  - the vertex buffer carries one float of padding; after moving vertices the geometry and
//    then the scene are committed.
// Queries run over the vertices in blocks of 256 with TBB, each block into its own buffer (the
// same scheme as minkq's CPU backend).
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

struct RTCDeviceTy;
struct RTCSceneTy;
struct RTCGeometryTy;

namespace minkq::bench {

class EmbreeVT {
 public:
  // Builds the triangle BVH over xyz (3 floats per vertex) and tris (3 int32 per triangle).
  EmbreeVT(const std::vector<float>& xyz, const std::vector<int32_t>& tris);
  ~EmbreeVT();
  EmbreeVT(const EmbreeVT&) = delete;
  EmbreeVT& operator=(const EmbreeVT&) = delete;

  // New positions (same count); refits.
  void refit(const std::vector<float>& xyz);
  // Every (vertex, triangle) within r, the triangle's own vertices dropped; pairs appended in
  // (block, vertex) order into out (cleared first). Returns the pair count.
  uint64_t query(float r, std::vector<int32_t>& out);

  static std::string version();

 private:
  RTCDeviceTy* device_ = nullptr;
  RTCSceneTy* scene_ = nullptr;
  RTCGeometryTy* geometry_ = nullptr;
  std::vector<float> xyz_;  // 3 per vertex + 1 float of padding; shared with Embree
  std::vector<uint32_t> tris_;
  std::vector<std::vector<int32_t>> parts_;
};

}  // namespace minkq::bench
