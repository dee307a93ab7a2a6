// arborx_bench's run of one scene: both libraries' trees, every ArborX pair set checked against
// minkq's (with the helpers that compare sets and judge sphere boundary pairs), then the timed
// contestants of both libraries, round-robin.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iterator>
#include <optional>
#include <stdexcept>
#include <thread>

#include "arborx_bench.h"
#include "arborx_peer.h"
#include "cpu/tree.h"

namespace peer {
namespace {

// Whether the measured minkq's CpuTree can keep its build scratch (reserve_build, after
// 995a213): revisions before it get no "scratch kept" rows.
template <class Tree>
auto keep_scratch(Tree& tree, int32_t n, int) -> decltype(tree.reserve_build(n), true) {
  tree.reserve_build(n);
  return true;
}
template <class Tree>
bool keep_scratch(Tree&, int32_t, long) {
  return false;
}

// "equal (N pairs)" or the sizes of both differences.
Check compare(const std::string& kind, const PairSet& minkq_set, const PairSet& arborx_set) {
  Check c{kind, "", true};
  const uint64_t only_minkq = mb::missing(minkq_set, arborx_set), only_arborx = mb::missing(arborx_set, minkq_set);
  c.ok = only_minkq == 0 && only_arborx == 0;
  c.verdict = c.ok ? "equal (" + std::to_string(minkq_set.size()) + " pairs)"
                   : "DIFFER: " + std::to_string(only_minkq) + " only in minkq, " + std::to_string(only_arborx) +
                         " only in ArborX (of " + std::to_string(minkq_set.size()) + ")";
  return c;
}

// Pairs in one sorted set and not the other.
PairSet difference(const PairSet& a, const PairSet& b) {
  PairSet d;
  std::set_difference(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(d));
  return d;
}

// Distance in double from a vertex to a triangle's box (float corners are exact in double).
double point_box_distance(const Scene& s, int v, int t) {
  double d2 = 0;
  for (int k = 0; k < 3; ++k) {
    double lo = INFINITY, hi = -INFINITY;
    for (int j = 0; j < 3; ++j) {
      const double x = s.xyz[3 * size_t(s.mesh.tris[3 * size_t(t) + j]) + k];
      lo = std::min(lo, x);
      hi = std::max(hi, x);
    }
    const double p = s.xyz[3 * size_t(v) + k], g = std::max({lo - p, p - hi, 0.0});
    d2 += g * g;
  }
  return std::sqrt(d2);
}

// minkq's count: the count-only flag where the library has it, else a zero-capacity buffer
// (the exact count comes back with MINKQ_ERROR_CAPACITY, nothing written).
#if ARBORX_BENCH_MINKQ_COUNT_FLAG
constexpr uint32_t kCountFlags = MINKQ_QUERY_COUNT;
constexpr const char* kCountHow = "MINKQ_QUERY_COUNT";
#else
constexpr uint32_t kCountFlags = 0;
constexpr const char* kCountHow = "capacity 0";
#endif

minkq_query_info run_minkq(minkq_scene* scene, minkq_query_kind kind, minkq_mode mode, float r, int32_t* out,
                           size_t capacity, uint32_t flags = 0) {
  const minkq_query_desc q{kind, mode, flags, r};
  minkq_query_info info{};
  const minkq_status st = minkq_scene_query(scene, &q, out, capacity, MINKQ_MEMORY_HOST, &info);
  if (st != MINKQ_SUCCESS && !(st == MINKQ_ERROR_CAPACITY && capacity == 0)) mb::check(st, "minkq_scene_query");
  return info;
}
PairSet minkq_set(minkq_scene* scene, minkq_query_kind kind, minkq_mode mode, float r) {
  mb::Result result = mb::new_result();
  const minkq_query_desc q{kind, mode, MINKQ_QUERY_CANONICAL, r};
  mb::check(minkq_scene_query_result(scene, &q, result.get()), "minkq_scene_query_result");
  return mb::to_set(minkq_result_pairs(result.get()), minkq_result_count(result.get()));
}

}  // namespace

SceneResult run_scene(Scene sc, const Options& opt, const Exec& space, minkq_device* device) {
  SceneResult res;
  res.load_start = mb::load_average();
  const int nv = int(sc.mesh.vertex_count()), nt = int(sc.mesh.triangle_count()), ne = int(sc.mesh.edge_count());
  const float r = sc.r;
  std::fprintf(stderr, "arborx_bench: %s: %d vertices, %d triangles, %d edges, r = %.6g (%.3gx mean edge)\n",
               sc.name.c_str(), nv, nt, ne, double(r), sc.factor);

  // minkq: the scene (both trees, incident pairs dropped) and its edge numbering.
  mb::Scene scene = mb::create_scene(device, sc.xyz, sc.mesh.tris);
  {
    std::vector<int32_t> edges(2 * minkq_scene_edge_count(scene.get()));
    mb::check(minkq_scene_edges(scene.get(), edges.data(), edges.size() / 2), "minkq_scene_edges");
    if (edges != sc.mesh.edges) throw std::runtime_error(sc.name + ": minkq's edge numbering differs from derive_edges");
  }
  // ArborX: views over the same arrays, and its two trees.
  const AxMesh m{decltype(AxMesh::points)(reinterpret_cast<AxPoint*>(sc.xyz.data()), size_t(nv)),
                 Borrowed<Tri>(reinterpret_cast<const Tri*>(sc.mesh.tris.data()), size_t(nt)),
                 Borrowed<Seg>(reinterpret_cast<const Seg*>(sc.mesh.edges.data()), size_t(ne))};
  AxBvh tri_tree = build_tree(space, triangle_boxes(space, m));
  AxBvh edge_tree = build_tree(space, edge_boxes(space, m));

  // ---- 1. the sets, pair for pair, before any timing ----
  const PairSet mk_vt_box = minkq_set(scene.get(), MINKQ_QUERY_VT, MINKQ_MODE_BOX, r);
  const PairSet mk_vt_sphere = minkq_set(scene.get(), MINKQ_QUERY_VT, MINKQ_MODE_SPHERE, r);
  const PairSet mk_ee = minkq_set(scene.get(), MINKQ_QUERY_EE, MINKQ_MODE_BOX, r);
  res.vt_box = mk_vt_box.size();
  res.vt_sphere = mk_vt_sphere.size();
  res.ee = mk_ee.size();
  View<int> offsets("offsets", 0), values("values", 0), counts("counts", std::max({nv, ne, 1}));
  auto add = [&](Check c) {
    std::fprintf(stderr, "  check %-52s %s\n", c.kind.c_str(), c.verdict.c_str());
    res.checks.push_back(std::move(c));
  };
  tri_tree.query(space, VertexBoxQueries<true>{m.points, r}, VtStore{m.tris}, values, offsets);
  add(compare("VT box, intersects(Box(v +- r))", mk_vt_box, csr_set(offsets, values, false)));
  {  // the plain rounding, for the record (not required to be equal)
    tri_tree.query(space, VertexBoxQueries<false>{m.points, r}, VtStore{m.tris}, values, offsets);
    Check c = compare("VT box, plain rounding fl(v +- r) (information)", mk_vt_box, csr_set(offsets, values, false));
    c.ok = true;
    add(c);
  }
  {
    tri_tree.query(space, ArborX::Experimental::attach_indices<int>(ArborX::Experimental::make_intersects(m.points, r)),
                   VtStore{m.tris}, values, offsets);
    const PairSet ax = csr_set(offsets, values, false);
    Check c = compare("VT sphere, intersects(Sphere(v, r))", mk_vt_sphere, ax);
    if (!c.ok) {  // rounding at the boundary is allowed, and reported; anything else is a failure
      PairSet diff = difference(mk_vt_sphere, ax);
      const PairSet other = difference(ax, mk_vt_sphere);
      diff.insert(diff.end(), other.begin(), other.end());
      double worst = 0;
      for (uint64_t p : diff) {
        const minkq::Pair vt = minkq::unpack_pair(p);
        worst = std::max(worst, std::fabs(point_box_distance(sc, vt.first, vt.second) / double(r) - 1.0));
      }
      c.ok = worst <= 0x1p-16;
      char b[200];
      std::snprintf(b, sizeof b, "; max |d / r - 1| of those %.3g: %s", worst,
                    c.ok ? "rounding at the boundary (minkq's r^2 is rounded up, ArborX compares sqrt(d^2) with r)"
                         : "NOT at the boundary");
      c.verdict += b;
    }
    add(c);
  }
  edge_tree.query(space, EdgeBoxQueries<true>{m, r}, EeStore{m.edges}, values, offsets);
  add(compare("EE box, public query (f > e kept)", mk_ee, csr_set(offsets, values, false)));
  const int ee_hint = std::max(1, max_count(space, offsets));  // the best buffer hint: one traversal
  edge_tree.query(space, EdgeBoxQueries<true>{m, r}, EeStore{m.edges}, values, offsets,
                  ArborX::Experimental::TraversalPolicy().setBufferSize(ee_hint));
  add(compare("EE box, public query with buffer hint", mk_ee, csr_set(offsets, values, false)));
  {
    edge_tree.query(space, EdgeBoxQueries<false>{m, r}, EeStore{m.edges}, values, offsets);
    Check c = compare("EE box, plain rounding (information)", mk_ee, csr_set(offsets, values, false));
    c.ok = true;
    add(c);
  }
  half_traversal_store(space, edge_tree, m, r, counts, offsets, values);
  add(compare("EE box, HalfTraversal", mk_ee, csr_set(offsets, values, true)));
  for (const Check& c : res.checks)
    if (!c.ok) {
      res.scene = std::move(sc);
      return res;  // no timing on a differing set
    }

  // ---- 2. timing, round-robin ----
  std::vector<Contestant>& cs = res.contestants;
  // Builds: each run builds a fresh tree (the previous one released untimed).
  std::optional<minkq::CpuTree> mk_tree;
  std::optional<AxBvh> ax_tree;
  const auto* v = reinterpret_cast<const minkq::Vec3*>(sc.xyz.data());
  const auto* tris = reinterpret_cast<const minkq::Triangle*>(sc.mesh.tris.data());
  const auto* edges = reinterpret_cast<const minkq::Edge*>(sc.mesh.edges.data());
  auto reset = [&] {
    mk_tree.reset();
    ax_tree.reset();
  };
  auto builds = [&](const char* row, const char* variant, auto boxes, View<AxBox> (*ax_boxes)(const Exec&, const AxMesh&),
                    int32_t n) {
    cs.emplace_back(row, "minkq", variant, reset,
                    [&, boxes, n] {
                      mk_tree.emplace().build(boxes, n);
                      return uint64_t(n);
                    },
                    uint64_t(n));
    cs.emplace_back(row, "ArborX", "boxes + BVH", reset,
                    [&, ax_boxes] {
                      ax_tree.emplace(build_tree(space, ax_boxes(space, m)));
                      space.fence();
                      return uint64_t(ax_tree->size());
                    },
                    uint64_t(n));
  };
  builds("build triangle tree", "CpuTree::build(TriangleBoxes)", minkq::TriangleBoxes{v, tris}, triangle_boxes, nt);
  builds("build edge tree", "CpuTree::build(EdgeBoxes)", minkq::EdgeBoxes{v, edges}, edge_boxes, ne);
  auto nothing = [] {};
  // Rebuilds of one tree that keeps its build scratch (what a scene reserved with
  // MINKQ_RESERVE_REBUILD does: no allocation); ArborX builds afresh again, having no rebuild in
  // place.
  minkq::CpuTree kept_triangles, kept_edges;
  if (keep_scratch(kept_triangles, nt, 0) && keep_scratch(kept_edges, ne, 0)) {
    const std::function<uint64_t()> ax_triangles = cs[1].run, ax_edges = cs[3].run;  // the builds above
    auto rebuild_rows = [&](const char* row, minkq::CpuTree& tree, auto boxes, int32_t n,
                            const std::function<uint64_t()>& arborx_build) {
      cs.emplace_back(row, "minkq", "CpuTree::build after reserve_build", nothing,
                      [&tree, boxes, n] {
                        tree.build(boxes, n);
                        return uint64_t(n);
                      },
                      uint64_t(n));
      cs.emplace_back(row, "ArborX", "boxes + BVH", reset, arborx_build, uint64_t(n));
    };
    rebuild_rows("rebuild triangle tree, scratch kept", kept_triangles, minkq::TriangleBoxes{v, tris}, nt, ax_triangles);
    rebuild_rows("rebuild edge tree, scratch kept", kept_edges, minkq::EdgeBoxes{v, edges}, ne, ax_edges);
  }
  auto minkq_count = [&](minkq_query_kind kind, minkq_mode mode) {
    return [&, kind, mode] { return run_minkq(scene.get(), kind, mode, r, nullptr, 0, kCountFlags).count; };
  };
  auto counted = [&](auto&& query) {  // zero the per-query slots, query, sum
    return [&, query] {
      Kokkos::deep_copy(space, counts, 0);
      query();
      return sum(space, counts);
    };
  };
  cs.emplace_back("VT box (count)", "minkq", std::string("box, ") + kCountHow, nothing, minkq_count(MINKQ_QUERY_VT, MINKQ_MODE_BOX),
                res.vt_box);
  cs.emplace_back("VT box (count)", "ArborX", "intersects(Box(v +- r))", nothing,
                counted([&] { tri_tree.query(space, VertexBoxQueries<true>{m.points, r}, VtCount{m.tris, counts}); }),
                res.vt_box);
  cs.emplace_back("VT sphere (count)", "minkq", std::string("sphere, ") + kCountHow, nothing,
                minkq_count(MINKQ_QUERY_VT, MINKQ_MODE_SPHERE), res.vt_sphere);
  // ArborX's sphere count is its own set's size: minkq's, or off by the boundary pairs reported.
  auto ax_sphere = [&] {
    tri_tree.query(space, ArborX::Experimental::attach_indices<int>(ArborX::Experimental::make_intersects(m.points, r)),
                   VtCount{m.tris, counts});
  };
  const uint64_t ax_sphere_count = counted(ax_sphere)();
  cs.emplace_back("VT sphere (count)", "ArborX", "intersects(Sphere(v, r))", nothing, counted(ax_sphere), ax_sphere_count);
  cs.emplace_back("EE box, each pair once (count)", "minkq", std::string("box, ") + kCountHow, nothing,
                minkq_count(MINKQ_QUERY_EE, MINKQ_MODE_BOX), res.ee);
  cs.emplace_back("EE box, each pair once (count)", "ArborX", "HalfTraversal (internal, as DBSCAN)", nothing,
                counted([&] { ArborX::Details::HalfTraversal(space, edge_tree, HalfCount{m.edges, counts}, GrownBoxGetter{r}); }),
                res.ee);
  cs.emplace_back("EE box, each pair once (count)", "ArborX", "public query, every pair twice, f <= e dropped", nothing,
                counted([&] { edge_tree.query(space, EdgeBoxQueries<true>{m, r}, EeCount{m.edges, counts}); }), res.ee);
  std::vector<int32_t> pair_buffer(2 * std::max<size_t>(res.ee, 1));
  cs.emplace_back("EE pairs stored", "minkq", "box, into a buffer that holds them", nothing,
                [&] { return run_minkq(scene.get(), MINKQ_QUERY_EE, MINKQ_MODE_BOX, r, pair_buffer.data(), res.ee).count; },
                res.ee);
  View<int> ax_offsets("offsets", 0), ax_values("values", 0);
  // The CSR query with the best buffer hint (one traversal), and without (the default policy: two).
  for (const auto& [variant, policy] :
       {std::pair{"CSR query, buffer hint = max per query", ArborX::Experimental::TraversalPolicy().setBufferSize(ee_hint)},
        std::pair{"CSR query, no hint (two traversals)", ArborX::Experimental::TraversalPolicy()}})
    cs.emplace_back("EE pairs stored", "ArborX", variant, nothing,
                    [&, policy = policy] {
                      edge_tree.query(space, EdgeBoxQueries<true>{m, r}, EeStore{m.edges}, ax_values, ax_offsets, policy);
                      space.fence();
                      return uint64_t(ax_values.extent(0));
                    },
                    res.ee);
  cs.emplace_back("EE pairs stored", "ArborX", "HalfTraversal count + fill", nothing,
                [&] {
                  half_traversal_store(space, edge_tree, m, r, counts, ax_offsets, ax_values);
                  return uint64_t(ax_values.extent(0));
                },
                res.ee);

  const auto gap = std::chrono::milliseconds(opt.gap_ms);
  for (int round = 0; round < opt.warmup + opt.repeats; ++round)
    for (Contestant& c : cs) {
      c.before();
      std::this_thread::sleep_for(gap);  // let the other runtime's workers go idle
      const double t0 = mb::now_ms();
      const uint64_t got = c.run();
      const double t1 = mb::now_ms();
      if (got != c.expect)
        throw std::runtime_error(sc.name + ": " + c.row + " (" + c.lib + ", " + c.variant + ") gave " +
                                 std::to_string(got) + ", expected " + std::to_string(c.expect));
      if (round >= opt.warmup) c.ms.push_back(t1 - t0);
    }
  reset();
  for (Contestant& c : cs) c.t = mb::summarize(c.ms);
  res.load_end = mb::load_average();
  res.scene = std::move(sc);
  return res;
}

}  // namespace peer
