// A tree's quality: its area cost (the surface area heuristic's estimate of the work a query
// does), which the stores compare with its value at build to tell when a refit tree has grown.
#pragma once

#include "minkq/bvh.h"

namespace minkq {

MINKQ_HD double half_area(const Box& b) {
  const double dx = double(b.hi.x) - b.lo.x, dy = double(b.hi.y) - b.lo.y, dz = double(b.hi.z) - b.lo.z;
  return dx * dy + dy * dz + dz * dx;
}

// One node's term of a tree's area cost: the half areas of its child boxes (the chance that a
// query entering the node tests into each child grows with its area, the SAH's estimate).
// Dividing the sum over all nodes by the root box's half area gives a scale-free cost.
MINKQ_HD double node_area(const BvhNode& node) {
  return half_area(node.left_box) + (node.right != kNoChild ? half_area(node.right_box) : 0.0);
}
MINKQ_HD double root_half_area(const BvhNode& root) {
  return half_area(root.right != kNoChild ? box_union(root.left_box, root.right_box) : root.left_box);
}

// A tree's area cost on the host: the sum of node_area over its nodes (in node order, so the
// same on every run) over the root box's half area; 0 without nodes or area.
inline double area_cost(const BvhNode* nodes, int64_t num_nodes) {
  if (num_nodes == 0) return 0.0;
  const double root = root_half_area(nodes[0]);
  if (!(root > 0.0)) return 0.0;
  double sum = 0.0;
  for (int64_t i = 0; i < num_nodes; ++i) sum += node_area(nodes[i]);
  return sum / root;
}

}  // namespace minkq
