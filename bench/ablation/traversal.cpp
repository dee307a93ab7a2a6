// minkq_ablation's traversal study (ablation.md, issue 8): the library's traversal habits
// against the variants they replaced, on the same trees (see main.cpp's header).
#include <cmath>
#include <cstdio>
#include <type_traits>

#include "ablation/ablation.h"
#include "studies/variants.h"

namespace minkq::bench::ablation {
namespace {

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

// Trees with leaf ranges of up to 1 (the binary tree: before), 2, 4, 8, 16, 32 and 64 primitives
// (the library's kLeafSize marked kept): VT sphere, EE box and EE capsule_exact on each; the
// pairs must not change.
std::string compare_leaf_sizes(const SceneFrames& sc, const Vec3* v, const Triangle* t, const Edge* e, float r,
                               int repeats, bool& ok) {
  const int32_t nv = int32_t(sc.mesh.vertex_count()), nt = int32_t(sc.mesh.triangle_count());
  const int32_t ne = int32_t(sc.mesh.edge_count());
  HostVector<int32_t> order;
  SortScratch scratch;
  sort_by_morton(PointBoxes{v}, nv, order, scratch);
  std::string out;
  Outcome base[3];
  for (int32_t leaf : {1, 2, 4, 8, 16, 32, 64}) {
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

}  // namespace

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
         compare_box_tests(sc, trees, v, t, e, r, repeats) + compare_leaf_lanes(sc, trees, v, t, e, r, repeats, ok);
}

}  // namespace minkq::bench::ablation
