// BVH invariants after build and after refit: every primitive lies in exactly one leaf range of
// at most kLeafSize positions, parent links agree with child links, each stored child box is
// exactly the union of the boxes below it,
// and depth stays within the traversal stack's bound even when all Morton codes tie.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>

#include "store.h"
#include "cpu/passes.h"
#include "cpu/radix_sort.h"
#include "cpu/tree.h"
#include "karras_tree.h"
#include "minkq/shapes.h"
#include "test_util.h"
#include "tree_counts.h"

namespace minkq {
namespace {

bool same_box(const Box& a, const Box& b) { return std::memcmp(&a, &b, sizeof(Box)) == 0; }

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
        EXPECT_TRUE(same_box(tree.leaf_box(p), boxes[prim])) << "position " << p;
        below = box_union(below, boxes[prim]);
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

// max_node_count(n) bounds the nodes of every build over n primitives, whatever their
// positions: a reserved CUDA tree sizes its nodes, arrival flags and refit by it, so that a
// refit captured into a CUDA graph still covers every node, at the same address, after a
// later rebuild keeps more of them (issue 30). The scenario is real: the same
// triangles keep a different number of nodes flat and twisted, and the bound is reached.
TEST(Bvh, max_node_count_bounds_every_build_over_the_same_primitives) {
  using test::node_count;
  auto triangle_boxes = [](const reference::Mesh& mesh) { return test::primitive_boxes(mesh, mesh.tris, 3); };
  const std::vector<Box> flat = triangle_boxes(reference::twisted_sheet(48, 0.0));
  const std::vector<Box> twisted = triangle_boxes(reference::twisted_sheet(48, 3.0));
  ASSERT_EQ(flat.size(), twisted.size());
  const int32_t n = int32_t(flat.size());
  EXPECT_NE(node_count(flat, kLeafSize), node_count(twisted, kLeafSize))
      << "the same triangles should keep a different number of nodes flat and twisted (so the first "
         "build's count is too few for one of the two orders)";
  for (int32_t leaf_size : {1, 2, 4, 8, kLeafSize}) {
    EXPECT_LE(node_count(flat, leaf_size), max_node_count(n)) << "leaf size " << leaf_size;
    EXPECT_LE(node_count(twisted, leaf_size), max_node_count(n)) << "leaf size " << leaf_size;
  }
  EXPECT_EQ(node_count(twisted, 1), max_node_count(n));  // a binary tree: every Karras node
  test::Random rng(test::fresh_seed());
  for (int32_t m : {0, 1, 2, 3, 17, 1000}) {
    const std::vector<Box> boxes = random_boxes(rng, m, 1.0f);
    for (int32_t leaf_size : {1, kLeafSize}) EXPECT_LE(node_count(boxes, leaf_size), max_node_count(m)) << m;
  }
  EXPECT_EQ(max_node_count(0), 0);
  EXPECT_EQ(max_node_count(1), 1);
}

// An unreserved CUDA tree holds node_room(kept, n) nodes and grows to grown_node_room when a
// blocking build keeps more (issue 56): kept plus half again, never past max_node_count, never
// shrinking, never fewer than kept.
TEST(Bvh, node_room_is_kept_plus_headroom_within_the_bound) {
  EXPECT_EQ(node_room(0, 0), 0);
  EXPECT_EQ(node_room(1, 1), 1);
  EXPECT_EQ(node_room(1, 2), 1);
  EXPECT_EQ(node_room(20, 1000), 30);
  EXPECT_EQ(node_room(21, 1000), 31);
  EXPECT_EQ(node_room(900, 1000), 999);
  EXPECT_EQ(node_room(1 << 30, (1 << 30) + 1), 1 << 30);  // no 32-bit overflow near the limit
  EXPECT_EQ(node_room(int32_t(1) << 28, INT32_MAX - 1), 3 << 27);
  for (int32_t n : {2, 3, 33, 100})
    for (int32_t kept = 1; kept <= max_node_count(n); ++kept) {
      EXPECT_GE(node_room(kept, n), kept) << n << " " << kept;
      EXPECT_LE(node_room(kept, n), max_node_count(n)) << n << " " << kept;
    }
  EXPECT_EQ(grown_node_room(30, 25, 1000), 30);  // fits: unchanged, also when fewer are kept
  EXPECT_EQ(grown_node_room(30, 30, 1000), 30);
  EXPECT_EQ(grown_node_room(30, 31, 1000), 46);
  EXPECT_EQ(grown_node_room(30, 800, 1000), 999);
}

// The caterpillar of tree_counts.h keeps nearly n - leaf size nodes where the same triangles on
// a line keep a few: a build at the caterpillar after one on the line must grow the node room
// the first build left (test_cuda.cpp checks the CUDA tree does, and gives the CPU's pairs).
TEST(Bvh, caterpillar_keeps_nearly_n_minus_leaf_size_nodes_and_the_room_grows_for_it) {
  const reference::Mesh line = test::caterpillar_mesh(false), caterpillar = test::caterpillar_mesh(true);
  ASSERT_EQ(line.tris, caterpillar.tris);
  const int32_t n = int32_t(line.triangle_count());
  const int32_t few = test::tree_counts(line).triangles, many = test::tree_counts(caterpillar).triangles;
  EXPECT_LE(few, 8);
  EXPECT_GE(many, n - kLeafSize - 10);  // 64 of n = 103: n - leaf size is 71
  EXPECT_LE(many, max_node_count(n));
  const int32_t room = node_room(few, n);
  ASSERT_GT(many, room) << "the caterpillar must outgrow the line's room";
  const int32_t grown = grown_node_room(room, many, n);
  EXPECT_GE(grown, many);
  EXPECT_LE(grown, max_node_count(n));
  EXPECT_EQ(grown_node_room(grown, few, n), grown);  // back on the line: kept, not shrunk
}

// The area cost is the sum of node_area over the nodes, over the root's half area: 1 as a
// growth right after a build, unchanged by exact scaling, and 0 for boxes without area.
TEST(Bvh, area_cost_is_scale_free_and_recorded_at_build) {
  test::Random rng(test::fresh_seed());
  std::vector<Box> boxes = random_boxes(rng, 3000, 10.0f);
  CpuTree tree;
  tree.build(GivenBoxes{boxes.data()}, int32_t(boxes.size()));
  double sum = 0.0;
  for (const BvhNode& node : tree.nodes()) sum += node_area(node);
  const Box root = box_union(tree.nodes()[0].left_box, tree.nodes()[0].right_box);
  const double dx = double(root.hi.x) - root.lo.x, dy = double(root.hi.y) - root.lo.y,
               dz = double(root.hi.z) - root.lo.z;
  EXPECT_DOUBLE_EQ(tree.area_cost(), sum / (dx * dy + dy * dz + dz * dx));
  EXPECT_EQ(tree.cost_at_build(), tree.area_cost());
  EXPECT_GT(tree.area_cost(), 1.0);  // the root's two children alone nearly cover the root
  const double built = tree.area_cost();
  for (Box& b : boxes) b = {0.125f * b.lo, 0.125f * b.hi};
  tree.refit(GivenBoxes{boxes.data()});
  EXPECT_EQ(tree.area_cost(), built);
  EXPECT_EQ(growth(tree.area_cost(), tree.cost_at_build()), 1.0);
  // Spread the boxes: the tree's grouping no longer fits, its cost grows.
  for (Box& b : boxes) {
    const Vec3 shift = rng.vec3(-20, 20);
    b = {b.lo + shift, b.hi + shift};
  }
  tree.refit(GivenBoxes{boxes.data()});
  EXPECT_GT(growth(tree.area_cost(), tree.cost_at_build()), 1.5);
  // Collinear boxes have no area: cost 0, growth 1 while so, infinite once they gain area.
  std::vector<Box> line(500);
  for (size_t i = 0; i < line.size(); ++i) line[i] = {{float(i), 0, 0}, {float(i) + 0.5f, 0, 0}};
  tree.build(GivenBoxes{line.data()}, int32_t(line.size()));
  EXPECT_EQ(tree.area_cost(), 0.0);
  EXPECT_EQ(growth(tree.area_cost(), tree.cost_at_build()), 1.0);
  line[7].hi.y = 1.0f;
  tree.refit(GivenBoxes{line.data()});
  EXPECT_EQ(growth(tree.area_cost(), tree.cost_at_build()), HUGE_VAL);
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

// The CPU build reaches its records top-down through the kept nodes only (build_nodes); the
// CUDA build computes every Karras node, scans the kept ones, writes them and refits. Both must
// give the same records, leaf boxes and numbering byte for byte (CPU and CUDA scenes agree
// exactly): checked here through the CUDA build's steps on the host, for every leaf size, sizes
// around the leaf size and above the parallel split, and keys that tie (all or half the boxes
// coincident: the index tie-break decides the splits).
TEST(Bvh, top_down_build_gives_the_records_of_the_cuda_build_steps) {
  test::Random rng(test::fresh_seed());
  auto check = [](const std::vector<Box>& boxes, int32_t leaf_size, const char* what) {
    const int32_t n = int32_t(boxes.size());
    HostVector<int32_t> order;
    SortScratch sort;
    sort_by_morton(GivenBoxes{boxes.data()}, n, order, sort);
    HostVector<BvhNode> top_down, karras;
    std::vector<BoxGroup> top_down_groups(size_t(box_group_count(n))), karras_groups(top_down_groups.size());
    build_nodes(sort.keys.data(), n, leaf_size, GivenBoxes{boxes.data()}, order.data(), top_down,
                top_down_groups.data());
    test::build_nodes_karras(sort.keys.data(), n, sort.element.data(), order.data(), leaf_size, karras,
                             karras_groups.data());
    ASSERT_EQ(top_down.size(), karras.size()) << what << " n " << n << " leaf size " << leaf_size;
    for (size_t i = 0; i < karras.size(); ++i)
      ASSERT_EQ(std::memcmp(&top_down[i], &karras[i], sizeof(BvhNode)), 0)
          << what << " n " << n << " leaf size " << leaf_size << ": node " << i << " (left " << top_down[i].left
          << "/" << karras[i].left << ", right " << top_down[i].right << "/" << karras[i].right << ", parent "
          << top_down[i].parent << "/" << karras[i].parent << ", split " << top_down[i].split << "/"
          << karras[i].split << ")";
    EXPECT_EQ(std::memcmp(top_down_groups.data(), karras_groups.data(), karras_groups.size() * sizeof(BoxGroup)), 0)
        << what << " n " << n << " leaf size " << leaf_size << ": leaf boxes";
  };
  for (int n : {2, 3, 5, 15, 16, 17, 18, 33, 100, 1000, 20000, 70000}) {
    const std::vector<Box> spread = random_boxes(rng, n, rng.uniform(0.1f, 10.0f));
    std::vector<Box> ties(size_t(n), Box{{1, 2, 3}, {1, 2, 3}});
    std::vector<Box> half = spread;
    for (size_t i = 0; i < half.size(); i += 2) half[i] = ties[i];
    for (int32_t leaf_size : {1, 2, 4, 7, kLeafSize}) {
      check(spread, leaf_size, "random boxes");
      check(ties, leaf_size, "coincident boxes");
      check(half, leaf_size, "half coincident");
    }
  }
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

// A tree that keeps its build scratch (reserve_build) rebuilds record for record as a fresh
// tree builds, whatever sizes came before (the kept leaf order, keys and Karras nodes of an
// earlier build must not leak into a later one), and counts the scratch it keeps in bytes().
TEST(Bvh, a_tree_that_keeps_its_scratch_rebuilds_as_a_fresh_one) {
  test::Random rng(test::fresh_seed());
  CpuTree kept;
  kept.reserve_build(3000);
  const size_t bare = [] {
    CpuTree t;
    return t.bytes();
  }();
  EXPECT_GE(kept.bytes(), bare + 3000 * 44) << "the reserved scratch shows in bytes()";
  for (int n : {3000, 3000, 17, 1, 0, 2, 5000, 3000}) {
    const std::vector<Box> boxes = random_boxes(rng, n, rng.uniform(0.5f, 5.0f));
    CpuTree fresh;
    fresh.build(GivenBoxes{boxes.data()}, n);
    kept.build(GivenBoxes{boxes.data()}, n);
    ASSERT_EQ(kept.nodes().size(), fresh.nodes().size()) << "n " << n;
    EXPECT_EQ(std::memcmp(kept.nodes().data(), fresh.nodes().data(), fresh.nodes().size() * sizeof(BvhNode)), 0)
        << "n " << n;
    EXPECT_EQ(kept.sorted_prims(), fresh.sorted_prims()) << "n " << n;
    EXPECT_EQ(std::memcmp(kept.leaf_groups(), fresh.leaf_groups(), size_t(box_group_count(n)) * sizeof(BoxGroup)), 0)
        << "n " << n;
    EXPECT_EQ(kept.cost_at_build(), fresh.cost_at_build()) << "n " << n;
    check_tree(kept, boxes);
    EXPECT_GE(kept.bytes(), fresh.bytes() + size_t(std::max(n, 3000)) * 44) << "n " << n;
  }
}

// The build's radix sort equals a stable sort by key, for any size (one block or many), key
// width, and share of ties (equal keys keep their order: the CUDA sort's index tie-break), and
// when whole digits are shared by every key (those passes are skipped). distinct -1: keys in a
// few clusters of shared top bits with distinct low bits, so that the runs of shared top bits
// the one-thread sort finishes are long (past the insertion sort's) as well as short.
TEST(Bvh, radix_sort_of_pairs_is_a_stable_sort_by_key) {
  test::Random rng(test::fresh_seed());
  for (const int64_t n : {0, 1, 2, 3, 100, 5000, 16383, 70001}) {
    for (const int bits : {1, 8, 13, 63, 64}) {
      for (const int distinct : {1, 7, 1 << 20, -1}) {
        HostVector<uint64_t> keys(static_cast<size_t>(n));
        HostVector<int32_t> values(static_cast<size_t>(n));
        const uint64_t mask = bits == 64 ? ~0ull : (1ull << bits) - 1;
        const uint64_t high = (uint64_t(rng.integer(0, INT32_MAX)) << 33) & mask;  // a shared high part
        for (int64_t i = 0; i < n; ++i) {
          const uint64_t low = uint64_t(rng.integer(0, distinct == -1 ? INT32_MAX : distinct - 1)) * 0x9e3779b97f4a7c15ull;
          const uint64_t cluster = uint64_t(rng.integer(0, 63)) << (bits > 16 ? bits - 16 : 0);
          keys[size_t(i)] = (distinct == 7 ? high | (low >> 61) : distinct == -1 ? cluster | (low >> 40) : low) & mask;
          values[size_t(i)] = int32_t(i);
        }
        std::vector<std::pair<uint64_t, int32_t>> expected(static_cast<size_t>(n));
        for (int64_t i = 0; i < n; ++i) expected[size_t(i)] = {keys[size_t(i)], values[size_t(i)]};
        std::stable_sort(expected.begin(), expected.end(),
                         [](const auto& a, const auto& b) { return a.first < b.first; });
        radix_sort_pairs(keys, values, bits);
        ASSERT_EQ(keys.size(), size_t(n));
        for (int64_t i = 0; i < n; ++i) {
          ASSERT_EQ(keys[size_t(i)], expected[size_t(i)].first) << "n " << n << " bits " << bits << " at " << i;
          ASSERT_EQ(values[size_t(i)], expected[size_t(i)].second) << "n " << n << " bits " << bits << " at " << i;
        }
      }
    }
  }
}

// Canonical order on the CPU (cpu::sort_pairs): lexicographic, for counts on either side of
// the one-thread threshold, ids from small to the largest an int32 holds, and as many pairs per
// first id as a dense query gives.
TEST(Bvh, canonical_sort_of_pairs_is_lexicographic) {
  test::Random rng(test::fresh_seed());
  for (const int64_t n : {0, 1, 2, 4095, 4096, 4097, 70001}) {
    for (const int32_t largest : {1, 300, 1 << 20, INT32_MAX}) {
      std::vector<std::pair<int32_t, int32_t>> expected(static_cast<size_t>(n));
      for (auto& [first, second] : expected) first = rng.integer(0, largest), second = rng.integer(0, largest);
      std::sort(expected.begin(), expected.end());
      expected.erase(std::unique(expected.begin(), expected.end()), expected.end());  // pairs are distinct
      std::vector<std::pair<int32_t, int32_t>> shuffled = expected;
      std::shuffle(shuffled.begin(), shuffled.end(), rng.engine);
      std::vector<int32_t> pairs;
      for (const auto& [first, second] : shuffled) pairs.insert(pairs.end(), {first, second});
      cpu::sort_pairs(pairs.data(), int64_t(shuffled.size()));
      for (size_t i = 0; i < expected.size(); ++i) {
        ASSERT_EQ(pairs[2 * i], expected[i].first) << "n " << n << " largest " << largest << " at " << i;
        ASSERT_EQ(pairs[2 * i + 1], expected[i].second) << "n " << n << " largest " << largest << " at " << i;
      }
    }
  }
}

// The leaf scan tests four boxes at a time (vector lanes on the host): for every range of a
// short sorted sequence, aligned to the groups of four or not, and every `after`, it must
// report exactly the positions whose box passes the shape's own test, in order, counting one
// node test per position scanned. Every fifth query point sits r beyond a box's face (a tie up
// to rounding).
TEST(Bvh, leaf_scan_four_at_a_time_matches_the_test_box_by_box) {
  test::Random rng(test::fresh_seed());
  const int32_t n = 23;
  std::vector<Box> boxes = random_boxes(rng, n, 1.0f);
  std::vector<BoxGroup> groups(static_cast<size_t>(box_group_count(n)));
  std::vector<int32_t> prims(static_cast<size_t>(n));
  for (int32_t p = 0; p < n; ++p) {
    set_group_box(groups[size_t(p >> 2)], p & 3, boxes[size_t(p)]);
    prims[size_t(p)] = 100 + p;
  }
  for (int trial = 0; trial < 50; ++trial) {
    const Vec3 c = rng.vec3(-1.0f, 1.0f);
    const float r = rng.uniform(0.0f, 0.5f);
    const Box& tie = boxes[size_t(rng.integer(0, n - 1))];
    const BoxShape shape = trial % 5 == 0 ? BoxShape{{tie.hi.x + r, c.y, c.z}, {tie.hi.x + r, c.y, c.z}, r}
                                          : BoxShape::from({c, c, r});
    for (int32_t first = 0; first < n; ++first)
      for (int32_t last = first; last < n; ++last)
        for (int32_t after = first - 2; after <= last; ++after) {
          std::vector<int32_t> got, want;
          auto on_hits = [&](int64_t base, unsigned hits, const BoxGroup& group) {
            EXPECT_EQ(base % 4, 0);
            EXPECT_EQ(&group, &groups[size_t(base / 4)]);
            for (int k = 0; k < 4; ++k)
              if (hits >> k & 1u) got.push_back(prims[size_t(base + k)]);
          };
          WorkCounts work;
          scan_leaves(groups.data(), shape, first, last, after, on_hits, work);
          for (int32_t p = std::max(first, after + 1); p <= last; ++p)
            if (shape.overlaps(boxes[size_t(p)])) want.push_back(100 + p);
          ASSERT_EQ(got, want) << "range " << first << ".." << last << " after " << after;
          EXPECT_EQ(work.node_tests, uint64_t(std::max(0, last - std::max(first, after + 1) + 1)));
        }
    // The lane test itself, for every lane mask.
    for (size_t g = 0; g < groups.size(); ++g)
      for (unsigned lanes = 0; lanes < 16; ++lanes) {
        unsigned want = 0;
        for (int k = 0; k < 4; ++k)
          if ((lanes >> k & 1u) && shape.overlaps(group_box(groups[g], k))) want |= 1u << k;
        ASSERT_EQ(shape.overlaps_group(groups[g], lanes), want) << "group " << g << " lanes " << lanes;
      }
  }
}

// Each shape's test on a group of four boxes (4-float lanes on the host, their own selects for
// min_num, max_num and next_down) gives, lane by lane, the verdict of its scalar test, which the
// CUDA backend runs: on random boxes and on the edge cases of the scalar code's branches (gaps
// of exactly r, a bound stepping from 0 or overflowing to -inf, segment directions that are 0,
// subnormal or huge on an axis, empty boxes, mixed signs of zero).
template <class Shape>
void expect_group_test_matches_scalar(test::Random& rng) {
  const float special[] = {0.0f, -0.0f, 1.40129846e-45f, 1.17549435e-38f, 1e-30f, 1.0f, 1e30f, FLT_MAX, INFINITY};
  auto pick = [&](float typical) {
    const float v = rng.integer(0, 2) == 0 ? special[rng.integer(0, 8)] : typical;
    return rng.integer(0, 1) ? v : -v;
  };
  for (int trial = 0; trial < 4000; ++trial) {
    const float scale = rng.log_uniform(1e-20f, 1e20f);
    const Vec3 offset = rng.integer(0, 3) == 0 ? rng.vec3(-1e7f, 1e7f) : Vec3{0, 0, 0};
    Vec3 p0 = offset + scale * rng.vec3(-1.0f, 1.0f);
    Vec3 p1 = p0 + scale * rng.vec3(-1.0f, 1.0f);
    for (int axis = 0; axis < 3; ++axis) {
      const int kind = rng.integer(0, 6);
      float& c0 = axis == 0 ? p0.x : (axis == 1 ? p0.y : p0.z);
      float& c = axis == 0 ? p1.x : (axis == 1 ? p1.y : p1.z);
      if (kind == 0) c = c0;                                        // d == 0 on this axis
      if (kind == 1) c0 = 0.0f, c = pick(1.40129846e-45f);          // from 0: a subnormal or special d
      if (kind == 2 && std::fabs(c0) < 1e30f) c = c0 + pick(1e30f);  // huge
    }
    const float r = rng.integer(0, 4) == 0 ? std::fabs(pick(scale)) : scale * rng.uniform(0.0f, 0.5f);
    if (!std::isfinite(r) || !std::isfinite(p1.x) || !std::isfinite(p1.y) || !std::isfinite(p1.z)) continue;
    const Shape shape = Shape::from({p0, p1, r});
    BoxGroup group;
    for (int k = 0; k < 4; ++k) {
      Box b = rng.box(p0 + scale * rng.vec3(-1.0f, 1.0f), scale);
      switch (rng.integer(0, 6)) {
        case 0: b.lo.x = p0.x + r, b.hi.x = std::max(b.hi.x, b.lo.x); break;  // gap of exactly r
        case 1: b.hi.y = p0.y - r, b.lo.y = std::min(b.lo.y, b.hi.y); break;
        case 2: b = {{r, -r, pick(1.0f)}, {r, -r, FLT_MAX}}; break;  // bounds - r or + r reach 0
        case 3: b = {{-FLT_MAX, pick(scale), -FLT_MAX}, {FLT_MAX, FLT_MAX, FLT_MAX}}; break;
        case 4: b = Box::empty(); break;
        default: break;
      }
      set_group_box(group, k, b);
    }
    for (unsigned lanes = 0; lanes < 16; ++lanes) {
      unsigned want = 0;
      for (int k = 0; k < 4; ++k)
        if ((lanes >> k & 1u) && shape.overlaps(group_box(group, k))) want |= 1u << k;
      ASSERT_EQ(shape.overlaps_group(group, lanes), want)
          << "trial " << trial << " lanes " << lanes << " p0 " << p0.x << " " << p0.y << " " << p0.z << " p1 " << p1.x
          << " " << p1.y << " " << p1.z << " r " << r;
    }
  }
}

TEST(Bvh, group_tests_of_every_shape_match_the_scalar_tests) {
  test::Random rng(test::fresh_seed());
  expect_group_test_matches_scalar<BoxShape>(rng);
  expect_group_test_matches_scalar<SphereShape>(rng);
  expect_group_test_matches_scalar<CapsuleRayShape>(rng);
  expect_group_test_matches_scalar<CapsuleExactShape>(rng);
}

// A point (p0 == p1) under the segment shapes gets the point shapes' verdicts exactly:
// capsule_ray the box mode's, capsule_exact the sphere mode's (a still vertex of a swept scene
// then gives the static pairs; fuzz/RESULTS.md, bug 7), scalar and four lanes at once, on boxes
// at gaps from just inside r to just past the sphere test's slack.
TEST(Bvh, segment_shapes_of_a_point_are_the_point_shapes) {
  test::Random rng(test::fresh_seed());
  for (int trial = 0; trial < 2000; ++trial) {
    const float scale = rng.log_uniform(1e-20f, 1e20f);
    const Vec3 p = (rng.integer(0, 1) ? rng.vec3(-1e4f, 1e4f) : Vec3{0, 0, 0}) + scale * rng.vec3(-1.0f, 1.0f);
    const float r = scale * rng.uniform(0.0f, 1.0f);
    const QueryGeometry q{p, p, r};
    const BoxShape box = BoxShape::from(q);
    const SphereShape sphere = SphereShape::from(q);
    const CapsuleRayShape ray = CapsuleRayShape::from(q);
    const CapsuleExactShape exact = CapsuleExactShape::from(q);
    BoxGroup group;
    for (int k = 0; k < 4; ++k) {
      // A box beside p along one or two axes, its near faces at r (1 + j 1e-6) from p.
      const float gap = r * (1.0f + float(rng.integer(-2, 20)) * 1e-6f);
      const float side = rng.uniform(0.0f, 1.0f) * gap;
      Box b = rng.box(p, scale);
      b.lo.x = p.x + gap, b.hi.x = std::max(b.hi.x, b.lo.x);
      if (rng.integer(0, 1)) b.hi.y = p.y - side, b.lo.y = std::min(b.lo.y, b.hi.y);
      set_group_box(group, k, b);
      EXPECT_EQ(ray.overlaps(b), box.overlaps(b)) << "trial " << trial << " box " << k;
      EXPECT_EQ(exact.overlaps(b), sphere.overlaps(b)) << "trial " << trial << " box " << k;
    }
    for (unsigned lanes = 0; lanes < 16; ++lanes) {
      ASSERT_EQ(ray.overlaps_group(group, lanes), box.overlaps_group(group, lanes)) << "trial " << trial;
      ASSERT_EQ(exact.overlaps_group(group, lanes), sphere.overlaps_group(group, lanes)) << "trial " << trial;
    }
  }
}

}  // namespace
}  // namespace minkq
