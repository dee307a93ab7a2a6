// The node counts of a mesh's CPU trees (cpu/tree.h, the trees the CUDA backend matches bit for
// bit): how many nodes a build over the same primitives keeps at given positions, for the tests
// of the CUDA tree's node sizing (issue 30).
#pragma once

#include <cstdint>
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

// The point whose 63-bit Morton code (morton.h) has its `ones` leading bits set and the rest
// clear, in a frame whose cells are one unit (an extent of 2^21): code bit 62 - b is bit
// 20 - b / 3 of axis b % 3 (x, y, z).
inline Vec3 code_prefix_point(int ones) {
  uint32_t q[3] = {0, 0, 0};
  for (int b = 0; b < ones; ++b) q[b % 3] |= 1u << (20 - b / 3);
  return {float(q[0]), float(q[1]), float(q[2])};
}

// chain + cluster + 1 unit right triangles, three vertices of their own each (centres at the
// corner + 1/2 in x and y, so every centre sits on the same offset from the frame's corner).
// caterpillar: triangle k < chain at code_prefix_point(k), whose code shares exactly k leading
// bits with every later one, so each Karras node splits off one triangle and stays while it
// covers more than the leaf size: a chain of kept nodes, nearly n - leaf size of them (the
// degenerate input the CUDA tree's node room must grow for); the cluster at the all-ones
// corner, and the last triangle at 2^21 in every axis, which fixes the frame's extent at 2^21.
// Otherwise the same triangles four units apart on a line: a balanced tree, few nodes.
inline reference::Mesh caterpillar_mesh(bool caterpillar, int chain = 62, int cluster = 40) {
  reference::Mesh mesh;
  const int n = chain + cluster + 1;
  for (int k = 0; k < n; ++k) {
    const float corner = float((1 << 21) - 1), far = float(1 << 21);
    Vec3 p{4.0f * float(k), 0.0f, 0.0f};
    if (caterpillar && k < chain) p = code_prefix_point(k);
    else if (caterpillar) p = k < n - 1 ? Vec3{corner, corner, corner} : Vec3{far, far, far};
    for (const Vec3& v : {p, p + Vec3{1.0f, 0.0f, 0.0f}, p + Vec3{0.0f, 1.0f, 0.0f}}) {
      mesh.tris.push_back(int32_t(mesh.xyz.size() / 3));
      mesh.xyz.insert(mesh.xyz.end(), {v.x, v.y, v.z});
    }
  }
  mesh.edges = reference::derive_edges(mesh.tris);
  return mesh;
}

}  // namespace minkq::test
