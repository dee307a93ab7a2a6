// Embree 3's rtcCollide (its tree against tree collision of two scenes, the broad phase of its
// cloth tutorial) as the baseline for pairs between two meshes: each element set (a mesh's
// vertices, triangles or edges) is a scene of one user geometry whose primitives' boxes are the
// elements' boxes, the query side's grown by r (rounded outward); rtcCollide reports the pairs
// whose boxes overlap, and its callback keeps those that pass minkq's own box test
// (box_gap_within on the unexpanded box, predicates.h), so the set is exactly minkq's box-mode
// set. Moved elements are refit (geometry build quality REFIT) or rebuilt (MEDIUM), as asked.
#pragma once

#include <cstdint>
#include <vector>

#include "minkq/hd.h"

struct RTCDeviceTy;
struct RTCSceneTy;
struct RTCGeometryTy;
struct RTCBoundsFunctionArguments;

namespace minkq::bench {

class EmbreeBoxes {
 public:
  // An empty scene on the shared Embree device; `refit`: moves refit its tree, else rebuild it.
  explicit EmbreeBoxes(bool refit);
  ~EmbreeBoxes();
  EmbreeBoxes(const EmbreeBoxes&) = delete;
  EmbreeBoxes& operator=(const EmbreeBoxes&) = delete;

  // The elements' boxes (same count after the first call) and the radius they are grown by for
  // Embree (0 for the tree side); commits the scene.
  void set(std::vector<Box> boxes, float r);
  const std::vector<Box>& boxes() const { return boxes_; }
  float radius() const { return r_; }
  RTCSceneTy* scene() const { return scene_; }
  static RTCDeviceTy* device();

 private:
  static void bounds(const ::RTCBoundsFunctionArguments* args);
  bool refit_;
  std::vector<Box> boxes_;
  float r_ = 0.0f;
  RTCSceneTy* scene_ = nullptr;
  RTCGeometryTy* geometry_ = nullptr;
};

// Every (query element, tree element) whose boxes are within the query's radius (minkq's box
// test), through rtcCollide(query, tree); pairs packed as first << 32 | second, sorted.
std::vector<uint64_t> embree_collide(const EmbreeBoxes& query, const EmbreeBoxes& tree);

}  // namespace minkq::bench
