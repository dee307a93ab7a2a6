// minkq_ablation's shared parts (bench/ablation/): what every study of the program uses to run
// and time a variant's queries and to print its row, the trees of a frame, and the studies'
// entry points, one file each (main.cpp writes their tables).
#pragma once

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "common.h"
#include "cpu/tree.h"
#include "minkq/queries.h"
#include "scenes.h"

namespace minkq::bench::ablation {

struct Outcome {
  WorkCounts work;
  double ms = 0;
  std::vector<uint64_t> pairs;  // sorted (first << 32 | second)
};

inline double median(std::vector<double> v) {
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

inline std::string row(const std::string& scene, const char* kind, const char* mode, const char* variant, const Outcome& o,
                int32_t queries, const Outcome& base) {
  std::ostringstream s;
  const double q = double(queries);
  s << "| " << scene << " | " << kind << " | " << mode << " | " << variant << " | " << fmt(double(o.work.nodes_visited) / q, 4)
    << " | " << fmt(double(o.work.node_tests) / q, 4) << " | " << fmt(double(o.work.primitive_tests) / q, 4) << " | "
    << o.pairs.size() << " | " << fmt(o.ms, 4) << " | " << fmt(base.ms / o.ms, 3) << "x |\n";
  return s.str();
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

// The studies, each returning its table rows (ok is cleared when a variant's pairs differ).
// traversal.cpp (ablation.md): queries in vertex id or Morton order, EE met twice or once,
// leaf sizes, fine node tests, leaf scans in lanes, the two box tests; and the fine node
// tests on 3-D-spread user boxes.
std::string compare_scene(const SceneFrames& sc, int repeats, bool& ok);
std::string compare_fine_nodes_spread(int32_t n, double hr, int repeats, bool& ok);
// trees.cpp (trees.md): Morton frames and the SAH build, refit or rebuilt.
std::string compare_tree_builds(const SceneFrames& sc, int repeats, bool& ok);
// wide.cpp (wide.md): 4- and 8-ary nodes; appends the node bytes read per query to bytes_read.
std::string compare_wide(const SceneFrames& sc, int repeats, bool& ok, std::string& bytes_read);
// policies.cpp (policies.md): rebuild policies end to end through the C API.
std::string compare_policies(const SceneFrames& sc, int rounds, bool& ok);
// contacts.cpp (contacts.md): node test and leaf screen under the leaf distance test.
std::string compare_contacts(const SceneFrames& sc, int repeats, bool& ok);
// fused.cpp (fused.md): minkq_scene_query_vt_ee against two minkq_scene_query calls.
std::string compare_fused(const SceneFrames& sc, minkq_device* device, int rounds, bool& ok);

}  // namespace minkq::bench::ablation
