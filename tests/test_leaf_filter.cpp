// The leaf filter (queries.h) a group of hits at a time: the incidence test on four edges in leaf
// order (EdgeGroup) against share_vertex / has_vertex edge by edge, and the EE and EV queries
// with the edges in leaf order, without them (edge by edge) and pair by pair (accept) giving the
// same pairs, in the same order, with the same work counts, into a pair emitter and a count-only
// one.
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "cpu/passes.h"
#include "cpu/tree.h"
#include "minkq/queries.h"
#include "test_util.h"

namespace minkq {
namespace {

// Edges over few vertices, so that many share one; some degenerate (both ends the same vertex).
std::vector<Edge> random_edges(test::Random& rng, int32_t n, int32_t vertices) {
  std::vector<Edge> edges(static_cast<size_t>(n));
  for (Edge& e : edges) {
    e.v[0] = rng.integer(0, vertices - 1);
    e.v[1] = rng.integer(0, 9) == 0 ? e.v[0] : rng.integer(0, vertices - 1);
  }
  return edges;
}

TEST(LeafFilter, incidence_of_four_edges_at_once_matches_share_vertex_and_has_vertex) {
  test::Random rng(test::fresh_seed());
  for (int trial = 0; trial < 20; ++trial) {
    const int32_t n = rng.integer(1, 41), vertices = rng.integer(1, 12);
    const std::vector<Edge> edges = random_edges(rng, n, vertices);
    std::vector<int32_t> sorted(static_cast<size_t>(n));
    for (int32_t p = 0; p < n; ++p) sorted[size_t(p)] = p;
    std::shuffle(sorted.begin(), sorted.end(), rng.engine);
    std::vector<EdgeGroup> groups(static_cast<size_t>(box_group_count(n)));
    for (int64_t g = 0; g < int64_t(groups.size()); ++g) fill_edge_group(g, edges.data(), sorted.data(), n, groups[size_t(g)]);
    for (int64_t g = 0; g < int64_t(groups.size()); ++g)
      for (int k = 0; k < 4; ++k) {
        const int64_t p = 4 * g + k;
        const Edge want = p < n ? edges[size_t(sorted[size_t(p)])] : Edge{{-1, -1}};
        EXPECT_EQ(groups[size_t(g)].v[0][k], want.v[0]);
        EXPECT_EQ(groups[size_t(g)].v[1][k], want.v[1]);
      }
    for (int32_t v = 0; v <= vertices; ++v)  // vertex `vertices` is on no edge
      for (int32_t w = 0; w <= vertices; ++w) {
        const Edge query{{v, w}};
        for (size_t g = 0; g < groups.size(); ++g)
          for (unsigned lanes = 0; lanes < 16; ++lanes) {
            unsigned shares = 0, has = 0;  // lanes past the last edge: never incident
            for (int k = 0; k < 4; ++k) {
              const int64_t p = int64_t(4 * g) + k;
              if (!(lanes >> k & 1u) || p >= n) continue;
              const Edge e = edges[size_t(sorted[size_t(p)])];
              if (share_vertex(query, e)) shares |= 1u << k;
              if (has_vertex(e, v)) has |= 1u << k;
            }
            ASSERT_EQ(incident_lanes(groups[g], v, w, lanes), shares)
                << "edge " << v << "-" << w << " group " << g << " lanes " << lanes;
            ASSERT_EQ(incident_lanes(groups[g], v, v, lanes), has) << "vertex " << v << " group " << g << " lanes " << lanes;
          }
      }
  }
}

// Pairs in the order met and the work, through run_query, into a pair emitter or counted.
struct Run {
  std::vector<Pair> pairs;
  uint64_t counted = 0;
  WorkCounts work;
};
template <class Shape, class Queries>
Run run_all(const BvhView& bvh, const Queries& queries, int32_t n, bool count_only) {
  Run run;
  auto emit = [&run](int32_t a, int32_t b) { run.pairs.push_back({a, b}); };
  cpu::CountPairs count{run.counted};  // the CPU backend's count-only emitter
  for (int32_t i = 0; i < n; ++i) {
    if (count_only) run_query<Shape>(bvh, queries, i, count, run.work);
    else run_query<Shape>(bvh, queries, i, emit, run.work);
  }
  if (!count_only) run.counted = run.pairs.size();
  return run;
}
// The same count and work; the same pairs in the same order where b emitted them (not only
// counted).
void expect_same(const Run& a, const Run& b, const char* what) {
  ASSERT_EQ(a.counted, b.counted) << what;
  EXPECT_EQ(a.work.nodes_visited, b.work.nodes_visited) << what;
  EXPECT_EQ(a.work.node_tests, b.work.node_tests) << what;
  EXPECT_EQ(a.work.primitive_tests, b.work.primitive_tests) << what;
  EXPECT_EQ(a.work.candidates, b.work.candidates) << what;
  if (b.pairs.empty()) return;
  ASSERT_EQ(a.pairs.size(), b.pairs.size()) << what;
  for (size_t k = 0; k < a.pairs.size(); ++k) {
    ASSERT_EQ(a.pairs[k].first, b.pairs[k].first) << what << ", pair " << k;
    ASSERT_EQ(a.pairs[k].second, b.pairs[k].second) << what << ", pair " << k;
  }
}

// With and without the leaf-ordered edges, emitted and counted: one result; and the pairs those
// of accept over every pair whose box test passes.
template <class Shape>
void check_sources(const std::vector<Vec3>& vertices, const std::vector<Edge>& edges, float r, uint32_t filters) {
  const int32_t n = int32_t(edges.size()), nv = int32_t(vertices.size());
  CpuTree tree;
  tree.build(EdgeBoxes{vertices.data(), edges.data()}, n);
  const BvhView bvh = tree.view();
  std::vector<EdgeGroup> groups(static_cast<size_t>(box_group_count(n)));
  for (int64_t g = 0; g < int64_t(groups.size()); ++g) fill_edge_group(g, edges.data(), bvh.sorted_prims, n, groups[size_t(g)]);
  std::vector<int32_t> order(static_cast<size_t>(nv));
  for (int32_t v = 0; v < nv; ++v) order[size_t(v)] = nv - 1 - v;

  EdgeEdgeQueries ee{vertices.data(), edges.data(), bvh.sorted_prims, r, filters};
  const Run by_edge = run_all<Shape>(bvh, ee, n, false);
  ee.leaf_edges = groups.data();
  expect_same(by_edge, run_all<Shape>(bvh, ee, n, false), "EE, edges in leaf order");
  expect_same(by_edge, run_all<Shape>(bvh, ee, n, true), "EE, counted");
  std::vector<Pair> want;
  const EdgeBoxes boxes{vertices.data(), edges.data()};
  for (int32_t p = 0; p < n; ++p) {
    const int32_t e = bvh.sorted_prims[p];
    for (int32_t s = p + 1; s < n; ++s) {
      const int32_t f = bvh.sorted_prims[s];
      if (Shape::from(ee.geometry(e)).overlaps(boxes(f)) && ee.template accept<Shape>(e, f)) want.push_back(ee.pair(e, f));
    }
  }
  std::vector<Pair> got = by_edge.pairs;  // in the order met; as sets
  auto before = [](Pair a, Pair b) { return a.first != b.first ? a.first < b.first : a.second < b.second; };
  std::sort(got.begin(), got.end(), before);
  std::sort(want.begin(), want.end(), before);
  ASSERT_EQ(got.size(), want.size());
  for (size_t k = 0; k < want.size(); ++k) {
    ASSERT_EQ(got[k].first, want[k].first) << "EE pair " << k;
    ASSERT_EQ(got[k].second, want[k].second) << "EE pair " << k;
  }

  if constexpr (is_box_shape<Shape>()) {  // EV: point queries take the point shapes
    VertexEdgeQueries ev{vertices.data(), edges.data(), order.data(), r, filters};
    const Run ev_by_edge = run_all<Shape>(bvh, ev, nv, false);
    ev.leaf_edges = groups.data();
    expect_same(ev_by_edge, run_all<Shape>(bvh, ev, nv, false), "EV, edges in leaf order");
    expect_same(ev_by_edge, run_all<Shape>(bvh, ev, nv, true), "EV, counted");
    size_t k = 0;
    for (int32_t i = 0; i < nv; ++i) {
      const int32_t v = order[size_t(i)];
      std::vector<Pair> of_v;
      for (int32_t s = 0; s < n; ++s) {
        const int32_t f = bvh.sorted_prims[s];
        if (Shape::from(ev.geometry(v)).overlaps(boxes(f)) && ev.template accept<Shape>(v, f)) of_v.push_back({v, f});
      }
      std::sort(of_v.begin(), of_v.end(), [](Pair a, Pair b) { return a.second < b.second; });
      std::vector<Pair> got(ev_by_edge.pairs.begin() + ptrdiff_t(k), ev_by_edge.pairs.begin() + ptrdiff_t(k + of_v.size()));
      std::sort(got.begin(), got.end(), [](Pair a, Pair b) { return a.second < b.second; });
      for (size_t j = 0; j < of_v.size(); ++j) {
        ASSERT_EQ(got[j].first, v) << "EV vertex " << v;
        ASSERT_EQ(got[j].second, of_v[j].second) << "EV vertex " << v;
      }
      k += of_v.size();
    }
    ASSERT_EQ(k, ev_by_edge.pairs.size());
  }
}

TEST(LeafFilter, ee_and_ev_give_the_same_pairs_and_work_with_edges_in_leaf_order_or_by_id) {
  test::Random rng(test::fresh_seed());
  for (int trial = 0; trial < 6; ++trial) {
    const int32_t nv = rng.integer(2, 400), n = rng.integer(1, 700);
    std::vector<Vec3> vertices(static_cast<size_t>(nv));
    for (Vec3& v : vertices) v = rng.vec3(-1.0f, 1.0f);
    const std::vector<Edge> edges = random_edges(rng, n, nv);
    const float r = rng.log_uniform(1e-3f, 0.3f);
    for (uint32_t filters : {0u, kDropIncident, kLeafExact, kDropIncident | kLeafExact}) {
      SCOPED_TRACE(testing::Message() << "edges " << n << " vertices " << nv << " r " << r << " filters " << filters);
      check_sources<BoxShape>(vertices, edges, r, filters);
      check_sources<CapsuleExactShape>(vertices, edges, r, filters);
    }
  }
}

}  // namespace
}  // namespace minkq
