// The Embree 3 peers, linked into minkq_bench: EmbreeVT, its point query as the VT baseline of the
// scenes, and EmbreeBoxes with embree_collide, its tree-against-tree rtcCollide as the baseline
// for pairs between two meshes (the geometries suite). Both decide their pairs with minkq's own
// predicates, so each set is exactly one of minkq's; what that takes is said at each class.
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "minkq/hd.h"

struct RTCDeviceTy;
struct RTCSceneTy;
struct RTCGeometryTy;
struct RTCBoundsFunctionArguments;

namespace minkq::bench {

// Embree 3's point query as the CPU baseline for VT queries (vertex within r of triangle),
// set up the way ../shared/REFERENCES.md says a fair comparison needs:
//  - Embree culls nodes with a float sphere-box test that has no robust variant, so it prunes
//    with the radius padded by 2^-20 relative (16 ulp) and the pairs are decided in the
//    callback with an exact test: minkq's own leaf predicate (point_triangle_within from
//    core/include/minkq/predicates.h, double precision with the stated 2^-20 S slack), so the
//    pair set is the one minkq's leaf_exact query returns;
//  - RTCPointQuery fields are set by name; scene and geometry build quality MEDIUM (HIGH's
//    spatial splits may call back twice for one primitive), so each frame's tree is a MEDIUM
//    rebuild: Embree 3.13 refits only in a dynamic scene of LOW quality (EmbreeBoxes below),
//    whose tree would cost its queries, and a query peer gets its best tree;
//  - the vertex buffer carries one float of padding; after moving vertices the geometry and
//    then the scene are committed.
// Queries run over the vertices in blocks of 256 with TBB, each block into its own buffer (the
// same scheme as minkq's CPU backend).
class EmbreeVT {
 public:
  // Builds the triangle BVH over xyz (3 floats per vertex) and tris (3 int32 per triangle).
  EmbreeVT(const std::vector<float>& xyz, const std::vector<int32_t>& tris);
  ~EmbreeVT();
  EmbreeVT(const EmbreeVT&) = delete;
  EmbreeVT& operator=(const EmbreeVT&) = delete;

  // New positions (same count); rebuilds the tree over them (a MEDIUM commit, see above).
  void rebuild(const std::vector<float>& xyz);
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

// Embree 3's rtcCollide (its tree against tree collision of two scenes, the broad phase of its
// cloth tutorial) as the baseline for box-mode pairs: each element set (a mesh's vertices,
// triangles or edges) is a scene of one user geometry whose primitives' boxes are the elements'
// boxes, the query side's grown by r (rounded outward, box_gap_bound); rtcCollide reports the
// pairs whose boxes overlap, and its callback keeps those that pass minkq's own box test
// (box_gap_within on the unexpanded boxes, predicates.h) and share no vertex when asked, so the
// set is exactly minkq's box-mode set. A scene collided with itself (EE) has every box grown by
// r/2: two such boxes overlap whenever the test can pass. Embree 3.13 reports each pair of a
// scene with itself both ways (never an element with itself); the callback keeps (lower, higher),
// minkq's EE order. Moved elements are refit (geometry build quality REFIT, scene LOW) or
// rebuilt (MEDIUM).
class EmbreeBoxes {
 public:
  enum class Side { query, tree, self };  // grown by r, not grown, grown by r/2
  // An empty scene on the shared Embree device; `refit`: moves refit its tree, else rebuild it.
  explicit EmbreeBoxes(bool refit);
  ~EmbreeBoxes();
  EmbreeBoxes(const EmbreeBoxes&) = delete;
  EmbreeBoxes& operator=(const EmbreeBoxes&) = delete;

  // The boxes of elements of `corners` vertices each (1: the vertices, `elements` unused; 2:
  // edges; 3: triangles) at positions xyz, as the library's trees box them (elements.h), computed
  // with TBB; the same count after the first call, `elements` kept by reference (the incidence
  // filter reads it). Commits the scene. r: the box test's radius.
  void set(const std::vector<float>& xyz, const std::vector<int32_t>& elements, int corners, float r, Side side);
  const std::vector<Box>& boxes() const { return boxes_; }
  const int32_t* elements() const { return elements_; }  // null for vertices
  int corners() const { return corners_; }
  float radius() const { return r_; }
  RTCSceneTy* scene() const { return scene_; }
  static RTCDeviceTy* device();

 private:
  static void bounds(const ::RTCBoundsFunctionArguments* args);
  bool refit_;
  std::vector<Box> boxes_;
  const int32_t* elements_ = nullptr;
  int corners_ = 1;
  float r_ = 0.0f, grow_ = 0.0f;
  RTCSceneTy* scene_ = nullptr;
  RTCGeometryTy* geometry_ = nullptr;
};

// Every (query element, tree element) whose boxes are within the query's radius (minkq's box
// test), through rtcCollide(query, tree), pairs sharing a vertex dropped when drop_incident; a
// scene with itself: each unordered pair once, (lower, higher). Pairs packed as first << 32 |
// second into out, sorted when asked. Not reentrant (the per-thread buffers are kept).
void embree_collide(const EmbreeBoxes& query, const EmbreeBoxes& tree, std::vector<uint64_t>& out,
                    bool drop_incident = false, bool sorted = true);

}  // namespace minkq::bench
