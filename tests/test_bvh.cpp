// BVH invariants after build and after refit: every primitive lies in exactly one leaf range of
// at most kLeafSize positions, parent links agree with child links, each stored child box is
// exactly the union of the boxes below it,
// and depth stays within the traversal stack's bound even when all Morton codes tie.
#include <gtest/gtest.h>

#include <functional>

#include "cpu_tree.h"
#include "minkq/queries.h"
#include "test_util.h"

namespace minkq {
namespace {

bool same_box(const Box& a, const Box& b) { return std::memcmp(&a, &b, sizeof(Box)) == 0; }
bool contains(const Box& outer, const Box& inner) {
  return outer.lo.x <= inner.lo.x && outer.lo.y <= inner.lo.y && outer.lo.z <= inner.lo.z &&
         inner.hi.x <= outer.hi.x && inner.hi.y <= outer.hi.y && inner.hi.z <= outer.hi.z;
}

// Walks the tree; returns the union of the subtree's leaf boxes and checks every invariant.
Box check_subtree(const CpuTree& tree, const std::vector<Box>& boxes, int32_t node, int depth, std::vector<int>& seen,
                  int& max_depth) {
  max_depth = std::max(max_depth, depth);
  const BvhNode& n = tree.nodes()[node];
  Box total = Box::empty();
  const int32_t children[2] = {n.left, n.right};
  const Box* stored[2] = {&n.left_box, &n.right_box};
  for (int side = 0; side < 2; ++side) {
    const int32_t child = children[side];
    if (child == kNoChild) continue;
    Box below = Box::empty();
    if (child < 0) {  // a leaf range of sorted positions
      const int32_t first = side ? n.split + 1 : ~child, last = side ? ~child : n.split;
      EXPECT_LE(first, last);
      EXPECT_LE(last - first + 1, kLeafSize);
      for (int32_t p = first; p <= last; ++p) {
        const int32_t prim = tree.sorted_prims()[p];
        ++seen[prim];
        below = box_union(below, boxes[prim]);
      }
      // Each primitive's quantized box, decoded as the traversal does, contains its box.
      if (last > first)
        for (int32_t p = first; p <= last; ++p) {
          const Box decoded = decode_box(tree.leaf_boxes()[p], *stored[side], range_steps(*stored[side]));
          EXPECT_TRUE(contains(decoded, boxes[tree.sorted_prims()[p]])) << "position " << p;
        }
    } else {
      EXPECT_EQ(tree.nodes()[child].parent, node << 1 | side);
      below = check_subtree(tree, boxes, child, depth + 1, seen, max_depth);
    }
    EXPECT_TRUE(same_box(*stored[side], below)) << "node " << node << " side " << side;
    total = box_union(total, below);
  }
  return total;
}

void check_tree(const CpuTree& tree, const std::vector<Box>& boxes) {
  std::vector<int> seen(boxes.size(), 0);
  int max_depth = 0;
  if (!boxes.empty()) {
    EXPECT_EQ(tree.nodes()[0].parent, -1);
    check_subtree(tree, boxes, 0, 1, seen, max_depth);
  }
  for (size_t i = 0; i < boxes.size(); ++i) ASSERT_EQ(seen[i], 1) << "primitive " << i;
  EXPECT_LE(max_depth, kTraversalStack - 1);
}

std::vector<Box> random_boxes(test::Random& rng, int n, float spread) {
  std::vector<Box> boxes(static_cast<size_t>(n));
  for (Box& b : boxes) b = rng.box(rng.vec3(-spread, spread), 0.1f);
  return boxes;
}

TEST(Bvh, invariants_hold_after_build_and_refit) {
  test::Random rng(test::fresh_seed());
  for (int n : {0, 1, 2, 3, 7, 100, 5000, 40000}) {
    std::vector<Box> boxes = random_boxes(rng, n, 10.0f);
    CpuTree tree;
    tree.build(GivenBoxes{boxes.data()}, n);
    check_tree(tree, boxes);
    // Subtrees of up to kLeafSize leaves are collapsed: well under the binary tree's n - 1 nodes.
    if (n >= 100) EXPECT_LT(tree.nodes().size(), size_t(n) / 2);
    for (Box& b : boxes) {
      const Vec3 shift = rng.vec3(-3, 3);
      b = {b.lo + shift, b.hi + shift};
    }
    tree.refit(GivenBoxes{boxes.data()});
    check_tree(tree, boxes);
  }
}

// A box encoded within a range box (any range containing it) decodes to a box that contains
// it and lies within the range, at every magnitude and sign, with flat axes, subnormal and
// near-overflow extents; for ordinary ranges the slack is under 1/64 of the range per bound
// (plus one rounding).
TEST(Bvh, quantized_boxes_contain_their_boxes_at_every_scale) {
  test::Random rng(test::fresh_seed());
  const float magnitudes[] = {1e-40f, 1e-30f, 1e-3f, 1.0f, 1e3f, 1e30f, 3e38f};
  for (int trial = 0; trial < 200000; ++trial) {
    const float m = magnitudes[rng.integer(0, 6)];
    const float centre_scale = rng.integer(0, 2) == 0 ? 0.0f : m * rng.log_uniform(1e-6f, 1.0f);
    const float extent = m * (rng.integer(0, 9) == 0 ? 1.0f : rng.log_uniform(1e-7f, 1.0f));
    auto point = [&] {
      const float c = centre_scale * rng.uniform(-1, 1);
      return std::fmin(std::fmax(c + extent * rng.uniform(-1, 1), -FLT_MAX), FLT_MAX);
    };
    Box range = Box::empty(), b = Box::empty();
    Vec3 corners[4];
    for (Vec3& c : corners) {
      c = {point(), point(), point()};
      if (rng.integer(0, 7) == 0) c.y = corners[0].y;  // a flat axis now and then
      range = box_expand(range, c);
    }
    b = box_expand(box_expand(b, corners[0]), corners[1]);
    const Vec3 steps = range_steps(range);
    const Box decoded = decode_box(encode_box(b, range, steps), range, steps);
    auto show = [](const Box& x) {
      char text[200];
      std::snprintf(text, sizeof text, "[%.9g %.9g %.9g; %.9g %.9g %.9g]", x.lo.x, x.lo.y, x.lo.z, x.hi.x, x.hi.y,
                    x.hi.z);
      return std::string(text);
    };
    ASSERT_TRUE(contains(decoded, b) && contains(range, decoded))
        << "trial " << trial << ": box " << show(b) << " in range " << show(range) << " decodes to " << show(decoded);
    for (int axis = 0; axis < 3; ++axis) {
      const double lo = component(range.lo, axis), hi = component(range.hi, axis), width = hi - lo;
      if (width < 1e-35 || width > 1e35) continue;  // the step is clamped there: looser, still containing
      // A code is 1/128 of the width or finer, plus the rounding of one addition.
      const double slack = width / 64.0 + std::max(std::fabs(lo), std::fabs(hi)) * 0x1p-23;
      EXPECT_LE(double(component(b.lo, axis)) - double(component(decoded.lo, axis)), slack);
      EXPECT_LE(double(component(decoded.hi, axis)) - double(component(b.hi, axis)), slack);
    }
  }
}

TEST(Bvh, coincident_boxes_tie_on_morton_codes_yet_stay_shallow) {
  std::vector<Box> boxes(100000, Box{{1, 2, 3}, {1, 2, 3}});
  CpuTree tree;
  tree.build(GivenBoxes{boxes.data()}, int32_t(boxes.size()));
  check_tree(tree, boxes);
  // Half the boxes far away at huge offsets, half coincident: extreme key skew.
  for (size_t i = 0; i < boxes.size(); i += 2) boxes[i] = Box{{1e7f, -1e7f, 3}, {1e7f, -1e7f, 3}};
  tree.build(GivenBoxes{boxes.data()}, int32_t(boxes.size()));
  check_tree(tree, boxes);
}

TEST(Bvh, build_is_deterministic) {
  test::Random rng(test::fresh_seed());
  const std::vector<Box> boxes = random_boxes(rng, 20000, 5.0f);
  CpuTree a, b;
  a.build(GivenBoxes{boxes.data()}, int32_t(boxes.size()));
  b.build(GivenBoxes{boxes.data()}, int32_t(boxes.size()));
  ASSERT_EQ(a.nodes().size(), b.nodes().size());
  EXPECT_EQ(std::memcmp(a.nodes().data(), b.nodes().data(), a.nodes().size() * sizeof(BvhNode)), 0);
}

}  // namespace
}  // namespace minkq
