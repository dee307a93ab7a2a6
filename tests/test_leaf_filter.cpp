// The leaf filter (leaf_filter.h) a group of hits at a time: the incidence test on four edges or
// triangles in leaf order (LeafGroup) against share_vertex / has_vertex one by one; the EE, EV
// and VT queries over the elements in leaf order giving, into a pair emitter and a count-only
// one, the same count and work, and the pairs of the by-id verdict (testing/by_id_queries.h)
// applied to every pair; and a refit from the elements in leaf order (LeafBoxes) giving the
// tree a refit by id gives.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <type_traits>
#include <vector>

#include "cpu/passes.h"
#include "cpu/tree.h"
#include "by_id_queries.h"
#include "minkq/leaf_filter.h"
#include "test_util.h"

namespace minkq {
namespace {

// Elements (edges, triangles) over few vertices, so that many share one; some degenerate (a
// vertex repeated).
template <class Prim>
std::vector<Prim> random_elements(test::Random& rng, int32_t n, int32_t vertices) {
  std::vector<Prim> elements(static_cast<size_t>(n));
  for (Prim& e : elements)
    for (int j = 0; j < LeafGroup<Prim>::kVertices; ++j)
      e.v[j] = j > 0 && rng.integer(0, 9) == 0 ? e.v[0] : rng.integer(0, vertices - 1);
  return elements;
}
std::vector<Edge> random_edges(test::Random& rng, int32_t n, int32_t vertices) {
  return random_elements<Edge>(rng, n, vertices);
}
std::vector<Triangle> random_triangles(test::Random& rng, int32_t n, int32_t vertices) {
  return random_elements<Triangle>(rng, n, vertices);
}

// The n elements in the leaf order `sorted` (fill_leaf_group over every group).
template <class Prim>
std::vector<LeafGroup<Prim>> leaf_groups(const std::vector<Prim>& elements, const int32_t* sorted, int32_t n) {
  std::vector<LeafGroup<Prim>> groups(static_cast<size_t>(box_group_count(n)));
  for (int64_t g = 0; g < int64_t(groups.size()); ++g) fill_leaf_group(g, elements.data(), sorted, n, groups[size_t(g)]);
  return groups;
}

// The groups of elements in a shuffled leaf order hold them lane by lane (lanes past the last:
// -1), give them back by id, and incident_lanes(v, w) is has_vertex(v) || has_vertex(w) lane by
// lane (for edges: share_vertex with the edge v-w).
template <class Prim>
void check_incidence(test::Random& rng) {
  constexpr int kVertices = LeafGroup<Prim>::kVertices;
  for (int trial = 0; trial < 20; ++trial) {
    const int32_t n = rng.integer(1, 41), vertices = rng.integer(1, 12);
    const std::vector<Prim> elements = random_elements<Prim>(rng, n, vertices);
    std::vector<int32_t> sorted(static_cast<size_t>(n));
    for (int32_t p = 0; p < n; ++p) sorted[size_t(p)] = p;
    std::shuffle(sorted.begin(), sorted.end(), rng.engine);
    const std::vector<LeafGroup<Prim>> groups = leaf_groups(elements, sorted.data(), n);
    Prim unset;
    for (int j = 0; j < kVertices; ++j) unset.v[j] = -7;
    std::vector<Prim> back(static_cast<size_t>(n), unset);
    for (int64_t g = 0; g < int64_t(groups.size()); ++g) scatter_leaf_group(g, groups[size_t(g)], sorted.data(), n, back.data());
    for (int32_t e = 0; e < n; ++e)
      for (int j = 0; j < kVertices; ++j) ASSERT_EQ(back[size_t(e)].v[j], elements[size_t(e)].v[j]) << "element " << e << " back by id";
    for (int64_t g = 0; g < int64_t(groups.size()); ++g)
      for (int k = 0; k < 4; ++k) {
        const int64_t p = 4 * g + k;
        for (int j = 0; j < kVertices; ++j)
          EXPECT_EQ(groups[size_t(g)].v[j][k], p < n ? elements[size_t(sorted[size_t(p)])].v[j] : -1);
      }
    for (int32_t v = 0; v <= vertices; ++v)  // vertex `vertices` is on no element
      for (int32_t w = 0; w <= vertices; ++w)
        for (size_t g = 0; g < groups.size(); ++g)
          for (unsigned lanes = 0; lanes < 16; ++lanes) {
            unsigned either = 0, has = 0;  // lanes past the last element: never incident
            for (int k = 0; k < 4; ++k) {
              const int64_t p = int64_t(4 * g) + k;
              if (!(lanes >> k & 1u) || p >= n) continue;
              const Prim e = elements[size_t(sorted[size_t(p)])];
              if (has_vertex(e, v) || has_vertex(e, w)) either |= 1u << k;
              if (has_vertex(e, v)) has |= 1u << k;
              if constexpr (std::is_same<Prim, Edge>::value) ASSERT_EQ(share_vertex(Edge{{v, w}}, e), (either >> k & 1u) != 0);
            }
            ASSERT_EQ(incident_lanes(groups[g], v, w, lanes), either)
                << "vertices " << v << ", " << w << " group " << g << " lanes " << lanes;
            ASSERT_EQ(incident_lanes(groups[g], v, v, lanes), has) << "vertex " << v << " group " << g << " lanes " << lanes;
          }
  }
}

TEST(LeafFilter, incidence_of_four_edges_at_once_matches_share_vertex_and_has_vertex) {
  test::Random rng(test::fresh_seed());
  check_incidence<Edge>(rng);
}

TEST(LeafFilter, incidence_of_four_triangles_at_once_matches_has_vertex) {
  test::Random rng(test::fresh_seed());
  check_incidence<Triangle>(rng);
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
  PairCounter count;  // the count-only emitter of both backends
  for (int32_t i = 0; i < n; ++i) {
    if (count_only) run_query<Shape>(bvh, queries, i, count, run.work);
    else run_query<Shape>(bvh, queries, i, emit, run.work);
  }
  run.counted = count_only ? count.counted : run.pairs.size();
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

// The same pairs in any order.
void expect_same_set(std::vector<Pair> got, std::vector<Pair> want, const char* what) {
  auto before = [](Pair a, Pair b) { return a.first != b.first ? a.first < b.first : a.second < b.second; };
  std::sort(got.begin(), got.end(), before);
  std::sort(want.begin(), want.end(), before);
  ASSERT_EQ(got.size(), want.size()) << what;
  for (size_t k = 0; k < want.size(); ++k) {
    ASSERT_EQ(got[k].first, want[k].first) << what << " pair " << k;
    ASSERT_EQ(got[k].second, want[k].second) << what << " pair " << k;
  }
}

// Emitted and counted: one result; and the pairs those of the by-id verdict (accept) over every
// pair whose box test passes.
template <class Shape>
void check_sources(const std::vector<Vec3>& vertices, const std::vector<Edge>& edges, float r, uint32_t filters) {
  const int32_t n = int32_t(edges.size()), nv = int32_t(vertices.size());
  CpuTree tree;
  tree.build(EdgeBoxes{vertices.data(), edges.data()}, n);
  const BvhView bvh = tree.view();
  const std::vector<EdgeGroup> groups = leaf_groups(edges, bvh.sorted_prims, n);
  std::vector<int32_t> order(static_cast<size_t>(nv));
  for (int32_t v = 0; v < nv; ++v) order[size_t(v)] = nv - 1 - v;

  const EdgeEdgeQueries ee{vertices.data(), groups.data(), bvh.sorted_prims, r, filters};
  const EdgeEdgeById ee_by_id{ee, edges.data()};
  const Run by_edge = run_all<Shape>(bvh, ee, n, false);
  expect_same(by_edge, run_all<Shape>(bvh, ee, n, true), "EE, counted");
  std::vector<Pair> want;
  const EdgeBoxes boxes{vertices.data(), edges.data()};
  for (int32_t p = 0; p < n; ++p) {
    const int32_t e = bvh.sorted_prims[p];
    for (int32_t s = p + 1; s < n; ++s) {
      const int32_t f = bvh.sorted_prims[s];
      if (Shape::from(ee_by_id.geometry(e)).overlaps(boxes(f)) && ee_by_id.template accept<Shape>(e, f))
        want.push_back(ee_by_id.pair(e, f));
    }
  }
  expect_same_set(by_edge.pairs, want, "EE");

  if constexpr (is_box_shape<Shape>()) {  // EV: point queries take the point shapes
    const VertexEdgeQueries ev{vertices.data(), groups.data(), order.data(), r, filters};
    const VertexEdgeById ev_by_id{ev, edges.data()};
    const Run ev_by_edge = run_all<Shape>(bvh, ev, nv, false);
    expect_same(ev_by_edge, run_all<Shape>(bvh, ev, nv, true), "EV, counted");
    size_t k = 0;
    for (int32_t i = 0; i < nv; ++i) {
      const int32_t v = order[size_t(i)];
      std::vector<Pair> of_v;
      for (int32_t s = 0; s < n; ++s) {
        const int32_t f = bvh.sorted_prims[s];
        if (Shape::from(ev_by_id.geometry(v)).overlaps(boxes(f)) && ev_by_id.template accept<Shape>(v, f))
          of_v.push_back({v, f});
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

TEST(LeafFilter, ee_and_ev_over_edges_in_leaf_order_give_the_by_id_verdicts_emitted_or_counted) {
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

// VT over the triangles in leaf order, emitted and counted: one result; the pairs those of the
// by-id verdict (accept) over every pair whose box test passes.
template <class Shape>
void check_vt_sources(const std::vector<Vec3>& vertices, const std::vector<Triangle>& triangles, float r,
                      uint32_t filters) {
  const int32_t n = int32_t(triangles.size()), nv = int32_t(vertices.size());
  CpuTree tree;
  tree.build(TriangleBoxes{vertices.data(), triangles.data()}, n);
  const BvhView bvh = tree.view();
  const std::vector<TriangleGroup> groups = leaf_groups(triangles, bvh.sorted_prims, n);
  std::vector<int32_t> order(static_cast<size_t>(nv));
  for (int32_t v = 0; v < nv; ++v) order[size_t(v)] = nv - 1 - v;

  const VertexTriangleQueries leaf{vertices.data(), groups.data(), order.data(), r, filters};
  const VertexTriangleById by_id{leaf, triangles.data()};
  const Run run = run_all<Shape>(bvh, leaf, nv, false);
  expect_same(run, run_all<Shape>(bvh, leaf, nv, true), "VT, counted");
  std::vector<Pair> want;
  const TriangleBoxes boxes{vertices.data(), triangles.data()};
  for (int32_t v = 0; v < nv; ++v)
    for (int32_t t = 0; t < n; ++t)
      if (Shape::from(by_id.geometry(v)).overlaps(boxes(t)) && by_id.template accept<Shape>(v, t)) want.push_back({v, t});
  expect_same_set(run.pairs, want, "VT");
}

TEST(LeafFilter, vt_over_triangles_in_leaf_order_gives_the_by_id_verdicts_emitted_or_counted) {
  test::Random rng(test::fresh_seed());
  for (int trial = 0; trial < 6; ++trial) {
    const int32_t nv = rng.integer(3, 300), n = rng.integer(1, 500);
    std::vector<Vec3> vertices(static_cast<size_t>(nv));
    for (Vec3& v : vertices) v = rng.vec3(-1.0f, 1.0f);
    const std::vector<Triangle> triangles = random_triangles(rng, n, nv);
    const float r = rng.log_uniform(1e-3f, 0.3f);
    for (uint32_t filters : {0u, kDropIncident, kLeafExact, kDropIncident | kLeafExact}) {
      SCOPED_TRACE(testing::Message() << "triangles " << n << " vertices " << nv << " r " << r << " filters " << filters);
      check_vt_sources<BoxShape>(vertices, triangles, r, filters);
      check_vt_sources<SphereShape>(vertices, triangles, r, filters);
    }
  }
}

// Node records and leaf boxes, bit for bit.
void expect_same_tree(const CpuTree& a, const CpuTree& b, const char* what) {
  ASSERT_EQ(a.nodes().size(), b.nodes().size()) << what;
  ASSERT_EQ(0, std::memcmp(a.nodes().data(), b.nodes().data(), a.nodes().size() * sizeof(BvhNode))) << what;
  ASSERT_EQ(0, std::memcmp(a.leaf_groups(), b.leaf_groups(), size_t(box_group_count(a.size())) * sizeof(BoxGroup)))
      << what;
}

TEST(LeafFilter, a_refit_from_elements_in_leaf_order_equals_one_by_id) {
  test::Random rng(test::fresh_seed());
  for (int trial = 0; trial < 8; ++trial) {
    const int32_t nv = rng.integer(3, 300), n = rng.integer(1, 600);
    SCOPED_TRACE(testing::Message() << "elements " << n << " vertices " << nv);
    std::vector<Vec3> vertices(static_cast<size_t>(nv)), moved(static_cast<size_t>(nv));
    for (Vec3& v : vertices) v = rng.vec3(-1.0f, 1.0f);
    for (Vec3& v : moved) v = rng.vec3(-2.0f, 2.0f);
    const std::vector<Triangle> triangles = random_triangles(rng, n, nv);
    const std::vector<Edge> edges = random_edges(rng, n, nv);
    CpuTree by_id, leaf, edges_by_id, edges_leaf;
    by_id.build(TriangleBoxes{vertices.data(), triangles.data()}, n);
    leaf.build(TriangleBoxes{vertices.data(), triangles.data()}, n);
    edges_by_id.build(EdgeBoxes{vertices.data(), edges.data()}, n);
    edges_leaf.build(EdgeBoxes{vertices.data(), edges.data()}, n);
    const std::vector<TriangleGroup> tg = leaf_groups(triangles, leaf.view().sorted_prims, n);
    const std::vector<EdgeGroup> eg = leaf_groups(edges, edges_leaf.view().sorted_prims, n);
    for (const Vec3* at : {moved.data(), vertices.data()}) {  // the second swept: both positions
      const Vec3* at1 = at == vertices.data() ? moved.data() : nullptr;
      by_id.refit(TriangleBoxes{at, triangles.data(), at1});
      leaf.refit(LeafBoxes<Triangle>{at, tg.data(), at1});
      expect_same_tree(by_id, leaf, "triangle tree");
      edges_by_id.refit(EdgeBoxes{at, edges.data(), at1});
      edges_leaf.refit(LeafBoxes<Edge>{at, eg.data(), at1});
      expect_same_tree(edges_by_id, edges_leaf, "edge tree");
    }
  }
}

}  // namespace
}  // namespace minkq
