// The Embree-based CPU reference: the candidate sets of minkq's modes computed by Embree 3's
// own BVH traversal. Embree prunes, conservatively (padded boxes, a padded radius); a callback
// decides each pair with minkq's own node test applied to the primitive's box and the mode's
// leaf filter. The set is therefore minkq's by definition, found by an independent traversal
// (see fuzz/README.md for which call produces which set and why).
#pragma once

#include <embree3/rtcore.h>

#include <memory>

#include "scene_checks.h"

namespace minkq::fuzz {

class EmbreeReference final : public IndependentSets {
 public:
  EmbreeReference();  // one device, pinned to SSE2 (results must not depend on the ISA)
  ~EmbreeReference() override;
  EmbreeReference(const EmbreeReference&) = delete;
  EmbreeReference& operator=(const EmbreeReference&) = delete;

  // Embree silently drops primitives with NaN, Inf or coordinates above about 1.8e18; those
  // scenes are compared with the brute-force definition only.
  bool accepts(const std::vector<float>& coordinates, float r) const override;
  MeshSets mesh_sets(const MeshGeometry& g, float r, uint32_t filters, bool moved) override;
  BoxSets box_sets(const BoxGeometry& g, minkq_shape shape, float r, bool moved) override;
  SweptSets swept_sets(const MeshGeometry& g, float r, uint32_t filters, bool moved) override;
  void reset() override;

  // The radius Embree prunes with: r padded well past the float error of its sphere-box test.
  static float pruning_radius(float r);

  struct BoxList;  // a committed Embree scene of user boxes (defined in the .cpp)

 private:
  RTCDevice device_;
  // Scenes of the last call, kept so that a refit reuses them (commit geometry, then scene).
  std::unique_ptr<BoxList> triangles_, edges_, vertex_queries_, edge_queries_, user_boxes_, user_queries_;
};

}  // namespace minkq::fuzz
