// The node counts of a mesh's CPU trees (cpu/tree.h, the trees the CUDA backend matches bit for
// bit): how many nodes a build over the same primitives keeps at given positions, for the tests
// of the CUDA tree's node sizing (issue 30).
#pragma once

#include <vector>

#include "cpu/tree.h"
#include "minkq_reference.h"

namespace minkq::test {

// The boxes of a mesh's primitives of `corners` vertices each (3: triangles, 2: edges).
inline std::vector<Box> primitive_boxes(const reference::Mesh& mesh, const std::vector<int32_t>& ids, int corners) {
  std::vector<Box> boxes(ids.size() / size_t(corners), Box::empty());
  for (size_t p = 0; p < boxes.size(); ++p)
    for (int k = 0; k < corners; ++k) {
      const float* v = &mesh.xyz[3 * size_t(ids[size_t(corners) * p + size_t(k)])];
      boxes[p] = box_expand(boxes[p], Vec3{v[0], v[1], v[2]});
    }
  return boxes;
}

inline int32_t node_count(const std::vector<Box>& boxes, int32_t leaf_size = kLeafSize) {
  CpuTree tree;
  tree.build(GivenBoxes{boxes.data()}, int32_t(boxes.size()), BuildConfig{leaf_size});
  return int32_t(tree.nodes().size());
}

struct TreeCounts {
  int32_t triangles, edges;
};
inline TreeCounts tree_counts(const reference::Mesh& mesh) {
  return {node_count(primitive_boxes(mesh, mesh.tris, 3)), node_count(primitive_boxes(mesh, reference::derive_edges(mesh.tris), 2))};
}

}  // namespace minkq::test
