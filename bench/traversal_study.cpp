// minkq_traversal_study: the self-queries' half traversal (traversal.h: a walk down the splits
// to the query's own leaf with no box test, then the nodes after it) beside the top-down walk
// it replaced (bench/studies/top_down_traversal.h) and beside queries run in groups
// (bench/studies/grouped_queries.h, not kept), in the same run, on the same trees and
// threads. Per scene: EE in box and capsule_exact modes (incident pairs dropped) over the edge
// tree, VV in box mode over the vertex tree, and VT in box and sphere modes (the vertices in
// Morton order against the triangle tree: no self-query, so only the grouped run differs
// there). Each query's pairs are first checked equal, in the order met, between the three; then
// each is counted (MINKQ_QUERY_STATS' counters) and timed, round by round. Writes traversal.md.
//
// usage: minkq_traversal_study [--threads N] [--repeats N] [--quick] [--large] [--data DIR] [--out DIR]
//   --large adds the 1M-triangle twisted sheet; --quick: small scenes, 3 repeats, no file written.
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <atomic>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "common.h"
#include "cpu/tree.h"
#include "scenes.h"
#include "study_options.h"
#include "studies/grouped_queries.h"
#include "studies/top_down_traversal.h"

using namespace minkq;
using namespace minkq::bench;

namespace {

struct Row {
  std::string scene, kind, mode;
  int32_t queries = 0;
  uint64_t pairs = 0;
  WorkCounts top_down, half, grouped;
  Timing t_top_down, t_half, t_grouped;
};

constexpr int32_t kBlock = 256;  // queries per parallel task, as cpu/passes.h

// Every query of the batch through one walk, counting pairs (the COUNT query's work).
enum Walk { kTopDown, kHalf, kGrouped };

// Queries [begin, end) through one walk.
template <class Shape, Walk kWalk, class Queries, class Emit, class Work>
void run_range(const BvhView& bvh, const Queries& queries, int32_t begin, int32_t end, Emit& emit, Work& work) {
  if constexpr (kWalk == kGrouped) {
    run_grouped<Shape>(bvh, queries, begin, end, emit, work);
  } else {
    for (int32_t i = begin; i < end; ++i) {
      if constexpr (kWalk == kHalf) run_query<Shape>(bvh, queries, i, emit, work);
      else run_query_top_down<Shape>(bvh, queries, i, emit, work);
    }
  }
}

template <class Shape, Walk kWalk, class Queries>
uint64_t count_all(const BvhView& bvh, const Queries& queries, int32_t n) {
  std::atomic<uint64_t> total{0};
  tbb::parallel_for(int32_t(0), (n + kBlock - 1) / kBlock, [&](int32_t b) {
    uint64_t count = 0;
    auto emit = [&count](int32_t, int32_t) { ++count; };
    NoWork work;
    run_range<Shape, kWalk>(bvh, queries, b * kBlock, std::min(n, (b + 1) * kBlock), emit, work);
    total += count;
  });
  return total;
}

// Pairs of every query in the order met, and the work counters, through one walk (serial).
// In blocks of kBlock queries, as count_all.
template <class Shape, Walk kWalk, class Queries>
std::vector<Pair> pairs_of(const BvhView& bvh, const Queries& queries, int32_t n, WorkCounts& work) {
  std::vector<Pair> pairs;
  auto emit = [&pairs](int32_t a, int32_t b) { pairs.push_back({a, b}); };
  for (int32_t b = 0; b * kBlock < n; ++b) run_range<Shape, kWalk>(bvh, queries, b * kBlock, std::min(n, (b + 1) * kBlock), emit, work);
  return pairs;
}

template <class Shape, class Queries>
bool study(const std::string& scene, const char* kind, const char* mode, const BvhView& bvh, const Queries& queries,
           int32_t n, int warmup, int repeats, std::vector<Row>& rows) {
  Row row;
  row.scene = scene, row.kind = kind, row.mode = mode, row.queries = n;
  const std::vector<Pair> a = pairs_of<Shape, kTopDown>(bvh, queries, n, row.top_down);
  const std::vector<Pair> b = pairs_of<Shape, kHalf>(bvh, queries, n, row.half);
  const std::vector<Pair> c = pairs_of<Shape, kGrouped>(bvh, queries, n, row.grouped);
  auto same = [](const std::vector<Pair>& x, const std::vector<Pair>& y) {
    bool equal = x.size() == y.size();
    for (size_t i = 0; equal && i < x.size(); ++i) equal = x[i].first == y[i].first && x[i].second == y[i].second;
    return equal;
  };
  if (!same(a, b) || !same(a, c) || row.top_down.nodes_visited != row.half.nodes_visited) {
    std::fprintf(stderr, "FAIL %s %s %s: the walks meet different pairs (%zu top-down, %zu half, %zu grouped)\n",
                 scene.c_str(), kind, mode, a.size(), b.size(), c.size());
    return false;
  }
  row.pairs = a.size();
  std::vector<double> t_a, t_b, t_c;
  for (int k = 0; k < warmup + repeats; ++k) {
    double start = now_ms();
    const uint64_t ca = count_all<Shape, kTopDown>(bvh, queries, n);
    const double ta = now_ms() - start;
    start = now_ms();
    const uint64_t cb = count_all<Shape, kHalf>(bvh, queries, n);
    const double tb = now_ms() - start;
    start = now_ms();
    const uint64_t cc = count_all<Shape, kGrouped>(bvh, queries, n);
    const double tc = now_ms() - start;
    if (ca != row.pairs || cb != row.pairs || cc != row.pairs) {
      std::fprintf(stderr, "FAIL %s %s %s: counts %llu / %llu / %llu, not %llu\n", scene.c_str(), kind, mode,
                   (unsigned long long)ca, (unsigned long long)cb, (unsigned long long)cc, (unsigned long long)row.pairs);
      return false;
    }
    if (k >= warmup) t_a.push_back(ta), t_b.push_back(tb), t_c.push_back(tc);
  }
  row.t_top_down = summarize(t_a);
  row.t_half = summarize(t_b);
  row.t_grouped = summarize(t_c);
  rows.push_back(row);
  return true;
}

bool study_scene(const SceneFrames& sc, int warmup, int repeats, std::vector<Row>& rows) {
  const auto* v = reinterpret_cast<const Vec3*>(sc.frames[0].data());
  const auto* e = reinterpret_cast<const Edge*>(sc.mesh.edges.data());
  const int32_t num_edges = int32_t(sc.mesh.edges.size() / 2), num_vertices = int32_t(sc.frames[0].size() / 3);
  const float r = float(sc.radius_factor * sc.mean_edge);
  std::fprintf(stderr, "%s: %d edges, r = %g\n", sc.name.c_str(), int(num_edges), double(r));
  const auto* t = reinterpret_cast<const Triangle*>(sc.mesh.tris.data());
  CpuTree edge_tree, vertex_tree, triangle_tree;
  edge_tree.build(EdgeBoxes{v, e}, num_edges);
  vertex_tree.build(PointBoxes{v}, num_vertices);
  triangle_tree.build(TriangleBoxes{v, t}, int32_t(sc.mesh.triangle_count()));
  // VT: the vertices in their Morton order (the vertex tree's leaf order), as the library runs them.
  const VertexTriangleQueries vt{v, t, vertex_tree.sorted_prims().data(), r, kDropIncident};
  const EdgeEdgeQueries ee{v, e, edge_tree.sorted_prims().data(), r, kDropIncident};
  const VertexVertexQueries vv{v, vertex_tree.sorted_prims().data(), r, 0};
  bool ok = study<BoxShape>(sc.name, "EE", "box", edge_tree.view(), ee, num_edges, warmup, repeats, rows);
  ok = study<CapsuleExactShape>(sc.name, "EE", "capsule_exact", edge_tree.view(), ee, num_edges, warmup, repeats, rows) && ok;
  ok = study<BoxShape>(sc.name, "VV", "box", vertex_tree.view(), vv, num_vertices, warmup, repeats, rows) && ok;
  ok = study<BoxShape>(sc.name, "VT", "box", triangle_tree.view(), vt, num_vertices, warmup, repeats, rows) && ok;
  ok = study<SphereShape>(sc.name, "VT", "sphere", triangle_tree.view(), vt, num_vertices, warmup, repeats, rows) && ok;
  return ok;
}

double per_query(uint64_t count, int32_t queries) { return queries ? double(count) / queries : 0.0; }

}  // namespace

int main(int argc, char** argv) {
  try {
    StudyOptions opt{MINKQ_BENCH_DATA_DIR, MINKQ_BENCH_RESULTS_DIR};
    if (!parse_study_options(argc, argv, "minkq_traversal_study", opt)) return 2;
    const std::string& out = opt.out;
    const int threads = opt.threads, repeats = opt.repeats;
    const bool quick = opt.quick;
    tbb::global_control control(tbb::global_control::max_allowed_parallelism, size_t(std::max(1, threads)));
    const int warmup = 2;
    const double load_start = load_average();
    std::vector<Row> rows;
    const bool ok = for_each_study_scene(opt, true, [&](const SceneFrames& sc) {
      return study_scene(sc, warmup, repeats, rows);
    });
    if (rows.empty()) {  // no table to write over the last one
      std::fprintf(stderr, ok ? "FAIL: no scene was studied\n" : "FAIL: the walks differ\n");
      return 1;
    }
    std::ostringstream o;
    o << "# Queries: the half traversal beside the top-down walk, and grouped queries (issue 27)\n\n"
      << written_by(opt, "minkq_traversal_study", load_start)
      << "**top-down** = the self-query's walk before (bench/studies/top_down_traversal.h: from the root, both "
      << "children of every node tested, left children ending at or before the query's own leaf skipped); "
      << "**half** = traversal.h's (down the splits to the query's own leaf with no box test, then the nodes "
      << "after it); VT is no self-query, so its top-down and half walks are the same walk; **grouped** = "
      << "bench/studies/grouped_queries.h, not kept (the EE or VV queries of one leaf range, or 16 consecutive VT "
      << "queries, share one walk with the box around all their boxes, then each scans the listed leaf ranges its "
      << "own box test passes). Same trees (the library's build), frame 0 of each scene, r = the scene's radius; "
      << "EE drops edges sharing a vertex, VT a vertex's own triangles; VT runs the vertices in Morton order. Each query's pairs were checked equal, in the order met, before timing. Work "
      << "per query from the counters of MINKQ_QUERY_STATS (nodes: internal node records read; node tests: "
      << "child boxes and leaf boxes tested). Times: every query counted (no pairs written) in blocks of "
      << kBlock << " queries over TBB, as MINKQ_QUERY_COUNT does, round by round, " << warmup << " untimed and "
      << repeats << " timed; ms = median (range); speed-ups over top-down.\n\n"
      << "| scene | kind | mode | queries | pairs | nodes / query, walk → grouped | node tests / query, top-down → half → grouped | "
         "top-down ms | half ms | grouped ms | half speed-up | grouped speed-up |\n"
         "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const Row& r : rows)
      o << "| " << r.scene << " | " << r.kind << " | " << r.mode << " | " << r.queries << " | " << r.pairs << " | "
        << fmt(per_query(r.half.nodes_visited, r.queries), 3) << " → " << fmt(per_query(r.grouped.nodes_visited, r.queries), 3)
        << " | " << fmt(per_query(r.top_down.node_tests, r.queries), 3) << " → "
        << fmt(per_query(r.half.node_tests, r.queries), 3) << " → " << fmt(per_query(r.grouped.node_tests, r.queries), 3)
        << " | " << r.t_top_down.text() << " | " << r.t_half.text() << " | " << r.t_grouped.text() << " | "
        << fmt(r.t_top_down.median / r.t_half.median, 3) << "x | " << fmt(r.t_top_down.median / r.t_grouped.median, 3)
        << "x |\n";
    if (!quick) {
      const std::string file = out + "/traversal.md";
      std::ofstream(file) << o.str();
      std::fprintf(stderr, "wrote %s\n", file.c_str());
    }
    std::fprintf(stderr, "%s", o.str().c_str());
    if (!ok) {
      std::fprintf(stderr, "FAIL: the walks differ\n");
      return 1;
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "minkq_traversal_study: %s\n", e.what());
    return 1;
  }
}
