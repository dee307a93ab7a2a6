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
// Both variants of a kind must return the same pairs (checked), except the two box tests
// (different roundings at the boundary: their counts are shown). Writes
// bench/results/ablation.md; see bench/README.md.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cinttypes>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "common.h"
#include "cpu_tree.h"
#include "minkq/queries.h"
#include "scenes.h"

namespace ref = minkq::reference;
using namespace minkq;
using namespace minkq::bench;

namespace {

// The EE source before issue 8: query i is edge i over the whole tree; pairs with f <= e are
// dropped at the leaf, so each unordered pair is reached twice and kept once.
struct EdgeEdgeTwice {
  EdgeEdgeQueries base;
  static constexpr bool kOncePerPair = true;
  QueryTarget target(int32_t i) const { return {i, -1}; }
  QueryGeometry geometry(int32_t e) const { return base.geometry(e); }
  template <class Shape>
  bool accept(int32_t e, int32_t f, const Box&) const {
    if (f <= e) return false;
    const Edge a = base.edges[e], b = base.edges[f];
    if ((base.filters & kDropIncident) &&
        (a.v[0] == b.v[0] || a.v[0] == b.v[1] || a.v[1] == b.v[0] || a.v[1] == b.v[1]))
      return false;
    if (base.filters & kLeafExact)
      return segment_segment_within(base.vertices[a.v[0]], base.vertices[a.v[1]], base.vertices[b.v[0]],
                                    base.vertices[b.v[1]], base.r);
    return true;
  }
  Pair pair(int32_t e, int32_t f) const { return {e, f}; }
};

// Each pair once, queries in edge id order: query i is edge i, pruned at its own leaf position.
struct EdgeEdgeOnceByIdOrder {
  EdgeEdgeQueries base;
  const int32_t* position;  // sorted leaf position of each edge
  static constexpr bool kOncePerPair = true;
  QueryTarget target(int32_t i) const { return {i, position[i]}; }
  QueryGeometry geometry(int32_t e) const { return base.geometry(e); }
  template <class Shape>
  bool accept(int32_t e, int32_t f, const Box& f_box) const { return base.accept<Shape>(e, f, f_box); }
  Pair pair(int32_t e, int32_t f) const { return base.pair(e, f); }
};

// The box test before box_gap_within: the query's box padded by r, rounded outward, against
// each box. Not symmetric, so an EE pair also needs it the other way round (the leaf filter
// does that for every shape but the library's BoxShape).
struct PaddedBoxShape {
  Box box;
  static PaddedBoxShape from(const QueryGeometry& q) { return {padded_segment_box(q.p0, q.p1, q.r)}; }
  bool overlaps(const Box& b) const { return boxes_overlap(box, b); }
  bool may_overlap(const Box& b) const { return boxes_overlap(box, b); }
  // Not symmetric: the other edge's padded box against this box is the reverse test.
  bool finer(const Box& b) const { return boxes_overlap(box, b); }
};

// The node tests before: the mode's own test at every node, not only at primitive boxes.
template <class Shape>
struct FineAtEveryNode {
  Shape shape;
  static FineAtEveryNode from(const QueryGeometry& q) { return {Shape::from(q)}; }
  bool overlaps(const Box& b) const { return shape.overlaps(b); }
  bool may_overlap(const Box& b) const { return shape.overlaps(b); }
  bool finer(const Box& b) const { return shape.finer(b); }
};

struct Outcome {
  WorkCounts work;
  double ms = 0;
  std::vector<uint64_t> pairs;  // sorted (first << 32 | second)
};

// Runs every query in blocks of 256 on all threads, counting work; times `repeats` runs.
template <class Shape, class Queries>
Outcome run(const BvhView& bvh, const Queries& queries, int32_t n, int repeats) {
  Outcome out;
  const int32_t blocks = (n + 255) / 256;
  std::vector<std::vector<uint64_t>> parts(static_cast<size_t>(blocks));
  std::vector<WorkCounts> work(static_cast<size_t>(blocks));
  auto once = [&] {
    tbb::parallel_for(int32_t(0), blocks, [&](int32_t b) {
      parts[size_t(b)].clear();
      work[size_t(b)] = WorkCounts{};
      auto emit = [&](int32_t x, int32_t y) { parts[size_t(b)].push_back(uint64_t(uint32_t(x)) << 32 | uint32_t(y)); };
      for (int32_t i = b * 256; i < std::min(n, (b + 1) * 256); ++i) run_query<Shape>(bvh, queries, i, emit, work[size_t(b)]);
    });
  };
  std::vector<double> times;
  once();  // warm-up
  for (int k = 0; k < repeats; ++k) {
    const double start = now_ms();
    once();
    times.push_back(now_ms() - start);
  }
  std::sort(times.begin(), times.end());
  out.ms = times[times.size() / 2];
  for (const auto& w : work) out.work.add(w);
  for (const auto& p : parts) out.pairs.insert(out.pairs.end(), p.begin(), p.end());
  std::sort(out.pairs.begin(), out.pairs.end());
  return out;
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
  std::vector<uint64_t> keys;
  std::vector<int32_t> order;
  sort_by_morton(PointBoxes{v}, nv, keys, order);
  std::string out;
  Outcome base[3];
  for (int32_t leaf : {1, 2, 4, 8, 16}) {
    CpuTree triangles, edges;
    triangles.build(TriangleBoxes{v, t}, nt, leaf);
    edges.build(EdgeBoxes{v, e}, ne, leaf);
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
  std::vector<uint64_t> keys;
  std::vector<int32_t> order;
  FrameTrees(const SceneFrames& sc, const Vec3* v, const Triangle* t, const Edge* e)
      : nv(int32_t(sc.mesh.vertex_count())), ne(int32_t(sc.mesh.edge_count())) {
    triangles.build(TriangleBoxes{v, t}, int32_t(sc.mesh.triangle_count()));
    edges.build(EdgeBoxes{v, e}, ne);
    sort_by_morton(PointBoxes{v}, nv, keys, order);
  }
};

std::string compare_fine_nodes(const SceneFrames& sc, const FrameTrees& trees, const Vec3* v, const Triangle* t,
                               const Edge* e, float r, int repeats, bool& ok) {
  const int32_t nv = trees.nv, ne = trees.ne;
  const CpuTree &triangles = trees.triangles, &edges = trees.edges;
  const std::vector<int32_t>& order = trees.order;
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
         compare_box_tests(sc, trees, v, t, e, r, repeats);
}

}  // namespace

int main(int argc, char** argv) {
  try {
    std::string data = MINKQ_BENCH_DATA_DIR, out = MINKQ_BENCH_RESULTS_DIR;
    int repeats = 5;
    double scale = 0;  // reference sizes
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      if (a == "--quick") repeats = 1;
      else if (a == "--out" && i + 1 < argc) out = argv[++i];
      else if (a == "--data" && i + 1 < argc) data = argv[++i];
      else if (a == "--triangles" && i + 1 < argc) scale = std::stod(argv[++i]);
      else {
        std::fprintf(stderr, "usage: minkq_ablation [--quick] [--out DIR] [--data DIR] [--triangles N]\n");
        return 2;
      }
    }
    const double load_start = load_average();
    std::ostringstream o;
    o << "# Traversal ablation (issue 8)\n\nMachine: " << machine_line("cpu (core traversal, TBB)") << ". Load average (1 min) at start "
      << fmt(load_start, 3) << ". Last frame of each scene, r = the scene's radius, incident pairs dropped, CPU backend "
      << "traversal on all threads; counts per query; ms = median of " << repeats << " runs after a warm-up; speed = "
      << "'before' ms / this ms, measured in this run. Written by `minkq_ablation`" << (repeats == 1 ? " --quick" : "")
      << ".\n\n| scene | kind | mode | variant | nodes / query | node tests / query | primitive tests / query | pairs | ms | speed |\n"
      << "|---|---|---|---|---|---|---|---|---|---|\n";
    bool ok = true;
    for (const std::string& name : {std::string("twist_target"), std::string("cloth_twist"), std::string("cloth_hanging"),
                                    std::string("softbody_gift")})
      o << compare_scene(make_scene(name, scale, 2, data), repeats, ok);
    for (const RealMesh& m : real_meshes())
      if (m.name == "unisex_shirt" || m.name == "multilayer_drape") o << compare_scene(load_real_scene(m, data), repeats, ok);
    for (const double hr : {0.01, 1.0}) o << compare_fine_nodes_spread(200000, hr, repeats, ok);
    o << "\nLoad average at end " << fmt(load_average(), 3) << ".\n";
    std::filesystem::create_directories(out);
    std::ofstream f(out + "/ablation.md");
    f << o.str();
    if (!f) throw std::runtime_error("cannot write " + out + "/ablation.md");
    std::fprintf(stderr, "wrote %s/ablation.md\n", out.c_str());
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
