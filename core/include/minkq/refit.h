// The bottom-up refit: each leaf range's primitive boxes written into its leaf groups and its
// parent's child box, then merged up the tree by the second child to arrive at each node. A
// build (build.h) ends with one over the collapsed tree; a refit is one alone.
#pragma once

#include "minkq/bvh.h"

namespace minkq {

MINKQ_HD int atomic_increment(int32_t* counter) {
#if defined(__CUDA_ARCH__)
  __threadfence();  // release: publish this thread's box writes before the sibling can read them
  const int before = atomicAdd(counter, 1);
  if (before != 0) __threadfence();  // acquire: the second arrival reads the sibling's box after this
  return before;
#else
  return __atomic_fetch_add(counter, 1, __ATOMIC_ACQ_REL);
#endif
}

MINKQ_HD Box load_box_coherent(const Box* b) {
#if defined(__CUDA_ARCH__)
  const volatile float* f = reinterpret_cast<const volatile float*>(b);  // bypass stale L1
  return {{f[0], f[1], f[2]}, {f[3], f[4], f[5]}};
#else
  return *b;
#endif
}

MINKQ_HD void store_child_box(BvhNode* nodes, int32_t slot, const Box& box) {
  BvhNode& parent = nodes[slot >> 1];
  if (slot & 1) parent.right_box = box; else parent.left_box = box;
}

// Whether a Boxes functor takes a leaf position (a static kByLeafPosition member: the elements
// kept in leaf order, leaf_groups.h's LeafBoxes) rather than a primitive id.
template <class Boxes>
using ByLeafPosition = std::integral_constant<bool, Boxes::kByLeafPosition>;
template <class Boxes>
constexpr bool by_leaf_position = flag_set<ByLeafPosition, Boxes>;

// A leaf range's box: the boxes of the primitives at sorted positions [first, last], each
// written into its group lane on the way (two ranges may share a group, never a lane).
template <class Boxes>
MINKQ_HD Box leaf_range_box(int32_t first, int32_t last, const Boxes& boxes, const int32_t* sorted_prims,
                            BoxGroup* leaf_groups) {
  static_assert(BoxesContract<Boxes>::value, "a refit reads its boxes from a Boxes functor (bvh.h)");
  Box box = Box::empty();
  for (int32_t q = first; q <= last; ++q) {
    const Box b = boxes(by_leaf_position<Boxes> ? q : sorted_prims[q]);
    set_group_box(leaf_groups[q >> 2], q & 3, b);
    box = box_union(box, b);
  }
  return box;
}

// Refit from child slot `slot` = (node << 1) | side (a thread per slot, 2 per node; a slot
// holding an internal node or no child returns at once): a leaf range writes its primitives'
// boxes (leaf_range_box) into the node's child box. The second of two children to arrive at a node
// (counters zeroed before the pass) merges both boxes and climbs on. Unions are exact.
template <class Boxes>
MINKQ_HD void refit_from_slot(int32_t slot, const Boxes& boxes, const int32_t* sorted_prims, BoxGroup* leaf_groups,
                              BvhNode* nodes, int32_t* arrivals) {
  const BvhNode& parent = nodes[slot >> 1];
  const int32_t child = (slot & 1) ? parent.right : parent.left;
  if (child >= 0 || child == kNoChild) return;
  const int32_t first = (slot & 1) ? parent.split + 1 : ~child, last = (slot & 1) ? ~child : parent.split;
  store_child_box(nodes, slot, leaf_range_box(first, last, boxes, sorted_prims, leaf_groups));
  int32_t node = slot >> 1;
  while (true) {
    if (nodes[node].right == kNoChild) return;  // one-primitive tree: nothing to merge
    if (atomic_increment(&arrivals[node]) == 0) return;
    const Box merged = box_union(load_box_coherent(&nodes[node].left_box),
                                 load_box_coherent(&nodes[node].right_box));
    slot = nodes[node].parent;
    if (slot < 0) return;
    store_child_box(nodes, slot, merged);
    node = slot >> 1;
  }
}

}  // namespace minkq
