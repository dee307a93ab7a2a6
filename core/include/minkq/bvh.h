// The tree's layout: a linear BVH (Karras 2012) over primitive boxes, with subtrees of up to a
// leaf size of primitives collapsed into leaf ranges. Flat arrays of PODs, identical on CPU and
// GPU. How it is made: morton.h (the keys), build.h (the hierarchy from sorted keys), refit.h
// (the boxes bottom-up), cost.h (its quality); each step a per-element __host__ __device__
// function that a backend's tree (core/src/cpu/tree.h, core/src/cuda/tree.cuh) only loops over.
// traversal.h walks it.
#pragma once

#include <utility>

#include "minkq/detect.h"
#include "minkq/hd.h"

namespace minkq {

// One internal node in 64 bytes: both children's boxes travel together, so a visit reads one
// record. A node covers the sorted leaf positions [first, last]; its left child covers
// [first, split] and its right child [split + 1, last] (Karras), which lets a self-query skip
// the left child. Child >= 0: internal node index; child < 0: a leaf range of at most
// kLeafSize positions, [~left, split] on the left and [split + 1, ~right] on the right.
struct BvhNode {
  Box left_box;
  Box right_box;
  int32_t left;
  int32_t right;   // kNoChild in the single root of a one-primitive tree
  int32_t parent;  // (parent index << 1) | side, -1 for the root
  int32_t split;   // last sorted leaf position under the left child
};
static_assert(sizeof(BvhNode) == 64, "node record must stay one 64-byte line");

// Primitives per leaf range at most: the bottom levels of the binary tree become a scan of
// contiguous leaf boxes, four at a time (fewer node records to read, to build and to store, and
// fewer data-dependent branches per query than node visits cost). 1 gives the plain binary
// tree; docs/design-notes.md links the study of sizes.
constexpr int32_t kLeafSize = 32;

// How a backend's tree is built: the one option is the leaf size, 1 or more (kLeafSize, the
// default, is what every scene of the C API uses). The pairs a query finds do not depend on it.
struct BuildConfig {
  int32_t leaf_size = kLeafSize;
};
constexpr int32_t kNoChild = INT32_MIN;
// Keys are 63 Morton bits plus a 32-bit index tie-break; each level down lengthens the shared
// key prefix, so depth <= 96 and a traversal stack of 128 entries never overflows.
constexpr int kTraversalStack = 128;
// Leaf positions must leave ~position distinct from kNoChild.
constexpr int64_t kMaxPrimitives = INT32_MAX - 1;
// The most primitives one tree holds: a tree over n keeps up to n - 1 node records
// (max_node_count, build.h), numbered 0 to n - 2, and a parent link or a refit's child slot,
// (node << 1) | side, must stay a non-negative int32 (a negative link reads as the root's).
// The last node's right slot, 2 (n - 2) + 1, reaches INT32_MAX at n = 2^30 + 1.
constexpr int64_t kMaxTreePrimitives = (int64_t(INT32_MAX) - 1) / 2 + 2;
static_assert(((kMaxTreePrimitives - 2) << 1 | 1) == INT32_MAX,
              "the last node's right child slot of the largest tree is the largest int32");
static_assert(kMaxTreePrimitives <= kMaxPrimitives, "a tree's primitives are elements");

struct BvhView {
  const BvhNode* nodes;
  const BoxGroup* leaf_groups;  // the box of the primitive at sorted position p: lane p % 4 of group p / 4
  const int32_t* sorted_prims;  // the primitive at each sorted position
  int32_t num_prims;
};

// Primitive boxes already evaluated, one per primitive: the form a build reads them in after
// evaluating each once (a Boxes functor: the box of primitive i).
struct GivenBoxes {
  const Box* boxes;
  MINKQ_HD Box operator()(int32_t i) const { return boxes[i]; }
};

// A Boxes functor: boxes(i), the box of primitive i (or, with kByLeafPosition, of leaf
// position i: refit.h). Checked where a tree is built or refit.
template <class B>
using BoxOf = decltype(std::declval<const B&>()(int32_t()));
template <class B>
constexpr bool is_boxes = detected_as<Box, BoxOf, B>;
template <class B>
struct BoxesContract {
  static_assert(is_boxes<B>, "Boxes: needs Box operator()(int32_t i) const, the box of primitive i");
  static constexpr bool value = is_boxes<B>;
};

}  // namespace minkq
