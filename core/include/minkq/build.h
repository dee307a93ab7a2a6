// The hierarchy from sorted Morton keys (morton.h): the binary Karras tree, node by node, and
// its collapse into the top of the tree (bvh.h) with small subtrees as leaf ranges.
#pragma once

#include "minkq/bvh.h"

namespace minkq {

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
// chain of nodes each one primitive larger than the one below keeps n - leaf_size), 1 for one
// primitive, none for none. The CUDA tree allocates this many once its scene is reserved for
// stream-ordered calls (node_room otherwise), so that no later build moves the nodes a CUDA
// graph was captured with or outgrows a captured refit.
MINKQ_HD constexpr int32_t max_node_count(int32_t n) { return n <= 1 ? n : n - 1; }

// The node records the CUDA tree allocates for a build over n primitives that keeps `kept`
// nodes: kept plus half again (kNodeHeadroomHalves / 2), so that rebuilds whose counts drift
// up a little do not allocate again, at most max_node_count(n). A build that keeps about one
// node in twenty primitives then holds about three in forty, not n - 1.
constexpr int32_t kNodeHeadroomHalves = 3;
MINKQ_HD constexpr int32_t node_room(int32_t kept, int32_t n) {
  const int64_t room = int64_t(kept) * kNodeHeadroomHalves / 2;
  return room < max_node_count(n) ? int32_t(room) : max_node_count(n);
}
// The room after a build that keeps `kept` nodes where `room` are allocated: unchanged while
// they fit (the room never shrinks: a blocking call grows it, none moves it back), else
// node_room(kept, n).
MINKQ_HD constexpr int32_t grown_node_room(int32_t room, int32_t kept, int32_t n) {
  return kept <= room ? room : node_room(kept, n);
}

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

}  // namespace minkq
