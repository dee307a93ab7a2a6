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
// Both variants of a kind must return the same pairs (checked), except the two box tests
// (different roundings at the boundary: their counts are shown). Writes
// bench/results/ablation.md and (the trees) bench/results/trees.md; see bench/README.md.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cinttypes>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "common.h"
#include "backend.h"
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

// A top-down binned SAH build (the tree-quality alternative of issue 8; not the library's
// build): each range of primitives is split where the summed half areas of the two sides,
// weighted by their counts, are least (centres binned in 32 slabs per axis; the middle when
// the centres coincide), until a side holds at most kLeafSize primitives. Nodes in preorder,
// leaf ranges contiguous: the library's layout, traversal and refit serve it unchanged.
template <class Boxes>
CpuTree build_sah(Boxes boxes, int32_t n) {
  constexpr int kBins = 32;
  std::vector<Box> box(static_cast<size_t>(n));
  std::vector<Vec3> centre(box.size());
  std::vector<int32_t> order(box.size());
  for (int32_t i = 0; i < n; ++i) {
    box[size_t(i)] = boxes(i);
    centre[size_t(i)] = box_centre(box[size_t(i)]);
    order[size_t(i)] = i;
  }
  auto axis_of = [](const Vec3& v, int axis) { return axis == 0 ? v.x : axis == 1 ? v.y : v.z; };
  // Partitions order[first..last] and returns the last position of the left side.
  auto split = [&](int32_t first, int32_t last) {
    Box bounds = Box::empty();
    for (int32_t p = first; p <= last; ++p) bounds = box_expand(bounds, centre[size_t(order[size_t(p)])]);
    double best = INFINITY;
    int best_axis = -1, best_bin = 0;
    for (int axis = 0; axis < 3; ++axis) {
      const float lo = axis_of(bounds.lo, axis), extent = axis_of(bounds.hi, axis) - lo;
      if (!(extent > 0.0f)) continue;
      Box bin_box[kBins];
      int32_t bin_count[kBins] = {};
      std::fill(bin_box, bin_box + kBins, Box::empty());
      for (int32_t p = first; p <= last; ++p) {
        const int32_t id = order[size_t(p)];
        const int b = std::min(kBins - 1, int((axis_of(centre[size_t(id)], axis) - lo) * (kBins / extent)));
        bin_box[b] = box_union(bin_box[b], box[size_t(id)]);
        ++bin_count[b];
      }
      double right_cost[kBins] = {};  // of bins b.. kBins - 1
      Box right = Box::empty();
      int32_t count = 0;
      for (int b = kBins - 1; b > 0; --b) {
        right = box_union(right, bin_box[b]);
        count += bin_count[b];
        right_cost[b] = count ? count * half_area(right) : -1.0;  // -1: empty side
      }
      Box left = Box::empty();
      count = 0;
      for (int b = 0; b + 1 < kBins; ++b) {
        left = box_union(left, bin_box[b]);
        count += bin_count[b];
        if (count == 0 || right_cost[b + 1] < 0.0) continue;
        const double cost = count * half_area(left) + right_cost[b + 1];
        if (cost < best) best = cost, best_axis = axis, best_bin = b;
      }
    }
    if (best_axis < 0) return first + (last - first) / 2;
    const float lo = axis_of(bounds.lo, best_axis), extent = axis_of(bounds.hi, best_axis) - lo;
    int32_t* middle = std::partition(order.data() + first, order.data() + last + 1, [&](int32_t id) {
      return std::min(kBins - 1, int((axis_of(centre[size_t(id)], best_axis) - lo) * (kBins / extent))) <= best_bin;
    });
    return int32_t(middle - order.data()) - 1;
  };
  std::vector<BvhNode> nodes;
  if (n == 1) nodes.push_back(one_leaf_root());
  struct Range {
    int32_t first, last, parent_slot;
  };
  std::vector<Range> stack;
  if (n > 1) stack.push_back({0, n - 1, -1});
  while (!stack.empty()) {
    const Range range = stack.back();
    stack.pop_back();
    const int32_t self = int32_t(nodes.size());
    if (range.parent_slot >= 0) {
      BvhNode& parent = nodes[size_t(range.parent_slot >> 1)];
      (range.parent_slot & 1 ? parent.right : parent.left) = self;
    }
    const int32_t s = split(range.first, range.last);
    BvhNode node{};
    node.parent = range.parent_slot;
    node.split = s;
    node.left = ~range.first;  // leaf ranges unless a child node links itself in
    node.right = ~range.last;
    nodes.push_back(node);
    // Right first: the left subtree follows its parent in memory.
    if (range.last - s > kLeafSize) stack.push_back({s + 1, range.last, self << 1 | 1});
    if (s - range.first + 1 > kLeafSize) stack.push_back({range.first, s, self << 1});
  }
  CpuTree tree;
  tree.adopt(std::move(nodes), std::move(order), boxes);
  return tree;
}

// Tree quality on the scenes' frame sequences (first and last frame): the library's Morton
// build refit from the first frame (what a simulator's refit-only steps run), the same
// rebuilt at the last frame (minkq_scene_rebuild), and the SAH build either way. Box mode,
// the scene's radius; growth = area cost over its value at build (minkq_scene_tree_growth),
// of the triangle tree for VT and of the edge tree for EE.
std::string compare_tree_builds(const SceneFrames& sc, int repeats, bool& ok) {
  const auto* v0 = reinterpret_cast<const Vec3*>(sc.frames.front().data());
  const auto* v = reinterpret_cast<const Vec3*>(sc.frames.back().data());
  const auto* t = reinterpret_cast<const Triangle*>(sc.mesh.tris.data());
  const auto* e = reinterpret_cast<const Edge*>(sc.mesh.edges.data());
  const float r = float(sc.radius_factor * sc.mean_edge);
  const int32_t nv = int32_t(sc.mesh.vertex_count()), nt = int32_t(sc.mesh.triangle_count());
  const int32_t ne = int32_t(sc.mesh.edge_count());
  std::fprintf(stderr, "%s (trees): %d V, %d T, r = %.4g\n", sc.name.c_str(), nv, nt, double(r));
  std::vector<uint64_t> keys;
  std::vector<int32_t> order;
  sort_by_morton(PointBoxes{v}, nv, keys, order);
  const VertexTriangleQueries vt{v, t, order.data(), r, kDropIncident};
  enum Build { kPerAxis, kCubes, kSah };
  struct Variant {
    Build build;
    bool refit;
    CpuTree trees[2];  // triangles, edges
    double build_ms;
    Outcome got[2];  // VT, EE: counts and pairs; ms from the interleaved rounds below
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
        x.trees[0] = build_sah(TriangleBoxes{at, t}, nt);
        x.trees[1] = build_sah(EdgeBoxes{at, e}, ne);
      } else {
        const MortonCells cells = build == kCubes ? MortonCells::kCubes : MortonCells::kPerAxis;
        x.trees[0].build(TriangleBoxes{at, t}, nt, kLeafSize, cells);
        x.trees[1].build(EdgeBoxes{at, e}, ne, kLeafSize, cells);
      }
      x.build_ms = now_ms() - x.build_ms;
      if (refit) {
        x.trees[0].refit(TriangleBoxes{v, t});
        x.trees[1].refit(EdgeBoxes{v, e});
      }
    }
  // Each variant's query once per round, round after round: load changes hit all alike.
  auto query = [&](const Variant& x, int kind, int reps) {
    const EdgeEdgeQueries ee{v, e, x.trees[1].sorted_prims().data(), r, kDropIncident};
    return kind == 0 ? run<BoxShape>(x.trees[0].view(), vt, nv, reps) : run<BoxShape>(x.trees[1].view(), ee, ne, reps);
  };
  std::vector<std::vector<double>> times(variants.size() * 2);
  for (int round = 0; round < 3 * repeats; ++round)
    for (size_t i = 0; i < variants.size(); ++i)
      for (int kind = 0; kind < 2; ++kind) times[2 * i + size_t(kind)].push_back(query(variants[i], kind, 1).ms);
  std::string out;
  for (size_t i = 0; i < variants.size(); ++i) {
    Variant& x = variants[i];
    for (int kind = 0; kind < 2; ++kind) {
      x.got[kind] = query(x, kind, 1);
      std::vector<double>& ts = times[2 * i + size_t(kind)];
      std::sort(ts.begin(), ts.end());
      x.got[kind].ms = ts[ts.size() / 2];
      ok &= x.got[kind].pairs == variants[0].got[kind].pairs;
      char label[200];
      const char* builds[3] = {"Morton, cells per axis", "Morton, cubic cells", "SAH"};
      const char* marks[3][2] = {{"", " (before)"}, {"", " (kept)"}, {"", ""}};  // [build][refit]
      std::snprintf(label, sizeof label, "%s, %s%s: growth %.2f, build both %.1f ms", builds[x.build],
                    x.refit ? "built at frame 0, refit" : "rebuilt at the last frame", marks[x.build][x.refit],
                    growth(x.trees[kind].area_cost(), x.trees[kind].cost_at_build()), x.build_ms);
      out += row(sc.name, kind ? "EE" : "VT", "box", label, x.got[kind], kind ? ne : nv, variants[0].got[kind]);
    }
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
         compare_box_tests(sc, trees, v, t, e, r, repeats);
}

}  // namespace

int main(int argc, char** argv) {
  try {
    std::string data = MINKQ_BENCH_DATA_DIR, out = MINKQ_BENCH_RESULTS_DIR;
    int repeats = 5;
    double scale = 0;  // reference sizes
    std::string sections = "all";  // or "traversal" (ablation.md) or "trees" (trees.md)
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      if (a == "--quick") repeats = 1;
      else if (a == "--out" && i + 1 < argc) out = argv[++i];
      else if (a == "--data" && i + 1 < argc) data = argv[++i];
      else if (a == "--triangles" && i + 1 < argc) scale = std::stod(argv[++i]);
      else if (a == "--only" && i + 1 < argc && (std::string(argv[i + 1]) == "traversal" || std::string(argv[i + 1]) == "trees"))
        sections = argv[++i];
      else {
        std::fprintf(stderr,
                     "usage: minkq_ablation [--quick] [--out DIR] [--data DIR] [--triangles N] [--only traversal|trees]\n");
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
    if (sections != "trees") {
      std::ostringstream o;
      o << "# Traversal ablation (issue 8)\n\nMachine: " << machine_line("cpu (core traversal, TBB)")
        << ". Load average (1 min) at start " << fmt(load_average(), 3) << ". Last frame of each scene, r = the scene's "
        << "radius, incident pairs dropped, CPU backend traversal on all threads; counts per query; " << timing
        << table_head;
      for (const std::string& name : {std::string("twist_target"), std::string("cloth_twist"), std::string("cloth_hanging"),
                                      std::string("softbody_gift")})
        o << compare_scene(make_scene(name, scale, 2, data), repeats, ok);
      for (const RealMesh& m : real_meshes())
        if (m.name == "unisex_shirt" || m.name == "multilayer_drape") o << compare_scene(load_real_scene(m, data), repeats, ok);
      for (const double hr : {0.01, 1.0}) o << compare_fine_nodes_spread(200000, hr, repeats, ok);
      o << "\nLoad average at end " << fmt(load_average(), 3) << ".\n";
      write("ablation.md", o.str());
    }
    if (sections != "traversal") {
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
