// The tree: a linear BVH (Karras 2012) over primitive boxes, with subtrees of up to a leaf size
// of primitives collapsed into leaf ranges. Flat arrays of PODs, identical on CPU and GPU:
// the node layout, Morton codes, the hierarchy from sorted keys, the bottom-up refit and the
// area cost, each step a per-element __host__ __device__ function that a backend's tree
// (core/src/cpu/tree.h, core/src/cuda/tree.cuh) only loops over. traversal.h walks it.
#pragma once

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
// tree; bench/README.md links the study of sizes.
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

// ---- Morton codes ----------------------------------------------------------------------------

MINKQ_HD uint64_t spread_bits_21(uint32_t v) {  // 21 bits -> every third bit of 63
  uint64_t x = v & 0x1fffffu;
  x = (x | x << 32) & 0x1f00000000ffffull;
  x = (x | x << 16) & 0x1f0000ff0000ffull;
  x = (x | x << 8) & 0x100f00f00f00f00full;
  x = (x | x << 4) & 0x10c30c30c30c30c3ull;
  x = (x | x << 2) & 0x1249249249249249ull;
  return x;
}

MINKQ_HD uint32_t quantize_21(float value, float lo, float scale) {
  const float q = (value - lo) * scale;  // scale = 2^21 / extent (see morton_frame)
  if (!(q > 0.0f)) return 0u;
  if (q >= 2097151.0f) return 2097151u;
  return uint32_t(q);
}

// 63-bit Morton code of a box's centre within the bounds of all centres, over cubic cells: a
// query's radius is the same in every axis, so each axis is split as often as its extent
// warrants (the usual per-axis frame would split a thin axis as often as the longest one).
struct MortonFrame {
  Vec3 lo;
  Vec3 scale;  // 2^21 / extent per axis, 0 for a flat axis
};
MINKQ_HD float morton_scale(float extent) { return extent > 0.0f ? 2097152.0f / extent : 0.0f; }
MINKQ_HD MortonFrame morton_frame(const Box& centre_bounds) {
  const Vec3 extent = centre_bounds.hi - centre_bounds.lo;
  const float scale = morton_scale(max_num(max_num(extent.x, extent.y), extent.z));
  return {centre_bounds.lo, {scale, scale, scale}};
}
MINKQ_HD Vec3 box_centre(const Box& b) { return 0.5f * (b.lo + b.hi); }
MINKQ_HD uint64_t morton_code(const MortonFrame& f, Vec3 c) {
  return spread_bits_21(quantize_21(c.x, f.lo.x, f.scale.x)) << 2 |
         spread_bits_21(quantize_21(c.y, f.lo.y, f.scale.y)) << 1 |
         spread_bits_21(quantize_21(c.z, f.lo.z, f.scale.z));
}

// ---- Hierarchy from sorted keys ---------------------------------------------------------------

MINKQ_HD int count_leading_zeros64(uint64_t x) {
#if defined(__CUDA_ARCH__)
  return __clzll((long long)x);
#else
  return x == 0 ? 64 : __builtin_clzll(x);
#endif
}

// Length of the common prefix of sorted keys i and j, the position breaking ties; -1 outside.
// j is 64-bit: the search below probes up to 2n positions away.
MINKQ_HD int common_prefix(const uint64_t* keys, int32_t n, int32_t i, int64_t j) {
  if (j < 0 || j >= n) return -1;
  const uint64_t a = keys[i], b = keys[j];
  if (a != b) return count_leading_zeros64(a ^ b);
  return 64 + count_leading_zeros64(uint64_t(uint32_t(i) ^ uint32_t(j))) - 32;  // index tie-break
}

// Node i of the binary Karras tree over n >= 2 sorted leaves: it covers positions
// [first, last]; its left child covers [first, split] (internal node `split` unless it is one
// leaf) and its right child [split + 1, last] (internal node split + 1 unless one leaf).
struct KarrasNode {
  int32_t first, last, split;
};
MINKQ_HD KarrasNode karras_node(int32_t i, const uint64_t* keys, int32_t n) {
  const int dir = common_prefix(keys, n, i, i + 1) - common_prefix(keys, n, i, i - 1) > 0 ? 1 : -1;
  const int delta_min = common_prefix(keys, n, i, i - dir);
  int64_t lmax = 2;
  while (common_prefix(keys, n, i, i + lmax * dir) > delta_min) lmax *= 2;
  int64_t l = 0;
  for (int64_t t = lmax / 2; t >= 1; t /= 2)
    if (common_prefix(keys, n, i, i + (l + t) * dir) > delta_min) l += t;
  const int32_t j = int32_t(i + l * dir);
  const int delta_node = common_prefix(keys, n, i, j);
  int64_t s = 0;
  for (int64_t div = 2;; div *= 2) {
    const int64_t t = (l + div - 1) / div;
    if (common_prefix(keys, n, i, i + (s + t) * dir) > delta_node) s += t;
    if (t <= 1) break;
  }
  const int32_t split = int32_t(i + s * dir + (dir < 0 ? -1 : 0));
  return {i < j ? i : j, i < j ? j : i, split};
}

// The Karras split of the range [first, last] (first < last) of sorted keys: its last position
// whose key shares more than the range's common prefix with keys[first] (the next key bit
// parts the range there). karras_node() finds the same split from the node's own end; a
// top-down build that knows each range from its parent needs only this one binary search.
MINKQ_HD int32_t split_position(const uint64_t* keys, int32_t n, int32_t first, int32_t last) {
  const int delta = common_prefix(keys, n, first, last);
  int32_t split = first, step = last - first;
  do {
    step = (step + 1) >> 1;
    const int32_t probe = split + step;
    if (probe < last && common_prefix(keys, n, first, probe) > delta) split = probe;
  } while (step > 1);
  return split;
}

// The root of a one-primitive tree: a single leaf range [0, 0] on the left, no right child.
MINKQ_HD BvhNode one_leaf_root() {
  BvhNode root{};
  root.left = ~0;
  root.right = kNoChild;
  root.parent = -1;
  root.split = 0;
  return root;
}

// Whether Karras node i stays an internal node: it covers more than leaf_size leaves (the root
// always stays). Kept nodes form the top of the tree: a parent covers more than its child.
MINKQ_HD bool keeps_range(int32_t first, int32_t last, int32_t leaf_size) { return last - first + 1 > leaf_size; }
MINKQ_HD bool keeps_node(int32_t i, const KarrasNode& k, int32_t leaf_size) {
  return i == 0 || keeps_range(k.first, k.last, leaf_size);
}

// The most node records a build over n primitives can keep, at any leaf size: n - 1 for
// n >= 2 (leaf size 1 keeps every Karras node, and larger ones may keep nearly as many: a
// chain of nodes each one primitive larger than the one below), 1 for one primitive, none for
// none. The CUDA tree sizes its nodes for this at its first build, so that no later build over
// the same primitives moves them or outgrows a refit captured into a CUDA graph.
MINKQ_HD constexpr int32_t max_node_count(int32_t n) { return n <= 1 ? n : n - 1; }

// Writes kept Karras node i as node new_index[i]: children that are kept nodes by their new
// index, every other child (a small subtree or one leaf) as a leaf range; links each kept
// child to it.
MINKQ_HD void collapse_node(int32_t i, const KarrasNode* karras, const int32_t* new_index, int32_t leaf_size,
                            BvhNode* nodes) {
  const KarrasNode k = karras[i];
  const int32_t self = new_index[i];
  BvhNode& node = nodes[self];
  node.split = k.split;
  if (i == 0) node.parent = -1;
  const bool left_internal = k.first != k.split && keeps_node(k.split, karras[k.split], leaf_size);
  if (left_internal) {
    node.left = new_index[k.split];
    nodes[node.left].parent = self << 1;
  } else {
    node.left = ~k.first;
  }
  const bool right_internal = k.last != k.split + 1 && keeps_node(k.split + 1, karras[k.split + 1], leaf_size);
  if (right_internal) {
    node.right = new_index[k.split + 1];
    nodes[node.right].parent = self << 1 | 1;
  } else {
    node.right = ~k.last;
  }
}

// ---- Bottom-up refit ---------------------------------------------------------------------------

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
// kept in leaf order, queries.h's LeafBoxes) rather than a primitive id.
template <class Boxes>
MINKQ_HD constexpr auto by_leaf_position(int) -> decltype(bool(Boxes::kByLeafPosition)) {
  return Boxes::kByLeafPosition;
}
template <class Boxes>
MINKQ_HD constexpr bool by_leaf_position(long) {
  return false;
}

// A leaf range's box: the boxes of the primitives at sorted positions [first, last], each
// written into its group lane on the way (two ranges may share a group, never a lane).
template <class Boxes>
MINKQ_HD Box leaf_range_box(int32_t first, int32_t last, const Boxes& boxes, const int32_t* sorted_prims,
                            BoxGroup* leaf_groups) {
  Box box = Box::empty();
  for (int32_t q = first; q <= last; ++q) {
    const Box b = boxes(by_leaf_position<Boxes>(0) ? q : sorted_prims[q]);
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

// ---- Tree quality ------------------------------------------------------------------------------

// Half a box's surface area, in double: the area cost below sums many of them.
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
