// The walk of traversal.h against its definition: the leaf ranges a query meets, and, for a
// self-query (the half traversal), that the path down to its own leaf range is followed with no
// box test while every other child past it is tested exactly as a top-down walk tests it. And
// the host's packets (packet.h): each member's hits are those of its own traversal.
#include <gtest/gtest.h>

#include <algorithm>
#include <tuple>
#include <vector>

#include "cpu/tree.h"
#include "minkq/packet.h"
#include "minkq/shapes.h"
#include "minkq/traversal.h"
#include "test_util.h"

namespace minkq {
namespace {

// One link of the tree: a child (a node or a leaf range) covering sorted positions
// [first, last], with the box its parent stores for it.
struct Link {
  int32_t first, last;
  Box box;
};
// A leaf range with the links above it, the root's child first and its own link last.
struct RangePath {
  int32_t first, last;
  std::vector<Link> links;
};

void collect_ranges(const CpuTree& tree, int32_t node, int32_t first, int32_t last, std::vector<Link>& above,
                    std::vector<RangePath>& out) {
  const BvhNode& n = tree.nodes()[node];
  const int32_t child[2] = {n.left, n.right};
  const int32_t lo[2] = {first, n.split + 1}, hi[2] = {n.split, last};
  const Box box[2] = {n.left_box, n.right_box};
  for (int side = 0; side < 2; ++side) {
    if (child[side] == kNoChild) continue;
    above.push_back({lo[side], hi[side], box[side]});
    if (child[side] < 0) out.push_back({lo[side], hi[side], above});
    else collect_ranges(tree, child[side], lo[side], hi[side], above, out);
    above.pop_back();
  }
}

std::vector<RangePath> ranges_of(const CpuTree& tree) {
  std::vector<RangePath> out;
  std::vector<Link> above;
  if (tree.view().num_prims > 0) collect_ranges(tree, 0, 0, tree.view().num_prims - 1, above, out);
  return out;
}

// A shape that passes every box (kind 1), none (kind 0), or runs the box mode's test (kind 2),
// counting its tests.
struct CountingShape {
  int kind;
  BoxShape box;
  mutable uint64_t tests = 0;
  bool may_overlap(const Box& b) const {
    ++tests;
    return kind == 2 ? box.may_overlap(b) : kind == 1;
  }
};

using Met = std::tuple<int32_t, int32_t, bool>;  // first, last, own

// The definition: a leaf range holding positions past `after` is met when it holds `after`
// itself (own), or when its box and the box of every link above it that does not hold `after`
// pass; a link holding `after` (the path) is never tested. Tests: every link past `after`
// whose parent is reached, except those on the path.
void expect_walk_as_defined(const CpuTree& tree, const CountingShape& shape, int32_t after, const char* what) {
  std::vector<Met> got;
  auto on_range = [&](int32_t first, int32_t last, const Box&, bool own) {
    got.emplace_back(first, last, own);
    EXPECT_TRUE(own || shape.kind != 0) << what << ": a rejected range was met";
  };
  shape.tests = 0;
  WorkCounts work;
  walk(tree.view(), shape, after, on_range, work);
  EXPECT_EQ(work.node_tests, shape.tests) << what;

  std::vector<Met> want;
  auto holds = [after](const Link& l) { return l.first <= after && after <= l.last; };
  for (const RangePath& r : ranges_of(tree)) {
    if (r.last <= after) continue;
    bool reached = true;
    for (size_t k = 0; k < r.links.size() && reached; ++k) {
      const Link& l = r.links[k];
      if (!holds(l)) reached = shape.kind == 2 ? shape.box.may_overlap(l.box) : shape.kind == 1;
    }
    if (reached) want.emplace_back(r.first, r.last, holds(r.links.back()));
  }
  // Tests, counted over the distinct links: a link is tested when its parent is reached (every
  // link above it is on the path or passes) and it holds positions past `after` off the path.
  struct Key {
    int32_t first, last;
    bool operator<(const Key& o) const { return std::tie(first, last) < std::tie(o.first, o.last); }
  };
  std::vector<Key> tested;
  for (const RangePath& r : ranges_of(tree)) {
    bool parent_reached = true;
    for (const Link& l : r.links) {
      if (!parent_reached) break;
      if (l.last > after && !holds(l)) {
        tested.push_back({l.first, l.last});
        parent_reached = shape.kind == 2 ? shape.box.may_overlap(l.box) : shape.kind == 1;
      } else if (l.last <= after) {
        parent_reached = false;  // never entered: holds nothing past `after`
      }
    }
  }
  std::sort(tested.begin(), tested.end());
  const uint64_t tests = uint64_t(std::unique(tested.begin(), tested.end(), [](const Key& a, const Key& b) {
                     return a.first == b.first && a.last == b.last;
                   }) - tested.begin());
  std::vector<Met> sorted_got = got;
  std::sort(sorted_got.begin(), sorted_got.end());
  std::sort(want.begin(), want.end());
  EXPECT_EQ(sorted_got, want) << what;
  EXPECT_EQ(std::adjacent_find(sorted_got.begin(), sorted_got.end()), sorted_got.end()) << what << ": a range met twice";
  EXPECT_EQ(shape.tests, tests) << what;
}

TEST(Walk, meets_the_leaf_ranges_past_the_query_and_tests_none_on_its_path) {
  test::Random rng(27);
  for (int32_t n : {1, 2, 3, 5, 17, 64, 300}) {
    for (int32_t leaf_size : {1, 4, kLeafSize}) {
      std::vector<Box> boxes(static_cast<size_t>(n));
      for (Box& b : boxes) b = rng.box(rng.vec3(-1.0f, 1.0f), 0.1f);
      CpuTree tree;
      tree.build(GivenBoxes{boxes.data()}, n, BuildConfig{leaf_size});
      for (int32_t after = -1; after < n; ++after) {
        for (int kind = 0; kind < 3; ++kind) {
          const Vec3 c = rng.vec3(-1.0f, 1.0f);
          const CountingShape shape{kind, BoxShape::from({c, c, rng.uniform(0.0f, 0.6f)})};
          const std::string what = "n " + std::to_string(n) + " leaf size " + std::to_string(leaf_size) + " after " +
                                   std::to_string(after) + " shape " + std::to_string(kind);
          expect_walk_as_defined(tree, shape, after, what.c_str());
        }
      }
    }
  }
}

// A member's hits as (position) of each lane, in the order met.
struct Collect {
  std::vector<int64_t>* out;
  void operator()(int64_t base, unsigned hits, const BoxGroup&) const {
    for (; hits != 0; hits &= hits - 1u) out->push_back(base + lowest_bit(hits));
  }
};

// A member's hits as (base, lanes) of each group, in the order met.
struct Groups {
  std::vector<std::pair<int64_t, unsigned>>* out;
  void operator()(int64_t base, unsigned hits, const BoxGroup&) const { out->push_back({base, hits}); }
};

// A packet's kPacket members of one shape kind: random geometries (points and segments, radii
// from 0 up, sometimes the same query twice) and bounds (-1, or a self-query's position, up to
// past the last leaf).
template <class Shape>
void random_packet(test::Random& rng, const CpuTree& tree, int32_t n, Shape (&shapes)[kPacket],
                   int32_t (&bounds)[kPacket]) {
  const bool self = rng.integer(0, 1) == 1;
  const int32_t first_bound = self ? rng.integer(0, n) : -1;
  for (int j = 0; j < kPacket; ++j) {
    bounds[j] = self ? std::min(first_bound + j, n) : -1;
    Vec3 p0 = rng.vec3(-1.0f, 1.0f);
    Vec3 p1 = rng.integer(0, 2) == 0 ? p0 : p0 + rng.vec3(-0.3f, 0.3f);
    if (self && bounds[j] < n && rng.integer(0, 1) == 0) {  // a self-query: its own leaf's box, as EE's
      const Box own = group_box(tree.view().leaf_groups[bounds[j] >> 2], bounds[j] & 3);
      p0 = own.lo;
      p1 = own.hi;
    }
    const float r = rng.integer(0, 4) == 0 ? 0.0f : rng.log_uniform(1e-4f, 0.5f);
    shapes[j] = j > 0 && rng.integer(0, 5) == 0 ? shapes[j - 1] : Shape::from({p0, p1, r});
  }
}

// Packets of 1 to kPacket members (4, or 8 in the AVX2 build of this test), random_packet's:
// each member gets exactly its own traversal's hits, each once.
template <class Shape>
void expect_packets_as_alone(test::Random& rng, const CpuTree& tree, int32_t n, const std::string& what) {
  for (int trial = 0; trial < 40; ++trial) {
    const int count = rng.integer(1, kPacket);
    Shape shapes[kPacket];
    int32_t bounds[kPacket];
    random_packet(rng, tree, n, shapes, bounds);
    std::vector<int64_t> got[kPacket];
    Collect on_hits[kPacket];
    for (int j = 0; j < kPacket; ++j) on_hits[j].out = &got[j];
    traverse_packet(tree.view(), shapes, bounds, (1u << count) - 1u, on_hits);
    for (int j = 0; j < kPacket; ++j) {
      std::vector<int64_t> want;
      Collect alone{&want};
      NoWork work;
      if (j < count) traverse_groups(tree.view(), shapes[j], bounds[j], alone, work);
      std::sort(got[j].begin(), got[j].end());
      std::sort(want.begin(), want.end());
      EXPECT_EQ(got[j], want) << what << " trial " << trial << " member " << j << " of " << count;
      EXPECT_EQ(std::adjacent_find(got[j].begin(), got[j].end()), got[j].end()) << what << ": a hit twice";
    }
  }
}

// Members scanning a span of leaf positions together (scan_together; any span, aligned or not,
// longer than a leaf or the 32 positions of one pass, with bounds inside, before and past it):
// each member of the set gets its own scan's hits (scan_leaves) in the same groups, others none.
template <class Shape>
void expect_scans_together_as_alone(test::Random& rng, const CpuTree& tree, int32_t n, const std::string& what) {
  for (int trial = 0; trial < 40; ++trial) {
    Shape shapes[kPacket];
    int32_t bounds[kPacket];
    random_packet(rng, tree, n, shapes, bounds);
    const int32_t first = rng.integer(0, n - 2), last = rng.integer(first + 1, n - 1);
    const unsigned members = unsigned(rng.integer(1, (1 << kPacket) - 1));
    std::vector<std::pair<int64_t, unsigned>> got[kPacket];
    Groups on_hits[kPacket];
    for (int j = 0; j < kPacket; ++j) on_hits[j].out = &got[j];
    scan_together(tree.view().leaf_groups, PacketBoxes::of(shapes, bounds), shapes, bounds, first, last, members,
                  on_hits);
    for (int j = 0; j < kPacket; ++j) {
      std::vector<std::pair<int64_t, unsigned>> want;
      Groups alone{&want};
      NoWork work;
      if ((members >> j) & 1u) scan_leaves(tree.view().leaf_groups, shapes[j], first, last, bounds[j], alone, work);
      EXPECT_EQ(got[j], want) << what << " trial " << trial << " member " << j << " of set " << members << " span "
                              << first << ".." << last << " bound " << bounds[j];
    }
  }
}

TEST(Walk, members_scanning_a_span_together_get_their_own_scans) {
  test::Random rng(test::fresh_seed());
  for (int32_t n : {2, 3, 5, 17, 64, 300, 1000}) {
    std::vector<Box> boxes(static_cast<size_t>(n));
    for (Box& b : boxes) b = rng.box(rng.vec3(-1.0f, 1.0f), rng.log_uniform(1e-3f, 0.2f));
    CpuTree tree;
    tree.build(GivenBoxes{boxes.data()}, n, BuildConfig{kLeafSize});
    const std::string what = "n " + std::to_string(n);
    expect_scans_together_as_alone<BoxShape>(rng, tree, n, what + " box");
    expect_scans_together_as_alone<SphereShape>(rng, tree, n, what + " sphere");
    expect_scans_together_as_alone<CapsuleRayShape>(rng, tree, n, what + " capsule_ray");
    expect_scans_together_as_alone<CapsuleExactShape>(rng, tree, n, what + " capsule_exact");
  }
}

TEST(Walk, packets_give_each_member_its_own_hits_for_every_shape) {
  test::Random rng(test::fresh_seed());
  for (int32_t n : {1, 2, 3, 5, 17, 64, 300, 1000}) {
    for (int32_t leaf_size : {1, 4, kLeafSize}) {
      std::vector<Box> boxes(static_cast<size_t>(n));
      for (Box& b : boxes) b = rng.box(rng.vec3(-1.0f, 1.0f), rng.log_uniform(1e-3f, 0.2f));
      CpuTree tree;
      tree.build(GivenBoxes{boxes.data()}, n, BuildConfig{leaf_size});
      const std::string what = "n " + std::to_string(n) + " leaf size " + std::to_string(leaf_size);
      expect_packets_as_alone<BoxShape>(rng, tree, n, what + " box");
      expect_packets_as_alone<SphereShape>(rng, tree, n, what + " sphere");
      expect_packets_as_alone<CapsuleRayShape>(rng, tree, n, what + " capsule_ray");
      expect_packets_as_alone<CapsuleExactShape>(rng, tree, n, what + " capsule_exact");
    }
  }
}

}  // namespace
}  // namespace minkq
