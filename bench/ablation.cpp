// minkq_ablation: what each traversal habit of issue 8 buys, measured in one run on the same
// trees: the library's traversal (core/include/minkq) against the variant it replaced, with
// the work counters (the same on every backend) and CPU time (median of repeats, all
// threads). Variants:
//   VT   queries in vertex id order         vs  in vertex Morton order (kept)
//   leaf ranges of 1 (the binary tree), 2, 4, 8 or 16 (kept) primitives: VT sphere, EE box
//        and EE capsule_exact on each
//   EE   every edge queries the whole tree  vs  each pair met once: a query reaches only the
//        and keeps f > e (each pair met        leaves after its own (kept; queries in leaf
//        twice)                                order, or in edge id order), and a finer test
//                                              also runs the other way round at the leaf
//   node tests: the mode's test at every node  vs  the box test inside the tree and the mode's
//        test at primitive boxes only (kept); at the scene's radius, at 8 r, and on 3-D-spread
//        user boxes
//   box test: the r-padded box, rounded outward  vs  the float gap <= r (kept; symmetric, so
//        EE needs it one way only)
//   trees: Morton codes over cells stretched per axis (before)  vs  cubic cells (kept); each
//        built at the first frame and refit to the last (a simulator's refit-only steps) and
//        rebuilt at the last frame (minkq_scene_rebuild), and a binned SAH build (not kept)
//        either way; with each tree's growth (minkq_scene_tree_growth)
//   VT + EE: two minkq_scene_query calls  vs  one minkq_scene_query_vt_ee call (through the C
//        API, on the CPU or with --backend cuda)
// Both variants of a kind must return the same pairs (checked), except the two box tests
// (different roundings at the boundary: their counts are shown). Writes
// bench/results/ablation.md and (the trees) bench/results/trees.md; see bench/README.md.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cinttypes>
#include <cstring>
#include <filesystem>
#include <functional>
#include <memory>
#include <fstream>
#include <sstream>
#include <type_traits>

#include "common.h"
#include "cpu/tree.h"
#include "minkq/queries.h"
#include "scenes.h"
#include "store.h"
#include "studies/box_tests.h"
#include "studies/trees.h"
#include "studies/variants.h"
#include "studies/wide_bvh.h"

namespace ref = minkq::reference;
using namespace minkq;
using namespace minkq::bench;

namespace {

struct Outcome {
  WorkCounts work;
  double ms = 0;
  std::vector<uint64_t> pairs;  // sorted (first << 32 | second)
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// Runs query_one(i, emit, work) for i < n in blocks of 256 on all threads, counting work;
// times `repeats` runs.
template <class QueryOne>
Outcome run_each(int32_t n, int repeats, const QueryOne& query_one) {
  Outcome out;
  const int32_t blocks = (n + 255) / 256;
  std::vector<std::vector<uint64_t>> parts(static_cast<size_t>(blocks));
  std::vector<WorkCounts> work(static_cast<size_t>(blocks));
  auto once = [&] {
    tbb::parallel_for(int32_t(0), blocks, [&](int32_t b) {
      parts[size_t(b)].clear();
      work[size_t(b)] = WorkCounts{};
      auto emit = [&](int32_t x, int32_t y) { parts[size_t(b)].push_back(pack_pair(x, y)); };
      for (int32_t i = b * 256; i < std::min(n, (b + 1) * 256); ++i) query_one(i, emit, work[size_t(b)]);
    });
  };
  std::vector<double> times;
  once();  // warm-up
  for (int k = 0; k < repeats; ++k) {
    const double start = now_ms();
    once();
    times.push_back(now_ms() - start);
  }
  out.ms = median(times);
  for (const auto& w : work) out.work.add(w);
  for (const auto& p : parts) out.pairs.insert(out.pairs.end(), p.begin(), p.end());
  std::sort(out.pairs.begin(), out.pairs.end());
  return out;
}

// query(variant, kind, repeats) for every variant and kind, timed round-robin: `rounds`
// rounds of one (warmed-up) run of each, so load changes hit all alike; then one more run of
// each for its counts and pairs, given the median time of its rounds. Returns [variant][kind].
template <class Query>
std::vector<std::vector<Outcome>> round_robin(size_t variants, int kinds, int rounds, const Query& query) {
  std::vector<std::vector<std::vector<double>>> times(variants, std::vector<std::vector<double>>(size_t(kinds)));
  for (int round = 0; round < rounds; ++round)
    for (size_t i = 0; i < variants; ++i)
      for (int kind = 0; kind < kinds; ++kind) times[i][size_t(kind)].push_back(query(i, kind, 1).ms);
  std::vector<std::vector<Outcome>> got(variants, std::vector<Outcome>(size_t(kinds)));
  for (size_t i = 0; i < variants; ++i)
    for (int kind = 0; kind < kinds; ++kind) {
      got[i][size_t(kind)] = query(i, kind, 1);
      got[i][size_t(kind)].ms = median(times[i][size_t(kind)]);
    }
  return got;
}

// The library's traversal: run_query over a binary tree.
template <class Shape, class Queries>
Outcome run(const BvhView& bvh, const Queries& queries, int32_t n, int repeats) {
  return run_each(n, repeats, [&](int32_t i, auto& emit, WorkCounts& work) { run_query<Shape>(bvh, queries, i, emit, work); });
}

std::string row(const std::string& scene, const char* kind, const char* mode, const char* variant, const Outcome& o,
                int32_t queries, const Outcome& base) {
  std::ostringstream s;
  const double q = double(queries);
  s << "| " << scene << " | " << kind << " | " << mode << " | " << variant << " | " << fmt(double(o.work.nodes_visited) / q, 4)
    << " | " << fmt(double(o.work.node_tests) / q, 4) << " | " << fmt(double(o.work.primitive_tests) / q, 4) << " | "
    << o.pairs.size() << " | " << fmt(o.ms, 4) << " | " << fmt(base.ms / o.ms, 3) << "x |\n";
  return s.str();
}

template <class Shape>
std::string compare_ee(const SceneFrames& sc, const Vec3* v, const Edge* e, float r, const char* mode, int repeats,
                       bool& ok) {
  const int32_t ne = int32_t(sc.mesh.edge_count());
  CpuTree tree;
  tree.build(EdgeBoxes{v, e}, ne);
  const EdgeEdgeQueries once{v, e, tree.sorted_prims().data(), r, kDropIncident};
  const EdgeEdgeTwice twice{once};
  std::vector<int32_t> position(static_cast<size_t>(ne));
  for (int32_t i = 0; i < ne; ++i) position[size_t(tree.sorted_prims()[size_t(i)])] = i;
  const EdgeEdgeOnceByIdOrder once_by_id{once, position.data()};
  const Outcome a = run<Shape>(tree.view(), twice, ne, repeats);
  const Outcome c = run<Shape>(tree.view(), once, ne, repeats);
  const Outcome d = run<Shape>(tree.view(), once_by_id, ne, repeats);
  // The once-variants' set is the twice-variant's minus pairs failing the reverse node test.
  ok &= std::includes(a.pairs.begin(), a.pairs.end(), c.pairs.begin(), c.pairs.end()) && d.pairs == c.pairs;
  return row(sc.name, "EE", mode, "each pair twice (before)", a, ne, a) +
         row(sc.name, "EE", mode, "once (kept)", c, ne, a) +
         row(sc.name, "EE", mode, "once, queries in edge id order", d, ne, a);
}

// Trees with leaf ranges of up to 1 (the binary tree: before), 2, 4, 8 and 16 primitives
// (the library's kLeafSize marked kept): VT sphere, EE box and EE capsule_exact on each; the pairs must not change.
std::string compare_leaf_sizes(const SceneFrames& sc, const Vec3* v, const Triangle* t, const Edge* e, float r,
                               int repeats, bool& ok) {
  const int32_t nv = int32_t(sc.mesh.vertex_count()), nt = int32_t(sc.mesh.triangle_count());
  const int32_t ne = int32_t(sc.mesh.edge_count());
  HostVector<int32_t> order;
  SortScratch scratch;
  sort_by_morton(PointBoxes{v}, nv, order, scratch);
  std::string out;
  Outcome base[3];
  for (int32_t leaf : {1, 2, 4, 8, 16}) {
    CpuTree triangles, edges;
    triangles.build(TriangleBoxes{v, t}, nt, BuildConfig{leaf});
    edges.build(EdgeBoxes{v, e}, ne, BuildConfig{leaf});
    const double node_bytes = 64.0 * double(triangles.nodes().size() + edges.nodes().size()) / double(nt);
    char label[160];
    std::snprintf(label, sizeof label, "leaf size %d%s: %.1f B of nodes / triangle", leaf,
                  leaf == 1 ? " (before)" : leaf == kLeafSize ? " (kept)" : "", node_bytes);
    const VertexTriangleQueries vt{v, t, order.data(), r, kDropIncident};
    const EdgeEdgeQueries ee{v, e, edges.sorted_prims().data(), r, kDropIncident};
    const Outcome got[3] = {run<SphereShape>(triangles.view(), vt, nv, repeats),
                            run<BoxShape>(edges.view(), ee, ne, repeats),
                            run<CapsuleExactShape>(edges.view(), ee, ne, repeats)};
    if (leaf == 1) std::copy(got, got + 3, base);
    for (int k = 0; k < 3; ++k) ok &= got[k].pairs == base[k].pairs;
    out += row(sc.name, "VT", "sphere", label, got[0], nv, base[0]) + row(sc.name, "EE", "box", label, got[1], ne, base[1]) +
           row(sc.name, "EE", "capsule_exact", label, got[2], ne, base[2]);
  }
  return out;
}

// The fine node tests (sphere, capsule_ray, capsule_exact) at every node (before) or only at
// primitive boxes, the padded box inside the tree (kept); at the scene's radius and at 8x it.
template <class Shape, class Queries>
std::string compare_fine_nodes_one(const std::string& scene, const BvhView& bvh, const Queries& queries, int32_t n,
                                   const char* kind, const char* mode, const char* radius, int repeats, bool& ok) {
  const Outcome a = run<FineAtEveryNode<Shape>>(bvh, queries, n, repeats);
  const Outcome b = run<Shape>(bvh, queries, n, repeats);
  ok &= a.pairs == b.pairs;
  return row(scene, kind, mode, (std::string("fine test at every node (before), ") + radius).c_str(), a, n, a) +
         row(scene, kind, mode, (std::string("box test inside, fine at primitives (kept), ") + radius).c_str(), b, n, a);
}

// The library's two trees of a frame, and its vertices in Morton order (the VT query order).
struct FrameTrees {
  int32_t nv, ne;
  CpuTree triangles, edges;
  HostVector<int32_t> order;
  FrameTrees(const SceneFrames& sc, const Vec3* v, const Triangle* t, const Edge* e)
      : nv(int32_t(sc.mesh.vertex_count())), ne(int32_t(sc.mesh.edge_count())) {
    triangles.build(TriangleBoxes{v, t}, int32_t(sc.mesh.triangle_count()));
    edges.build(EdgeBoxes{v, e}, ne);
    SortScratch scratch;
    sort_by_morton(PointBoxes{v}, nv, order, scratch);
  }
};

std::string compare_fine_nodes(const SceneFrames& sc, const FrameTrees& trees, const Vec3* v, const Triangle* t,
                               const Edge* e, float r, int repeats, bool& ok) {
  const int32_t nv = trees.nv, ne = trees.ne;
  const CpuTree &triangles = trees.triangles, &edges = trees.edges;
  const HostVector<int32_t>& order = trees.order;
  std::string out;
  for (const float factor : {1.0f, 8.0f}) {
    const float rr = r * factor;
    const char* radius = factor == 1.0f ? "r" : "8 r";
    const VertexTriangleQueries vt{v, t, order.data(), rr, kDropIncident};
    const EdgeEdgeQueries ee{v, e, edges.sorted_prims().data(), rr, kDropIncident};
    out += compare_fine_nodes_one<SphereShape>(sc.name, triangles.view(), vt, nv, "VT", "sphere", radius, repeats, ok);
    out += compare_fine_nodes_one<CapsuleRayShape>(sc.name, edges.view(), ee, ne, "EE", "capsule_ray", radius, repeats, ok);
    out += compare_fine_nodes_one<CapsuleExactShape>(sc.name, edges.view(), ee, ne, "EE", "capsule_exact", radius, repeats, ok);
  }
  return out;
}

// Leaf scans box by box, or the box test four boxes at a time in vector lanes and the finer
// test box by box (before), or both tests in vector lanes (kept): VT sphere, EE box (no finer
// test), capsule_ray and capsule_exact on the library's trees; the pairs must not change.
template <class Shape, class Queries>
std::string compare_leaf_lanes_one(const std::string& scene, const BvhView& bvh, const Queries& queries, int32_t n,
                                   const char* kind, const char* mode, int repeats, bool& ok) {
  const bool finer = !std::is_same<Shape, BoxShape>::value;
  const Outcome one = run<LeafBoxByBox<Shape>>(bvh, queries, n, repeats);
  std::string out = row(scene, kind, mode, "leaf boxes tested one by one", one, n, one);
  if (finer) {
    const Outcome box_lanes = run<FinerBoxByBox<Shape>>(bvh, queries, n, repeats);
    ok &= box_lanes.pairs == one.pairs;
    out += row(scene, kind, mode, "box test in vector lanes, finer test one by one (before)", box_lanes, n, one);
  }
  const Outcome kept = run<Shape>(bvh, queries, n, repeats);
  ok &= kept.pairs == one.pairs;
  return out + row(scene, kind, mode, finer ? "box and finer tests in vector lanes (kept)" : "box test in vector lanes (kept)",
                   kept, n, one);
}

std::string compare_leaf_lanes(const SceneFrames& sc, const FrameTrees& trees, const Vec3* v, const Triangle* t,
                               const Edge* e, float r, int repeats, bool& ok) {
  const int32_t nv = trees.nv, ne = trees.ne;
  const VertexTriangleQueries vt{v, t, trees.order.data(), r, kDropIncident};
  const EdgeEdgeQueries ee{v, e, trees.edges.sorted_prims().data(), r, kDropIncident};
  const BvhView tri = trees.triangles.view(), edge = trees.edges.view();
  return compare_leaf_lanes_one<SphereShape>(sc.name, tri, vt, nv, "VT", "sphere", repeats, ok) +
         compare_leaf_lanes_one<BoxShape>(sc.name, edge, ee, ne, "EE", "box", repeats, ok) +
         compare_leaf_lanes_one<CapsuleRayShape>(sc.name, edge, ee, ne, "EE", "capsule_ray", repeats, ok) +
         compare_leaf_lanes_one<CapsuleExactShape>(sc.name, edge, ee, ne, "EE", "capsule_exact", repeats, ok);
}

// Box mode: the padded box (before) against the float gap test (kept), VT and EE. The pair
// sets may differ at the boundary (different roundings, both conservative): counts shown.
std::string compare_box_tests(const SceneFrames& sc, const FrameTrees& trees, const Vec3* v, const Triangle* t,
                              const Edge* e, float r, int repeats) {
  const int32_t nv = trees.nv, ne = trees.ne;
  const CpuTree &triangles = trees.triangles, &edges = trees.edges;
  const VertexTriangleQueries vt{v, t, trees.order.data(), r, kDropIncident};
  const EdgeEdgeQueries ee{v, e, edges.sorted_prims().data(), r, kDropIncident};
  const Outcome vt_before = run<PaddedBoxShape>(triangles.view(), vt, nv, repeats);
  const Outcome vt_kept = run<BoxShape>(triangles.view(), vt, nv, repeats);
  const Outcome ee_before = run<PaddedBoxShape>(edges.view(), ee, ne, repeats);
  const Outcome ee_kept = run<BoxShape>(edges.view(), ee, ne, repeats);
  return row(sc.name, "VT", "box", "padded box, rounded outward (before)", vt_before, nv, vt_before) +
         row(sc.name, "VT", "box", "float gap <= r, box_gap_within (kept)", vt_kept, nv, vt_before) +
         row(sc.name, "EE", "box", "padded box both ways (before)", ee_before, ne, ee_before) +
         row(sc.name, "EE", "box", "float gap <= r, one way: symmetric (kept)", ee_kept, ne, ee_before);
}

// The same on 3-D-spread user boxes (minkq_hr_study's recipe, where the sphere test drops up
// to 47% of the box candidates): n cubes of half-size h = hr * r, centres uniform in [0,1]^3,
// r such that a padded-box query meets about 8 boxes; n sphere queries at uniform points and
// n capsule queries along cube diagonals (length 2 sqrt(3) h) in uniform directions.
std::string compare_fine_nodes_spread(int32_t n, double hr, int repeats, bool& ok) {
  const double r = std::cbrt(8.0 / n) / (2 * (1 + hr)), h = hr * r, len = 2 * std::sqrt(3.0) * h;
  uint64_t state = uint64_t(hr * 1e6) + 977;
  auto uniform = [&state] {  // splitmix64 -> [0, 1)
    uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return double((z ^ (z >> 31)) >> 11) * 0x1p-53;
  };
  std::vector<Box> boxes(static_cast<size_t>(n));
  std::vector<Vec3> points(boxes.size()), p0(boxes.size()), p1(boxes.size());
  for (size_t i = 0; i < boxes.size(); ++i) {
    const double c[3] = {uniform(), uniform(), uniform()};
    boxes[i] = {{float(c[0] - h), float(c[1] - h), float(c[2] - h)}, {float(c[0] + h), float(c[1] + h), float(c[2] + h)}};
    points[i] = {float(uniform()), float(uniform()), float(uniform())};
    const double th = std::acos(2 * uniform() - 1), ph = 2 * 3.141592653589793 * uniform();
    const double d[3] = {std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)};
    const double q[3] = {uniform(), uniform(), uniform()};
    p0[i] = {float(q[0] - 0.5 * len * d[0]), float(q[1] - 0.5 * len * d[1]), float(q[2] - 0.5 * len * d[2])};
    p1[i] = {float(q[0] + 0.5 * len * d[0]), float(q[1] + 0.5 * len * d[1]), float(q[2] + 0.5 * len * d[2])};
  }
  CpuTree tree;
  tree.build(GivenBoxes{boxes.data()}, n);
  char name[96], radius[32];
  std::snprintf(name, sizeof name, "3-D spread cubes, h/r = %g", hr);
  std::snprintf(radius, sizeof radius, "%d queries", int(n));
  const UserQueries spheres{points.data(), nullptr, float(r)}, capsules{p0.data(), p1.data(), float(r)};
  return compare_fine_nodes_one<SphereShape>(name, tree.view(), spheres, n, "user", "sphere", radius, repeats, ok) +
         compare_fine_nodes_one<CapsuleRayShape>(name, tree.view(), capsules, n, "user", "capsule_ray", radius, repeats, ok) +
         compare_fine_nodes_one<CapsuleExactShape>(name, tree.view(), capsules, n, "user", "capsule_exact", radius, repeats, ok);
}

// A scene's first and last frame in the core's types, its radius, and its vertices at the
// last frame in Morton order (the VT query order); announces the scene on stderr.
struct FirstAndLast {
  const Vec3 *v0, *v;
  const Triangle* t;
  const Edge* e;
  float r;
  int32_t nv, nt, ne;
  HostVector<int32_t> order;
  FirstAndLast(const SceneFrames& sc, const char* study)
      : v0(reinterpret_cast<const Vec3*>(sc.frames.front().data())),
        v(reinterpret_cast<const Vec3*>(sc.frames.back().data())),
        t(reinterpret_cast<const Triangle*>(sc.mesh.tris.data())),
        e(reinterpret_cast<const Edge*>(sc.mesh.edges.data())),
        r(float(sc.radius_factor * sc.mean_edge)),
        nv(int32_t(sc.mesh.vertex_count())),
        nt(int32_t(sc.mesh.triangle_count())),
        ne(int32_t(sc.mesh.edge_count())) {
    std::fprintf(stderr, "%s (%s): %d V, %d T, r = %.4g\n", sc.name.c_str(), study, nv, nt, double(r));
    SortScratch scratch;
    sort_by_morton(PointBoxes{v}, nv, order, scratch);
  }
};

// Tree quality on the scenes' frame sequences (first and last frame): the library's Morton
// build refit from the first frame (what a simulator's refit-only steps run), the same
// rebuilt at the last frame (minkq_scene_rebuild), and the SAH build either way. Box mode,
// the scene's radius; growth = area cost over its value at build (minkq_scene_tree_growth),
// of the triangle tree for VT and of the edge tree for EE.
std::string compare_tree_builds(const SceneFrames& sc, int repeats, bool& ok) {
  const FirstAndLast frames(sc, "trees");
  const Vec3 *v0 = frames.v0, *v = frames.v;
  const Triangle* t = frames.t;
  const Edge* e = frames.e;
  const float r = frames.r;
  const int32_t nv = frames.nv, nt = frames.nt, ne = frames.ne;
  const VertexTriangleQueries vt{v, t, frames.order.data(), r, kDropIncident};
  enum Build { kPerAxis, kCubes, kSah };
  struct Variant {
    Build build;
    bool refit;
    CpuTree trees[2];  // triangles, edges (Morton builds)
    SahTree sah[2];    // the same (SAH build)
    double build_ms;
    BvhView view(int kind) const { return build == kSah ? sah[kind].view() : trees[kind].view(); }
    double growth_of(int kind) const {
      return build == kSah ? sah[kind].growth() : tree_growth_of(trees[kind]);
    }
  };
  std::vector<Variant> variants;
  for (const Build build : {kPerAxis, kCubes, kSah})
    for (const bool refit : {true, false}) {
      Variant& x = variants.emplace_back();
      x.build = build;
      x.refit = refit;
      const Vec3* at = refit ? v0 : v;
      x.build_ms = now_ms();
      if (build == kSah) {
        x.sah[0] = build_sah(TriangleBoxes{at, t}, nt);
        x.sah[1] = build_sah(EdgeBoxes{at, e}, ne);
      } else if (build == kCubes) {
        x.trees[0].build(TriangleBoxes{at, t}, nt);
        x.trees[1].build(EdgeBoxes{at, e}, ne);
      } else {
        build_per_axis(x.trees[0], TriangleBoxes{at, t}, nt);
        build_per_axis(x.trees[1], EdgeBoxes{at, e}, ne);
      }
      x.build_ms = now_ms() - x.build_ms;
      if (refit && build == kSah) {
        x.sah[0].refit(TriangleBoxes{v, t});
        x.sah[1].refit(EdgeBoxes{v, e});
      } else if (refit) {
        x.trees[0].refit(TriangleBoxes{v, t});
        x.trees[1].refit(EdgeBoxes{v, e});
      }
    }
  const std::vector<std::vector<Outcome>> got = round_robin(variants.size(), 2, 3 * repeats, [&](size_t i, int kind, int reps) {
    const Variant& x = variants[i];
    const EdgeEdgeQueries ee{v, e, x.view(1).sorted_prims, r, kDropIncident};
    return kind == 0 ? run<BoxShape>(x.view(0), vt, nv, reps) : run<BoxShape>(x.view(1), ee, ne, reps);
  });
  std::string out;
  for (size_t i = 0; i < variants.size(); ++i) {
    const Variant& x = variants[i];
    for (int kind = 0; kind < 2; ++kind) {
      ok &= got[i][size_t(kind)].pairs == got[0][size_t(kind)].pairs;
      char label[200];
      const char* builds[3] = {"Morton, cells per axis", "Morton, cubic cells", "SAH"};
      const char* marks[3][2] = {{"", " (before)"}, {"", " (kept)"}, {"", ""}};  // [build][refit]
      std::snprintf(label, sizeof label, "%s, %s%s: growth %.2f, build both %.1f ms", builds[x.build],
                    x.refit ? "built at frame 0, refit" : "rebuilt at the last frame", marks[x.build][x.refit],
                    x.growth_of(kind), x.build_ms);
      out += row(sc.name, kind ? "EE" : "VT", "box", label, got[i][size_t(kind)], kind ? ne : nv, got[0][size_t(kind)]);
    }
  }
  return out;
}

// One mode over a wide tree's pair (triangles, edges): kind 0 = VT sphere, 1 = EE box,
// 2 = EE capsule_exact.
template <int W, bool kLanes>
Outcome run_wide(const WideTree<W> (&trees)[2], const VertexTriangleQueries& vt, const EdgeEdgeQueries& ee, int kind,
                 int32_t nv, int32_t ne, int reps) {
  auto go = [&](auto shape, const WideTree<W>& tree, const auto& queries, int32_t n) {
    using Shape = decltype(shape);
    return run_each(n, reps, [&](int32_t i, auto& emit, WorkCounts& work) {
      run_query_wide<W, kLanes, Shape>(tree, queries, i, emit, work);
    });
  };
  if (kind == 0) return go(SphereShape{}, trees[0], vt, nv);
  if (kind == 1) return go(BoxShape{}, trees[1], ee, ne);
  return go(CapsuleExactShape{}, trees[1], ee, ne);
}

// Wide nodes (issue 8's untried lever; bench/studies/wide_bvh.h, not the library's tree). Each
// scene's two binary trees are built at the first frame with leaf ranges of 16 (the
// library's), 4 or 1, collapsed there to 4- and 8-ary nodes, and refit to the last frame (the
// wide nodes take the refit boxes), as a simulator's refit-only steps run them. VT sphere, EE
// box and EE capsule_exact at the scene's radius; the pairs of every variant checked equal to
// the binary tree's; variants timed round-robin (round_robin).
// Also appends to `bytes_read` a summary row per mode: node-record bytes read per query by the
// binary tree and by the leaf-16 wide trees (nodes / query x record size).
std::string compare_wide(const SceneFrames& sc, int repeats, bool& ok, std::string& bytes_read) {
  const FirstAndLast frames(sc, "wide");
  const Vec3 *v0 = frames.v0, *v = frames.v;
  const Triangle* t = frames.t;
  const Edge* e = frames.e;
  const float r = frames.r;
  const int32_t nv = frames.nv, nt = frames.nt, ne = frames.ne;
  const VertexTriangleQueries vt{v, t, frames.order.data(), r, kDropIncident};
  struct Trees {
    CpuTree binary[2];  // triangles, edges
    WideTree<4> wide4[2], wide4q[2];  // float child boxes, 8-bit quantized child boxes
    WideTree<8> wide8[2], wide8q[2];
  };
  const int32_t leaf_sizes[3] = {kLeafSize, 4, 1};
  std::vector<std::unique_ptr<Trees>> trees;
  for (const int32_t leaf : leaf_sizes) {
    Trees& x = *trees.emplace_back(std::make_unique<Trees>());
    x.binary[0].build(TriangleBoxes{v0, t}, nt, BuildConfig{leaf});
    x.binary[1].build(EdgeBoxes{v0, e}, ne, BuildConfig{leaf});
    for (int k = 0; k < 2; ++k) {
      x.wide4[k].collapse(x.binary[k]);
      x.wide8[k].collapse(x.binary[k]);
      x.wide4q[k].collapse(x.binary[k]);
      x.wide8q[k].collapse(x.binary[k]);
    }
    x.binary[0].refit(TriangleBoxes{v, t});
    x.binary[1].refit(EdgeBoxes{v, e});
    for (int k = 0; k < 2; ++k) {
      x.wide4[k].fill(x.binary[k]);
      x.wide8[k].fill(x.binary[k]);
      x.wide4q[k].fill(x.binary[k], true);
      x.wide8q[k].fill(x.binary[k], true);
    }
  }
  struct Variant {
    std::string label;
    size_t record_bytes;
    std::function<Outcome(int kind, int reps)> query;
  };
  std::vector<Variant> variants;
  auto bytes_label = [&](const std::string& what, size_t node_bytes) {
    char b[64];
    std::snprintf(b, sizeof b, ": %.1f B of nodes / triangle", double(node_bytes) / nt);
    return what + b;
  };
  {
    const Trees& x = *trees[0];
    Variant& binary = variants.emplace_back();
    binary.record_bytes = sizeof(BvhNode);
    binary.label = bytes_label("binary, leaf 16 (kept)", 64 * (x.binary[0].nodes().size() + x.binary[1].nodes().size()));
    binary.query = [&x, &vt, v, e, r, nv, ne](int kind, int reps) {
      const EdgeEdgeQueries ee{v, e, x.binary[1].sorted_prims().data(), r, kDropIncident};
      if (kind == 0) return run<SphereShape>(x.binary[0].view(), vt, nv, reps);
      if (kind == 1) return run<BoxShape>(x.binary[1].view(), ee, ne, reps);
      return run<CapsuleExactShape>(x.binary[1].view(), ee, ne, reps);
    };
  }
  // Quantized records (see WideTree::fill) would hold a float origin, 3 exponent bytes, a pad
  // byte and 8-bit planes instead of float boxes: 72 B per 4-wide node, 128 B per 8-wide.
  auto add_wide = [&](int width, size_t leaf_index, bool lanes, bool quantized) {
    const Trees& x = *trees[leaf_index];
    const size_t count = width == 4 ? x.wide4[0].nodes().size() + x.wide4[1].nodes().size()
                                    : x.wide8[0].nodes().size() + x.wide8[1].nodes().size();
    const size_t record = quantized ? (width == 4 ? 72 : 128) : (width == 4 ? sizeof(WideNode<4>) : sizeof(WideNode<8>));
    const std::string what = std::to_string(width) + "-wide, leaf " + std::to_string(leaf_sizes[leaf_index]) +
                             (quantized ? ", 8-bit child boxes" : "") +
                             (lanes ? ", tested in 4-float lanes" : ", tested one by one");
    Variant& wide = variants.emplace_back();
    wide.record_bytes = record;
    wide.label = bytes_label(what, count * record);
    wide.query = [&x, &vt, v, e, r, nv, ne, width, lanes, quantized](int kind, int reps) {
      const EdgeEdgeQueries ee{v, e, x.binary[1].sorted_prims().data(), r, kDropIncident};
      if (width == 8) return run_wide<8, true>(quantized ? x.wide8q : x.wide8, vt, ee, kind, nv, ne, reps);
      return lanes ? run_wide<4, true>(quantized ? x.wide4q : x.wide4, vt, ee, kind, nv, ne, reps)
                   : run_wide<4, false>(x.wide4, vt, ee, kind, nv, ne, reps);
    };
  };
  add_wide(4, 0, false, false);
  add_wide(4, 0, true, false);
  add_wide(4, 1, true, false);
  add_wide(4, 2, true, false);
  add_wide(8, 0, true, false);
  add_wide(8, 1, true, false);
  add_wide(8, 2, true, false);
  add_wide(4, 0, true, true);
  add_wide(4, 1, true, true);
  add_wide(8, 0, true, true);
  const std::vector<std::vector<Outcome>> got = round_robin(
      variants.size(), 3, 3 * repeats, [&](size_t i, int kind, int reps) { return variants[i].query(kind, reps); });
  std::string out;
  const char* kinds[3] = {"VT", "EE", "EE"};
  const char* modes[3] = {"sphere", "box", "capsule_exact"};
  for (int kind = 0; kind < 3; ++kind)
    for (size_t i = 0; i < variants.size(); ++i) {
      const Outcome& o = got[i][size_t(kind)];
      ok &= o.pairs == got[0][size_t(kind)].pairs;
      out += row(sc.name, kinds[kind], modes[kind], variants[i].label.c_str(), o, kind ? ne : nv, got[0][size_t(kind)]);
    }
  // Binary, then the leaf-16 wide trees: 4-wide float, 4-wide 8-bit, 8-wide float, 8-wide 8-bit.
  const size_t summarized[5] = {0, 2, 8, 5, 10};
  for (int kind = 0; kind < 3; ++kind) {
    bytes_read += "| " + sc.name + " | " + kinds[kind] + " | " + modes[kind] + " |";
    const double base = double(got[0][size_t(kind)].work.nodes_visited) * sizeof(BvhNode);
    for (const size_t i : summarized) {
      const double b = double(got[i][size_t(kind)].work.nodes_visited) * double(variants[i].record_bytes);
      bytes_read += " " + fmt(b / (kind ? ne : nv), 4) + (i ? " (" + fmt(b / base, 3) + "x)" : "") + " |";
    }
    bytes_read += " " + fmt(got[0][size_t(kind)].ms / got[8][size_t(kind)].ms, 3) + "x |\n";
  }
  return out;
}

// Rebuild policies end to end, through the C API as a simulator calls it: a scene created at
// frame 0, then per step minkq_scene_refit or minkq_scene_rebuild to the next frame, the
// growth read back (minkq_scene_tree_growth), and the VT and EE queries (box mode, incident
// pairs dropped, into reused results). Every policy's pairs are checked equal step by step
// (digests) and its work counted in a separate, untimed STATS pass; the policies' whole
// sequences run round-robin, `rounds` times; ms = median over rounds of the sequence's sum.
struct Policy {
  const char* label;
  int every;         // rebuild every `every` steps (0: not by count)
  double threshold;  // rebuild when the growth read after the last step exceeds it (0: never)
};
constexpr Policy kPolicies[] = {{"refit every step (the default)", 0, 0.0},
                                {"rebuild every step", 1, 0.0},
                                {"rebuild every 5th step", 5, 0.0},
                                {"rebuild when growth > 1.5 (minkq.h's advice)", 0, 1.5},
                                {"rebuild when growth > 1.2", 0, 1.2}};

struct PolicyRun {
  double update_ms = 0, query_ms = 0, growth_max = 1.0;
  int rebuilds = 0;
  uint64_t vt_nodes = 0, ee_nodes = 0;
  std::vector<uint64_t> digests;  // VT, EE per step (counted runs only)
};

PolicyRun run_policy(minkq_device* device, const SceneFrames& sc, const Policy& policy, float r, bool counted) {
  PolicyRun run;
  Scene scene = create_scene(device, sc.frames[0], sc.mesh.tris);
  Result vt = new_result(), ee = new_result();
  double growth = 1.0;
  for (size_t k = 1; k < sc.frames.size(); ++k) {
    const minkq_buffer vb{sc.frames[k].data(), 12, sc.frames[k].size() / 3, MINKQ_MEMORY_HOST};
    const int step = int(k);
    const bool rebuild = (policy.every > 0 && step % policy.every == 0) || (policy.threshold > 0 && growth > policy.threshold);
    double start = now_ms();
    check(rebuild ? minkq_scene_rebuild(scene.get(), vb) : minkq_scene_refit(scene.get(), vb), "minkq_scene_refit/rebuild");
    check(minkq_scene_tree_growth(scene.get(), &growth), "minkq_scene_tree_growth");
    run.update_ms += now_ms() - start;
    run.rebuilds += rebuild ? 1 : 0;
    run.growth_max = std::max(run.growth_max, growth);
    const minkq_query_desc qvt{MINKQ_QUERY_VT, MINKQ_MODE_BOX, 0, r}, qee{MINKQ_QUERY_EE, MINKQ_MODE_BOX, 0, r};
    start = now_ms();
    check(minkq_scene_query_result(scene.get(), &qvt, vt.get()), "minkq_scene_query_result");
    check(minkq_scene_query_result(scene.get(), &qee, ee.get()), "minkq_scene_query_result");
    run.query_ms += now_ms() - start;
    if (!counted) continue;
    const uint32_t stats = MINKQ_QUERY_STATS | MINKQ_QUERY_DIGEST;
    const minkq_query_desc cvt{MINKQ_QUERY_VT, MINKQ_MODE_BOX, stats, r}, cee{MINKQ_QUERY_EE, MINKQ_MODE_BOX, stats, r};
    check(minkq_scene_query_result(scene.get(), &cvt, vt.get()), "minkq_scene_query_result");
    run.vt_nodes += minkq_result_stats(vt.get()).nodes_visited;
    run.digests.push_back(minkq_result_digest(vt.get()));
    check(minkq_scene_query_result(scene.get(), &cee, ee.get()), "minkq_scene_query_result");
    run.ee_nodes += minkq_result_stats(ee.get()).nodes_visited;
    run.digests.push_back(minkq_result_digest(ee.get()));
  }
  return run;
}

std::string compare_policies(const SceneFrames& sc, int rounds, bool& ok) {
  const float r = float(sc.radius_factor * sc.mean_edge);
  const int32_t nv = int32_t(sc.mesh.vertex_count()), ne = int32_t(sc.mesh.edge_count());
  const int steps = int(sc.frames.size()) - 1;
  std::fprintf(stderr, "%s (policies): %d V, %d T, %d steps, r = %.4g\n", sc.name.c_str(), nv,
               int(sc.mesh.triangle_count()), steps, double(r));
  Device device = open_device("cpu");
  const size_t n = std::size(kPolicies);
  std::vector<PolicyRun> counted(n);
  for (size_t i = 0; i < n; ++i) {
    counted[i] = run_policy(device.get(), sc, kPolicies[i], r, true);
    ok &= counted[i].digests == counted[0].digests;
  }
  std::vector<std::vector<double>> update(n), query(n), total(n);
  for (int round = 0; round < rounds; ++round)
    for (size_t i = 0; i < n; ++i) {
      const PolicyRun run = run_policy(device.get(), sc, kPolicies[i], r, false);
      update[i].push_back(run.update_ms);
      query[i].push_back(run.query_ms);
      total[i].push_back(run.update_ms + run.query_ms);
    }
  std::string out;
  const double base = median(total[0]);
  for (size_t i = 0; i < n; ++i) {
    const PolicyRun& c = counted[i];
    const double t = median(total[i]);
    out += "| " + sc.name + " | " + std::to_string(steps) + " | " + kPolicies[i].label + " | " + std::to_string(c.rebuilds) +
           " | " + fmt(c.growth_max, 3) + " | " + fmt(double(c.vt_nodes) / (double(nv) * steps), 4) + " | " +
           fmt(double(c.ee_nodes) / (double(ne) * steps), 4) + " | " + fmt(median(update[i]), 4) + " | " +
           fmt(median(query[i]), 4) + " | " + fmt(t, 4) + " | " + fmt(base / t, 3) + "x |\n";
  }
  return out;
}

// ---- Contacts: the node test and the leaf screen under the leaf distance test ---------------

// A library source with a study's leaf test in place of its own: `candidates` (the source
// without kLeafExact) keeps its incident-pair and reverse finer tests, then leaf_test(q, prim).
template <class Queries, class LeafTest>
struct WithLeafTest {
  Queries candidates;
  LeafTest leaf_test;
  WithLeafTest(Queries source, LeafTest test) : candidates(source), leaf_test(test) { candidates.filters &= ~kLeafExact; }
  QueryTarget target(int32_t i) const { return candidates.target(i); }
  QueryGeometry geometry(int32_t q) const { return candidates.geometry(q); }
  template <class Shape>
  bool accept(int32_t q, int32_t prim, const Box&) const {
    return candidates.template accept<Shape>(q, prim) && leaf_test(q, prim);
  }
  Pair pair(int32_t q, int32_t prim) const { return candidates.pair(q, prim); }
};

// EE's screen tried for VT (not kept): point p against triangle abc along v = 3 (p - the
// centroid), where the triangle's projection ends at max_k v.x_k, so the gap is
// min_k v.(p - x_k) / |v|; "apart" beyond r + 2^-18 T, T = max_k |p - x_k|_1 >= S (the bound
// argument of predicates.h's segments_apart).
bool point_triangle_apart(Vec3 p, Vec3 a, Vec3 b, Vec3 c, float r) {
  const Vec3d pd = to_double(p);
  const Vec3d pa = pd - to_double(a), pb = pd - to_double(b), pc = pd - to_double(c);
  const Vec3d v = pa + pb + pc;
  const double vv = dot(v, v);
  if (!(vv > 0.0)) return false;  // p at the centroid: no axis
  const double gap = min_num(dot(v, pa), min_num(dot(v, pb), dot(v, pc))) / std::sqrt(vv);
  return gap > double(r) + 0x1p-18 * max3(abs_sum(pa), abs_sum(pb), abs_sum(pc));
}

// Contacts (MINKQ_QUERY_LEAF_EXACT) four ways on the library's trees at the last frame: the
// finer node mode (sphere for VT, capsule_exact for EE: the benchmark's leaf_exact before) or
// the box test, each with the full distance test alone or behind the separation screen (EE:
// the library's; VT: the study's). The four must return the same pairs; they run round-robin.
std::string compare_contacts(const SceneFrames& sc, int repeats, bool& ok) {
  const auto* v = reinterpret_cast<const Vec3*>(sc.frames.back().data());
  const auto* t = reinterpret_cast<const Triangle*>(sc.mesh.tris.data());
  const auto* e = reinterpret_cast<const Edge*>(sc.mesh.edges.data());
  const float r = float(sc.radius_factor * sc.mean_edge);
  std::fprintf(stderr, "%s (contacts): %zu V, %zu T, r = %.4g\n", sc.name.c_str(), sc.mesh.vertex_count(),
               sc.mesh.triangle_count(), double(r));
  const FrameTrees trees(sc, v, t, e);
  const uint32_t filters = kDropIncident | kLeafExact;
  const VertexTriangleQueries vt{v, t, trees.order.data(), r, filters};
  const EdgeEdgeQueries ee{v, e, trees.edges.sorted_prims().data(), r, filters};
  // VT behind the study's screen; EE with the full distance alone (before the library's screen).
  const WithLeafTest vt_screened(vt, [&vt](int32_t q, int32_t t) {
    const Triangle tri = vt.prims[t];
    const Vec3 *x = vt.vertices, p = x[q], a = x[tri.v[0]], b = x[tri.v[1]], c = x[tri.v[2]];
    return !point_triangle_apart(p, a, b, c, vt.r) && point_triangle_within(p, a, b, c, vt.r);
  });
  const WithLeafTest ee_full(ee, [&ee](int32_t e, int32_t f) {
    const Edge lo = ee.edges[e < f ? e : f], hi = ee.edges[e < f ? f : e];
    const Vec3* x = ee.vertices;
    return segment_segment_distance_within(x[lo.v[0]], x[lo.v[1]], x[hi.v[0]], x[hi.v[1]], ee.r);
  });
  const BvhView tri = trees.triangles.view(), edge = trees.edges.view();
  // [kind][variant]; variants: finer + full, box + full, box + screen, finer + screen.
  static const char* const labels[2][4] = {
      {"finer node test, full distance test (before)", "box node test, full distance test (kept)",
       "box node test, separation screen first", "finer node test, separation screen first"},
      {"finer node test, full distance test (before)", "box node test, full distance test",
       "box node test, separation screen first (kept)", "finer node test, separation screen first"}};
  const auto got = round_robin(4, 2, 3 * repeats, [&](size_t variant, int kind, int reps) {
    if (kind == 0) {
      switch (variant) {
        case 0: return run<SphereShape>(tri, vt, trees.nv, reps);
        case 1: return run<BoxShape>(tri, vt, trees.nv, reps);
        case 2: return run<BoxShape>(tri, vt_screened, trees.nv, reps);
        default: return run<SphereShape>(tri, vt_screened, trees.nv, reps);
      }
    }
    switch (variant) {
      case 0: return run<CapsuleExactShape>(edge, ee_full, trees.ne, reps);
      case 1: return run<BoxShape>(edge, ee_full, trees.ne, reps);
      case 2: return run<BoxShape>(edge, ee, trees.ne, reps);
      default: return run<CapsuleExactShape>(edge, ee, trees.ne, reps);
    }
  });
  std::string out;
  for (int kind = 0; kind < 2; ++kind)
    for (size_t i = 0; i < 4; ++i) {
      ok &= got[i][size_t(kind)].pairs == got[0][size_t(kind)].pairs;
      const bool box = i == 1 || i == 2;
      out += row(sc.name, kind ? "EE" : "VT", box ? "box" : kind ? "capsule_exact" : "sphere", labels[kind][i],
                 got[i][size_t(kind)], kind ? trees.ne : trees.nv, got[0][size_t(kind)]);
    }
  return out;
}

std::string compare_scene(const SceneFrames& sc, int repeats, bool& ok) {
  const auto* v = reinterpret_cast<const Vec3*>(sc.frames.back().data());
  const auto* t = reinterpret_cast<const Triangle*>(sc.mesh.tris.data());
  const auto* e = reinterpret_cast<const Edge*>(sc.mesh.edges.data());
  const float r = float(sc.radius_factor * sc.mean_edge);
  const int32_t nv = int32_t(sc.mesh.vertex_count()), nt = int32_t(sc.mesh.triangle_count());
  std::fprintf(stderr, "%s: %d V, %d T, r = %.4g\n", sc.name.c_str(), nv, nt, double(r));
  const FrameTrees trees(sc, v, t, e);
  const VertexTriangleQueries by_id{v, t, nullptr, r, kDropIncident}, by_morton{v, t, trees.order.data(), r, kDropIncident};
  const Outcome a = run<SphereShape>(trees.triangles.view(), by_id, nv, repeats);
  const Outcome b = run<SphereShape>(trees.triangles.view(), by_morton, nv, repeats);
  ok &= a.pairs == b.pairs;
  std::string out = row(sc.name, "VT", "sphere", "vertex id order (before)", a, nv, a) +
                    row(sc.name, "VT", "sphere", "vertex Morton order", b, nv, a);
  out += compare_ee<BoxShape>(sc, v, e, r, "box", repeats, ok);
  out += compare_ee<CapsuleExactShape>(sc, v, e, r, "capsule_exact", repeats, ok);
  return out + compare_leaf_sizes(sc, v, t, e, r, repeats, ok) + compare_fine_nodes(sc, trees, v, t, e, r, repeats, ok) +
         compare_box_tests(sc, trees, v, t, e, r, repeats) + compare_leaf_lanes(sc, trees, v, t, e, r, repeats, ok);
}

}  // namespace

// ---- One pass for VT and EE: minkq_scene_query_vt_ee against two minkq_scene_query calls ------

// The scene created at the first frame and refit to the last (a simulator's refit-only step),
// then per variant one step's queries: VT and EE by two calls, or by one fused call; the box
// candidates and the contacts (box + leaf_exact). Pairs checked equal by digest.
std::string compare_fused(const SceneFrames& sc, minkq_device* device, int rounds, bool& ok) {
  const float r = float(sc.radius_factor * sc.mean_edge);
  std::fprintf(stderr, "%s (fused): %d V, %d T, r = %.4g\n", sc.name.c_str(), int(sc.mesh.vertex_count()),
               int(sc.mesh.triangle_count()), double(r));
  Scene scene = create_scene(device, sc.frames[0], sc.mesh.tris);
  const std::vector<float>& last = sc.frames.back();
  check(minkq_scene_refit(scene.get(), {last.data(), 12, last.size() / 3, MINKQ_MEMORY_HOST}), "minkq_scene_refit");
  Result vt = new_result(), ee = new_result();
  struct Variant {
    const char* output;
    uint32_t flags;
    bool fused;
  };
  const Variant variants[] = {{"box candidates", 0, false}, {"box candidates", 0, true},
                              {"contacts (leaf_exact)", MINKQ_QUERY_LEAF_EXACT, false},
                              {"contacts (leaf_exact)", MINKQ_QUERY_LEAF_EXACT, true}};
  auto run = [&](const Variant& v, uint32_t extra) {
    const minkq_query_desc qvt{MINKQ_QUERY_VT, MINKQ_MODE_BOX, v.flags | extra, r};
    const minkq_query_desc qee{MINKQ_QUERY_EE, MINKQ_MODE_BOX, v.flags | extra, r};
    if (v.fused) {
      check(minkq_scene_query_vt_ee_result(scene.get(), &qvt, &qee, vt.get(), ee.get()), "minkq_scene_query_vt_ee_result");
    } else {
      check(minkq_scene_query_result(scene.get(), &qvt, vt.get()), "minkq_scene_query_result");
      check(minkq_scene_query_result(scene.get(), &qee, ee.get()), "minkq_scene_query_result");
    }
  };
  const size_t n = std::size(variants);
  std::vector<std::pair<uint64_t, uint64_t>> digests(n), counts(n);
  for (size_t i = 0; i < n; ++i) {
    run(variants[i], MINKQ_QUERY_DIGEST);  // also the warm-up, growing the results
    digests[i] = {minkq_result_digest(vt.get()), minkq_result_digest(ee.get())};
    counts[i] = {minkq_result_count(vt.get()), minkq_result_count(ee.get())};
    ok &= digests[i] == digests[i & ~size_t(1)];
  }
  std::vector<std::vector<double>> times(n);
  for (int round = 0; round < rounds; ++round)
    for (size_t i = 0; i < n; ++i) {
      const double start = now_ms();
      run(variants[i], 0);
      times[i].push_back(now_ms() - start);
    }
  std::string out;
  for (size_t i = 0; i < n; ++i) {
    const double ms = median(times[i]), before = median(times[i & ~size_t(1)]);
    out += "| " + sc.name + " | " + std::to_string(sc.mesh.triangle_count()) + " | " + variants[i].output + " | " +
           (variants[i].fused ? "one call (minkq_scene_query_vt_ee)" : "two calls (VT, then EE)") + " | " +
           std::to_string(counts[i].first) + " | " + std::to_string(counts[i].second) + " | " + fmt(ms, 4) + " | " +
           fmt(before / ms, 3) + "x |\n";
  }
  return out;
}

int main(int argc, char** argv) {
  try {
    std::string data = MINKQ_BENCH_DATA_DIR, out = MINKQ_BENCH_RESULTS_DIR;
    int repeats = 5;
    double scale = 0;  // reference sizes
    std::string sections = "all";  // or "traversal" (ablation.md), "trees" (trees.md), "wide" (wide.md), "policies" (policies.md), "contacts" (contacts.md), "fused" (fused.md)
    std::string backend = "cpu";   // the device of the C API studies (fused)
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      if (a == "--quick") repeats = 1;
      else if (a == "--out" && i + 1 < argc) out = argv[++i];
      else if (a == "--data" && i + 1 < argc) data = argv[++i];
      else if (a == "--triangles" && i + 1 < argc) scale = std::stod(argv[++i]);
      else if (a == "--backend" && i + 1 < argc) backend = argv[++i];
      else if (a == "--only" && i + 1 < argc &&
               (std::string(argv[i + 1]) == "traversal" || std::string(argv[i + 1]) == "trees" ||
                std::string(argv[i + 1]) == "wide" || std::string(argv[i + 1]) == "policies" ||
                std::string(argv[i + 1]) == "contacts" || std::string(argv[i + 1]) == "fused"))
        sections = argv[++i];
      else {
        std::fprintf(stderr,
                     "usage: minkq_ablation [--quick] [--out DIR] [--data DIR] [--triangles N] [--backend cpu|cuda] "
                     "[--only traversal|trees|wide|policies|contacts|fused]\n");
        return 2;
      }
    }
    const std::string table_head =
        "| scene | kind | mode | variant | nodes / query | node tests / query | primitive tests / query | pairs | ms | "
        "speed |\n|---|---|---|---|---|---|---|---|---|---|\n";
    const std::string timing = "ms = median of " + std::to_string(repeats) + " runs after a warm-up; speed = 'before' ms / "
                               "this ms, measured in this run. Written by `minkq_ablation`" +
                               std::string(repeats == 1 ? " --quick" : "") + ".\n\n";
    bool ok = true;
    std::filesystem::create_directories(out);
    auto write = [&out](const std::string& name, const std::string& text) {
      std::ofstream f(out + "/" + name);
      f << text;
      if (!f) throw std::runtime_error("cannot write " + out + "/" + name);
      std::fprintf(stderr, "wrote %s/%s\n", out.c_str(), name.c_str());
    };
    if (sections == "all" || sections == "traversal") {
      std::ostringstream o;
      o << "# Traversal ablation (issue 8)\n\nMachine: " << machine_line("cpu (core traversal, TBB)")
        << ". Load average (1 min) at start " << fmt(load_average(), 3) << ". Last frame of each scene, r = the scene's "
        << "radius, incident pairs dropped, CPU backend traversal on all threads; counts per query; " << timing
        << table_head;
      for (const std::string& name : {std::string("twist_target"), std::string("cloth_twist"), std::string("cloth_hanging"),
                                      std::string("softbody_gift")})
        o << compare_scene(make_scene(name, scale, 2, data), repeats, ok);
      for (const RealMesh& m : available_real_meshes(data))
        if (m.name == "unisex_shirt" || m.name == "multilayer_drape") o << compare_scene(load_real_scene(m, data), repeats, ok);
      for (const double hr : {0.01, 1.0}) o << compare_fine_nodes_spread(200000, hr, repeats, ok);
      o << "\nLoad average at end " << fmt(load_average(), 3) << ".\n";
      write("ablation.md", o.str());
    }
    if (sections == "all" || sections == "trees") {
      std::ostringstream o;
      o << "# Tree quality: refit, rebuild, SAH (issue 8)\n\nMachine: " << machine_line("cpu (core traversal, TBB)")
        << ". Load average (1 min) at start " << fmt(load_average(), 3) << ". Every procedural scene's first and last "
        << "frame, r = the scene's radius, box mode, incident pairs dropped, CPU backend traversal on all threads; the "
        << "pairs of every variant checked equal. 'before': Morton trees over cells stretched per axis (the usual LBVH "
        << "frame, the library's until this table), built at the first frame and refit to the last, as a simulator's "
        << "refit-only steps run them; 'kept': the same over cubic cells (the library's). 'build both' is the "
        << "time to build the scene's two trees (the Morton build on all threads, the SAH study on one); growth = the "
        << "tree's area cost over its value at its build (minkq_scene_tree_growth). Counts per query; the variants "
        << "run round-robin, " << 3 * repeats << " rounds (each round one warm-up and one timed run of every query "
        << "batch); ms = the median of the timed runs; speed = 'before' ms / this ms. Written by `minkq_ablation`"
        << (repeats == 1 ? " --quick" : "") << ".\n\n"
        << table_head;
      for (const std::string& name : procedural_scene_names())
        o << compare_tree_builds(make_scene(name, scale, 2, data), repeats, ok);
      o << compare_tree_builds(make_scene("twist_target", scale, 2, data), repeats, ok);
      o << "\nLoad average at end " << fmt(load_average(), 3) << ".\n";
      write("trees.md", o.str());
    }
    if (sections == "all" || sections == "wide") {
      std::ostringstream o;
      o << "# Wide nodes: 4- and 8-ary trees collapsed from the binary one (issue 8)\n\nMachine: "
        << machine_line("cpu (core traversal, TBB)") << ". Load average (1 min) at start " << fmt(load_average(), 3)
        << ". A study (bench/studies/wide_bvh.h), not the library's tree. Every procedural scene and the twisted sheet; each "
        << "scene's binary trees built at its first frame (leaf ranges of 16, the library's, or of 4 or 1), collapsed "
        << "there to W-ary nodes (the child with the largest box area opened until W children; child boxes stored "
        << "by axis, " << sizeof(WideNode<4>) << " B per 4-wide node, " << sizeof(WideNode<8>) << " B per 8-wide), "
        << "and refit to the last frame, as a simulator's refit-only steps run them; leaf ranges, leaf order and leaf "
        << "scans unchanged. r = the scene's radius, incident pairs dropped, CPU traversal on all threads; the pairs of "
        << "every variant checked equal to the binary tree's. nodes = node records read (a wide record is two or four "
        << "64-byte lines); node tests = child and leaf boxes tested (a 4-lane test counts its non-empty lanes). "
        << "'4-float lanes': the box test (box_gap_within) on 4 children at once with GCC vector extensions (SSE2 "
        << "here; the same float operations as the scalar test, so the same answers). Counts per query; variants run "
        << "round-robin, " << 3 * repeats << " rounds; ms = median of the timed runs; speed = the binary tree's ms / this "
        << "ms. Written by `minkq_ablation --only wide`" << (repeats == 1 ? " --quick" : "") << ".\n\n"
        << table_head;
      std::string bytes_read;
      for (const std::string& name : procedural_scene_names())
        o << compare_wide(make_scene(name, scale, 2, data), repeats, ok, bytes_read);
      o << compare_wide(make_scene("twist_target", scale, 2, data), repeats, ok, bytes_read);
      o << "\n## Node-record bytes read per query\n\nFrom the table above: nodes / query x record size (binary 64 B; "
        << "4-wide float " << sizeof(WideNode<4>) << " B, 8-bit 72 B; 8-wide float " << sizeof(WideNode<8>)
        << " B, 8-bit 128 B), leaf ranges of 16; in brackets the ratio to the binary tree. Leaf boxes scanned (24 B "
        << "each) come on top and are the same for all. A GPU traversal is bound by these dependent reads; the CPU "
        << "speed of the 4-wide 8-bit tree (its boxes stored decoded, so not its real cost) is the last column.\n\n"
        << "| scene | kind | mode | binary | 4-wide | 4-wide 8-bit | 8-wide | 8-wide 8-bit | CPU speed, 4-wide 8-bit |\n"
        << "|---|---|---|---|---|---|---|---|---|\n"
        << bytes_read;
      o << "\nLoad average at end " << fmt(load_average(), 3) << ".\n";
      write("wide.md", o.str());
    }
    if (sections == "all" || sections == "policies") {
      constexpr int kFrames = 21;
      std::ostringstream o;
      o << "# Rebuild policies end to end (issue 8)\n\nMachine: " << machine_line("cpu") << ". Load average (1 min) at "
        << "start " << fmt(load_average(), 3) << ". Every procedural scene and the twisted sheet over " << kFrames
        << " frames of its motion: the scene created at frame 0 (not timed), then per step the update to the next frame "
        << "(minkq_scene_refit, or minkq_scene_rebuild where the policy says, then minkq_scene_tree_growth) and the VT "
        << "and EE queries (box mode, r = the scene's radius, incident pairs dropped, into reused results), through "
        << "the C API on the CPU device (all threads). A growth policy reads the growth after each step and rebuilds at "
        << "the next. Every policy's pairs checked equal at every step (digests); nodes per query from a separate "
        << "untimed MINKQ_QUERY_STATS pass, averaged over the steps; growth max = the largest growth read. The policies' "
        << "whole sequences run round-robin, " << repeats << " rounds; ms = median over the rounds of the sequence's "
        << "sum; speed = 'refit every step' total / this total. Written by `minkq_ablation --only policies`"
        << (repeats == 1 ? " --quick" : "") << ".\n\n"
        << "| scene | steps | policy | rebuilds | growth max | VT nodes / query | EE nodes / query | update ms | query ms | "
           "total ms | speed |\n|---|---|---|---|---|---|---|---|---|---|---|\n";
      for (const std::string& name : procedural_scene_names())
        o << compare_policies(make_scene(name, scale, kFrames, data), repeats, ok);
      o << compare_policies(make_scene("twist_target", scale, kFrames, data), repeats, ok);
      o << "\nLoad average at end " << fmt(load_average(), 3) << ".\n";
      write("policies.md", o.str());
    }
    if (sections == "all" || sections == "contacts") {
      std::ostringstream o;
      o << "# Contacts: node test and leaf screen under the leaf distance test (issue 8)\n\nMachine: "
        << machine_line("cpu (core traversal, TBB)") << ". Load average (1 min) at start " << fmt(load_average(), 3)
        << ". Contacts are the output of MINKQ_QUERY_LEAF_EXACT: every pair within r by the double-precision distance "
        << "test at the leaves. Four ways to them on the library's trees at each scene's last frame (r = the scene's "
        << "radius, incident pairs dropped, all threads): the finer node mode (sphere for VT, capsule_exact for EE) or "
        << "the box test in the tree and at the primitive boxes, and at the leaves the full distance test alone or behind "
        << "the separation screen (the gap along the axis joining the two elements' centres: predicates.h's "
        << "segments_apart for EE, the same idea for VT in ablation.cpp). All four "
        << "return the same pairs (checked). Counts per query; the variants run round-robin, " << 3 * repeats
        << " rounds; ms = the median; speed = 'before' ms / this ms, in the same run. Written by `minkq_ablation --only "
        << "contacts`" << (repeats == 1 ? " --quick" : "") << ".\n\n"
        << table_head;
      for (const std::string& name : procedural_scene_names()) o << compare_contacts(make_scene(name, scale, 2, data), repeats, ok);
      o << compare_contacts(make_scene("twist_target", scale, 2, data), repeats, ok);
      for (const RealMesh& m : available_real_meshes(data))
        if (m.name == "unisex_shirt" || m.name == "multilayer_drape" || m.name == "rod-twist3036")
          o << compare_contacts(load_real_scene(m, data), repeats, ok);
      o << "\nLoad average at end " << fmt(load_average(), 3) << ".\n";
      write("contacts.md", o.str());
    }
    if (sections == "all" || sections == "fused") {
      Device device = open_device(backend.c_str());
      const std::string file = backend == "cpu" ? "fused.md" : "fused_" + backend.substr(0, backend.find(':')) + ".md";
      std::ostringstream o;
      o << "# One pass for VT and EE (issue 8)\n\nMachine: " << machine_line(minkq_device_name(device.get()))
        << ". Load average (1 min) at start " << fmt(load_average(), 3) << ". Each scene created at its first frame "
        << "and refit to its last, r = the scene's radius, incident pairs dropped, box mode; one step's VT and EE "
        << "queries through the C API into reused results: two minkq_scene_query_result calls against one "
        << "minkq_scene_query_vt_ee_result call (one parallel loop over both query sets on the CPU; one kernel launch "
        << "and one count readback on CUDA), for the box candidates and for the contacts (leaf_exact). Pairs checked "
        << "equal by digest. The variants run round-robin, " << 3 * repeats << " rounds after a warm-up; ms = the "
        << "median; speed = two calls' ms / this ms, in the same run. Written by `minkq_ablation --only fused"
        << (backend == "cpu" ? "" : " --backend " + backend) << "`" << (repeats == 1 ? " --quick" : "") << ".\n\n"
        << "| scene | triangles | output | variant | VT pairs | EE pairs | ms | speed |\n|---|---|---|---|---|---|---|---|\n";
      for (const std::string& name : procedural_scene_names())
        o << compare_fused(make_scene(name, scale, 2, data), device.get(), 3 * repeats, ok);
      o << compare_fused(make_scene("twist_target", scale, 2, data), device.get(), 3 * repeats, ok);
      for (const RealMesh& m : available_real_meshes(data))
        if (m.name == "unisex_shirt" || m.name == "multilayer_drape")
          o << compare_fused(load_real_scene(m, data), device.get(), 3 * repeats, ok);
      o << compare_fused(make_scene("twist_target", 1e6, 2, data), device.get(), 3 * repeats, ok);
      o << "\nLoad average at end " << fmt(load_average(), 3) << ".\n";
      write(file, o.str());
    }
    if (!ok) {
      std::fprintf(stderr, "FAIL: a variant returned different pairs\n");
      return 1;
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "minkq_ablation: %s\n", e.what());
    return 3;
  }
}
