// The contracts the compiler checks (detect.h): the library's own shapes, work types, box
// functors, query sources and emitters fulfil them (static_assert here; the executors are
// checked where the stores are instantiated, store.h), types lacking a member do not, and a
// shape written outside the library that fulfils the Shape contract gets exact results from the
// one traversal. contract_violation.cpp is compiled by a ctest that expects the compiler to
// name the missing member.
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "by_id_queries.h"
#include "cpu/passes.h"
#include "cpu/tree.h"
#include "minkq/leaf_filter.h"
#include "minkq/leaf_groups.h"
#include "test_util.h"

namespace minkq {
namespace {

// The library's types.
static_assert(ShapeContract<BoxShape>::value && ShapeContract<SphereShape>::value);
static_assert(ShapeContract<CapsuleRayShape>::value && ShapeContract<CapsuleExactShape>::value);
static_assert(WorkContract<WorkCounts>::value && WorkContract<NoWork>::value);
static_assert(BoxesContract<GivenBoxes>::value && BoxesContract<PointBoxes>::value);
static_assert(BoxesContract<TriangleBoxes>::value && BoxesContract<EdgeBoxes>::value);
static_assert(BoxesContract<LeafBoxes<Triangle>>::value && BoxesContract<LeafBoxes<Edge>>::value);
template <class Shape>
constexpr bool every_source_with() {
  return QuerySourceContract<VertexTriangleQueries, Shape>::value && QuerySourceContract<VertexEdgeQueries, Shape>::value &&
         QuerySourceContract<EdgeEdgeQueries, Shape>::value && QuerySourceContract<VertexVertexQueries, Shape>::value &&
         QuerySourceContract<UserQueries, Shape>::value;
}
static_assert(every_source_with<BoxShape>() && every_source_with<SphereShape>());
static_assert(every_source_with<CapsuleRayShape>() && every_source_with<CapsuleExactShape>());
static_assert(EmitContract<PairCounter>::value);
// The optional flags (detect.h's flag_set): set where a type declares them, false elsewhere.
static_assert(counts_only<PairCounter> && !counts_only<WorkCounts>);
static_assert(by_leaf_position<LeafBoxes<Edge>> && !by_leaf_position<GivenBoxes> && !by_leaf_position<EdgeBoxes>);

// Types that lack a member fail the traits (used where ShapeContract and the others would stop
// the compiler, with the messages contract_violation.cpp checks).
struct NoFiner {  // a shape without finer(): a single-primitive leaf range could not be tested
  static NoFiner from(const QueryGeometry&) { return {}; }
  bool may_overlap(const Box&) const { return true; }
  bool overlaps(const Box&) const { return true; }
  unsigned overlaps_group(const BoxGroup&, unsigned lanes) const { return lanes; }
};
static_assert(!is_shape<NoFiner> && !shape_contract::kFiner<NoFiner> && shape_contract::kOverlaps<NoFiner>);
struct NoGroupTest {  // overlaps_group taking the wrong arguments
  static NoGroupTest from(const QueryGeometry&) { return {}; }
  bool may_overlap(const Box&) const { return true; }
  bool overlaps(const Box&) const { return true; }
  bool finer(const Box&) const { return true; }
  unsigned overlaps_group(const Box&) const { return 0; }
};
static_assert(!is_shape<NoGroupTest>);
static_assert(!is_work<int> && !is_boxes<Box>);
// The by-id forms (testing/by_id_queries.h) answer for one pair only: not query sources.
static_assert(!is_query_source<EdgeEdgeById, BoxShape> && !is_query_source<VertexTriangleById, BoxShape>);
struct CountsWithoutAdd {  // says it only counts but cannot add a group's count
  static constexpr bool kCountsOnly = true;
  void operator()(int32_t, int32_t) {}
};
static_assert(!is_emitter<CountsWithoutAdd>);

// A shape from outside the library: the half-space x <= p0.x + r. Its test of a box (lo.x
// within the bound) is monotone under box inclusion, so it fulfils the contract's semantics
// as well as its members.
struct HalfSpaceShape {
  float x;
  static HalfSpaceShape from(const QueryGeometry& q) { return {q.p0.x + q.r}; }
  bool overlaps(const Box& b) const { return b.lo.x <= x; }
  bool may_overlap(const Box& b) const { return overlaps(b); }
  bool finer(const Box&) const { return true; }
  unsigned overlaps_group(const BoxGroup& g, unsigned lanes) const {
    return lanes_where(lanes, [&](int k) { return overlaps(group_box(g, k)); });
  }
};
static_assert(ShapeContract<HalfSpaceShape>::value);

TEST(Contracts, a_shape_from_outside_the_library_gets_exactly_the_boxes_it_overlaps) {
  test::Random rng(test::fresh_seed());
  for (int trial = 0; trial < 20; ++trial) {
    const int32_t n = rng.integer(1, 500);
    std::vector<Box> boxes(static_cast<size_t>(n));
    for (Box& b : boxes) b = box_expand(Box::of_point(rng.vec3(-1.0f, 1.0f)), rng.vec3(-1.0f, 1.0f));
    CpuTree tree;
    tree.build(GivenBoxes{boxes.data()}, n);
    const HalfSpaceShape shape = HalfSpaceShape::from({rng.vec3(-1.2f, 1.2f), {}, 0.0f});
    std::vector<int32_t> got, want;
    auto on_leaf = [&](int32_t prim, const Box&) { got.push_back(prim); };
    NoWork work;
    traverse(tree.view(), shape, -1, on_leaf, work);
    for (int32_t i = 0; i < n; ++i)
      if (shape.overlaps(boxes[size_t(i)])) want.push_back(i);
    std::sort(got.begin(), got.end());
    ASSERT_EQ(got, want) << "boxes " << n << " bound " << shape.x;
  }
}

}  // namespace
}  // namespace minkq
