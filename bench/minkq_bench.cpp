// minkq_bench: the benchmark driver of issue 7. For each scene, frame, backend and mode it
// measures BVH build, refit, VT and EE query time (warm-up, repeats, median and range),
// candidates, true contacts (the double-precision reference oracle), false-positive ratio and
// false negatives (any non-zero count fails the run), the speedup against box mode and against
// Embree's point query on the CPU, and a measured narrow-phase cost per candidate for the
// end-to-end estimate. Writes Markdown tables and CSV files naming the machine; see
// bench/README.md and `minkq_bench --help`.
#include <malloc.h>
#include <tbb/global_control.h>
#include <tbb/parallel_reduce.h>
#include <tbb/blocked_range.h>

#include <cinttypes>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <functional>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "common.h"
#include "cpu/tree.h"
#include "minkq/queries.h"
#include "embree_vt.h"
#include "minkq/predicates.h"
#include "scenes.h"

namespace fs = std::filesystem;
namespace ref = minkq::reference;
using namespace minkq::bench;

namespace {

const char* const kUsage = R"(usage: minkq_bench [options]

Runs the benchmark suites and writes Markdown tables and CSV files to --out.

suites (--suites, comma separated; default scenes,real,sweep,scale):
  scenes  the eight Newton scenes at reference size plus REFERENCES.md's twisted sheet
          (256^2), every frame: build, refit, VT/EE in every mode, Embree VT, narrow phase
  real    the real meshes (data/meshes.tar.xz, the larger ones from --data) at r = 0.25 x mean edge
  sweep   radius sweep 0.1x-8x mean edge on the last frame of each scene (real meshes to 2x)
  scale   large instances (--scale-triangles) of --scale-scenes

options:
  --data DIR              the benchmark-only meshes (default: ../shared/data beside the source tree;
                          a mesh in neither it nor data/meshes.tar.xz is skipped, by name)
  --out DIR               result folder (default: bench/results in the source tree)
  --quick                 smoke run (seconds): reference scenes, 2 frames, 1 repeat, no
                          warm-up, suites scenes only, written to --out (give one!)
  --frames N              frames per scene in the scenes suite (default 4)
  --repeats N             timed repeats per measurement (default 5; sweep/scale use fewer)
  --warmup N              untimed runs before them (default 1)
  --threads N             limit TBB (minkq CPU backend, oracle, Embree loop) to N threads
  --backends LIST         cpu,cuda (default: cpu, and cuda where a GPU is usable)
  --scenes LIST           only these procedural scenes (scenes, sweep suites)
  --scale-scenes LIST     scenes of the scale suite (default twist_target; any scene name)
  --scale-triangles LIST  target sizes (default 1e6,2e6)
  --no-embree             skip the Embree baseline
  --export DIR            also write every scene's frames as binary files for warp_baseline.py
  --export-only DIR       write them and measure nothing (the oracle is not run either)
  --list                  print the scenes (vertices, triangles, edges, radius) and exit
  --list-at T             the same for the procedural scenes scaled to about T triangles

exit status: 0 success, 1 false negatives found, 2 bad arguments, 3 failure
)";

struct Options {
  std::string data_dir = MINKQ_BENCH_DATA_DIR;
  std::string out_dir = MINKQ_BENCH_RESULTS_DIR;
  bool quick = false, embree = true, list = false;
  double list_at = 0;  // --list-at: list the scenes at this many triangles
  bool export_only = false;
  int frames = 4, repeats = 5, warmup = 1, threads = 0;
  std::set<std::string> suites = {"scenes", "real", "sweep", "scale"};
  std::vector<std::string> backends;
  std::vector<std::string> scenes;
  std::vector<std::string> scale_scenes = {"twist_target"};
  std::vector<double> scale_triangles = {1e6, 2e6};
  std::string export_dir;
};

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ','))
    if (!item.empty()) out.push_back(item);
  return out;
}

struct ModeSpec {
  minkq_query_kind kind;
  const char* name;
  minkq_mode mode;
  uint32_t flags;
};
// VT capsule_ray / capsule_exact are box / sphere for points (minkq.h), so they are not repeated.
// leaf_exact (the contacts) runs behind the box node test: 1.03-1.21x (VT) and 2.12-2.82x (EE)
// faster than behind sphere / capsule_exact (minkq_ablation --only contacts).
const ModeSpec kModes[] = {
    {MINKQ_QUERY_VT, "box", MINKQ_MODE_BOX, 0},
    {MINKQ_QUERY_VT, "sphere", MINKQ_MODE_SPHERE, 0},
    {MINKQ_QUERY_VT, "leaf_exact", MINKQ_MODE_BOX, MINKQ_QUERY_LEAF_EXACT},
    {MINKQ_QUERY_EE, "box", MINKQ_MODE_BOX, 0},
    {MINKQ_QUERY_EE, "capsule_ray", MINKQ_MODE_CAPSULE_RAY, 0},
    {MINKQ_QUERY_EE, "capsule_exact", MINKQ_MODE_CAPSULE_EXACT, 0},
    {MINKQ_QUERY_EE, "leaf_exact", MINKQ_MODE_BOX, MINKQ_QUERY_LEAF_EXACT},
};

struct QueryRow {
  std::string suite, scene, backend, kind, mode;
  int64_t vertices = 0, triangles = 0, edges = 0;
  int frame = 0;
  double factor = 0, r = 0;
  Timing t;
  uint64_t candidates = 0, truth = 0, fn = 0;
  int64_t diff_vs_leaf = -1;  // Embree rows: size of the symmetric difference with minkq's leaf_exact set
  minkq_query_stats work{};   // minkq rows: the traversal's work (MINKQ_QUERY_STATS, one untimed run)
  double load = 0;
  double fp() const { return truth ? (double(candidates) - double(truth)) / double(truth) : NAN; }
};
struct StepRow {  // build or refit
  std::string suite, scene, backend, step;
  int64_t triangles = 0;
  int frame = 0;
  Timing t;
  double load = 0;
};
struct NarrowRow {
  std::string suite, scene, kind;
  double ns_per_candidate = 0;
  uint64_t candidates = 0;
};
struct SceneInfo {
  std::string suite, scene, recipe;
  int64_t vertices = 0, triangles = 0, edges = 0;
  int frames = 0;
  double factor = 0, r = 0, mean_edge = 0, oracle_ms = 0, load_start = 0, load_end = 0;
  std::vector<uint64_t> vt_truth, ee_truth;
  double layout_bytes = 0, rss_bytes = 0;
};

struct Report {
  std::vector<QueryRow> queries;
  std::vector<StepRow> steps;
  std::vector<NarrowRow> narrow;
  std::vector<SceneInfo> scenes;
  std::vector<std::string> skipped;
  uint64_t false_negatives = 0;
};

// Bytes of trees and scene data of a CPU VT+EE scene from the library's layouts: vertices
// (12 B) in the store (the only copy: the C API keeps none), the triangles and the edges in
// their trees' leaf order only (TriangleGroup: 48 B per four, EdgeGroup: 32 B per four) and the
// vertices' query order (4 B); per tree what CpuTree::bytes() counts (node records of 64 B plus
// a 4 B refit counter, and per primitive a sorted-order id and a leaf box, 4 + 24 B) on the
// library's own trees, built here.
double layout_bytes(const SceneFrames& sc) {
  const auto* v = reinterpret_cast<const minkq::Vec3*>(sc.mesh.xyz.data());
  const auto* t = reinterpret_cast<const minkq::Triangle*>(sc.mesh.tris.data());
  const auto* e = reinterpret_cast<const minkq::Edge*>(sc.mesh.edges.data());
  const int64_t nv = int64_t(sc.mesh.vertex_count()), nt = int64_t(sc.mesh.triangle_count());
  const int64_t ne = int64_t(sc.mesh.edge_count());
  minkq::CpuTree triangles, edges;
  triangles.build(minkq::TriangleBoxes{v, t}, int32_t(nt));
  edges.build(minkq::EdgeBoxes{v, e}, int32_t(ne));
  const double leaf_triangles = double(sizeof(minkq::TriangleGroup)) * double(minkq::box_group_count(nt));
  const double leaf_edges = double(sizeof(minkq::EdgeGroup)) * double(minkq::box_group_count(ne));
  return 16.0 * double(nv) + leaf_triangles + leaf_edges + double(triangles.bytes() + edges.bytes());
}

// The narrow phase a simulator runs on every candidate, at its cheapest: the double-precision
// distance test minkq's leaf_exact applies (core/include/minkq/predicates.h), over the box
// candidates, on the same threads. Returns ns per candidate.
double measure_narrow(const SceneFrames& sc, const std::vector<float>& xyz, bool vt, const std::vector<int32_t>& pairs,
                      float r, int warmup, int repeats) {
  const uint64_t n = pairs.size() / 2;
  if (n == 0) return NAN;
  auto at = [&](int32_t i) { return minkq::Vec3{xyz[3 * size_t(i)], xyz[3 * size_t(i) + 1], xyz[3 * size_t(i) + 2]}; };
  const auto& tris = sc.mesh.tris;
  const auto& edges = sc.mesh.edges;
  volatile uint64_t sink = 0;
  const Timing t = measure(warmup, repeats, [&] {
    sink = tbb::parallel_reduce(
        tbb::blocked_range<uint64_t>(0, n, 4096), uint64_t(0),
        [&](const tbb::blocked_range<uint64_t>& range, uint64_t acc) {
          for (uint64_t i = range.begin(); i != range.end(); ++i) {
            const int32_t a = pairs[2 * i], b = pairs[2 * i + 1];
            if (vt)
              acc += minkq::point_triangle_within(at(a), at(tris[3 * size_t(b)]), at(tris[3 * size_t(b) + 1]),
                                                  at(tris[3 * size_t(b) + 2]), r);
            else
              acc += minkq::segment_segment_within(at(edges[2 * size_t(a)]), at(edges[2 * size_t(a) + 1]),
                                                   at(edges[2 * size_t(b)]), at(edges[2 * size_t(b) + 1]), r);
          }
          return acc;
        },
        [](uint64_t x, uint64_t y) { return x + y; });
  });
  (void)sink;
  return t.median * 1e6 / double(n);
}

void export_scene(const std::string& dir, const SceneFrames& sc, const std::string& tag, float r) {
  fs::create_directories(dir);
  // Little-endian: "MKQB", u32 version 1, u32 V, T, E, F, f32 r, then F frames of 3V f32,
  // 3T i32, 2E i32.
  std::ofstream f(dir + "/" + tag + ".mkqb", std::ios::binary);
  auto u32 = [&](uint32_t x) { f.write(reinterpret_cast<const char*>(&x), 4); };
  f.write("MKQB", 4);
  u32(1);
  u32(uint32_t(sc.mesh.vertex_count()));
  u32(uint32_t(sc.mesh.triangle_count()));
  u32(uint32_t(sc.mesh.edge_count()));
  u32(uint32_t(sc.frames.size()));
  f.write(reinterpret_cast<const char*>(&r), 4);
  for (const auto& fr : sc.frames) f.write(reinterpret_cast<const char*>(fr.data()), std::streamsize(fr.size() * 4));
  f.write(reinterpret_cast<const char*>(sc.mesh.tris.data()), std::streamsize(sc.mesh.tris.size() * 4));
  f.write(reinterpret_cast<const char*>(sc.mesh.edges.data()), std::streamsize(sc.mesh.edges.size() * 4));
  if (!f) throw std::runtime_error("cannot write " + dir + "/" + tag + ".mkqb");
}

struct CaseConfig {
  std::string suite;
  double factor = -1;  // < 0: the scene's own radius factor
  std::string tag;     // scene label in the tables (default: scene name)
  bool embree = true, narrow = true, steps = true;
  int repeats = 5, warmup = 1;
  double max_pairs = 0;  // > 0: skip the case when box mode would return more pairs than this
};

void run_scene(const SceneFrames& sc, const CaseConfig& cfg, const Options& opt, Report& rep) {
  const std::string label = cfg.tag.empty() ? sc.name : cfg.tag;
  const double factor = cfg.factor >= 0 ? cfg.factor : sc.radius_factor;
  const float r = float(factor * sc.mean_edge);
  SceneInfo info;
  info.suite = cfg.suite;
  info.scene = label;
  info.recipe = sc.recipe;
  info.vertices = int64_t(sc.mesh.vertex_count());
  info.triangles = int64_t(sc.mesh.triangle_count());
  info.edges = int64_t(sc.mesh.edge_count());
  info.frames = int(sc.frames.size());
  info.factor = factor;
  info.r = r;
  info.mean_edge = sc.mean_edge;
  info.load_start = load_average();
  info.layout_bytes = layout_bytes(sc);
  if (cfg.max_pairs > 0) {  // count box candidates without storing them (capacity 0)
    Device dev = open_device("cpu");
    Scene scene = create_scene(dev.get(), sc.frames.back(), sc.mesh.tris);
    for (minkq_query_kind kind : {MINKQ_QUERY_VT, MINKQ_QUERY_EE}) {
      const minkq_query_desc q{kind, MINKQ_MODE_BOX, 0, r};
      minkq_query_info qi{};
      const minkq_status st = minkq_scene_query(scene.get(), &q, nullptr, 0, MINKQ_MEMORY_HOST, &qi);
      if (st != MINKQ_SUCCESS && st != MINKQ_ERROR_CAPACITY) check(st, "minkq_scene_query");
      if (double(qi.count) > cfg.max_pairs) {
        std::fprintf(stderr, "[%s] %s: skipped, %s box mode would return %" PRIu64 " pairs (limit %.3g)\n", cfg.suite.c_str(),
                     label.c_str(), kind == MINKQ_QUERY_VT ? "VT" : "EE", qi.count, cfg.max_pairs);
        rep.skipped.push_back(label + " (" + (kind == MINKQ_QUERY_VT ? "VT" : "EE") + " box mode: " + fmt_count(double(qi.count)) + " pairs)");
        return;
      }
    }
  }
  std::fprintf(stderr, "[%s] %s: %" PRId64 " V, %" PRId64 " T, %" PRId64 " E, %d frames, r = %.4g (%.3gx mean edge), load %.2f\n",
               cfg.suite.c_str(), label.c_str(), info.vertices, info.triangles, info.edges, info.frames, double(r), factor,
               info.load_start);
  if (!opt.export_dir.empty()) export_scene(opt.export_dir, sc, cfg.suite + "__" + label, r);
  if (opt.export_only) return;

  // The oracle, once per frame (shared by every backend and mode).
  std::vector<PairSet> vt_truth, ee_truth;
  const double t0 = now_ms();
  for (const auto& xyz : sc.frames) {
    ref::Mesh m = sc.mesh;
    m.xyz = xyz;
    vt_truth.push_back(to_set(ref::vt_contacts(m, r, true)));
    ee_truth.push_back(to_set(ref::ee_contacts(m, r, true)));
    info.vt_truth.push_back(vt_truth.back().size());
    info.ee_truth.push_back(ee_truth.back().size());
  }
  info.oracle_ms = now_ms() - t0;

  // Per frame, every timed contestant (each minkq mode on each backend, and Embree) runs once
  // per round, round after round, so a change of machine load hits all of them alike and the
  // ratios between them stay meaningful on a shared machine.
  struct Contestant {
    std::string backend;
    const ModeSpec* mode;  // null for Embree
    std::function<void()> run;
    std::function<PairSet()> pairs;
    std::vector<double> times;
    std::function<minkq_query_stats()> work;  // minkq only: an untimed run with MINKQ_QUERY_STATS
  };
  std::vector<int32_t> box_vt, box_ee;  // box candidates of the last frame (cpu)
  std::vector<Device> devices;
  std::vector<Scene> scenes;
  std::vector<std::vector<Result>> results;  // per backend, per mode
  for (const std::string& backend : opt.backends) {
    devices.push_back(open_device(backend));
    if (cfg.steps) {
      malloc_trim(0);
      const double rss0 = resident_bytes();
      scenes.push_back(create_scene(devices.back().get(), sc.frames[0], sc.mesh.tris));
      if (backend == "cpu") info.rss_bytes = resident_bytes() - rss0;
      Scene& scene = scenes.back();
      const Timing tb = measure(cfg.warmup, cfg.repeats, [&] { scene = create_scene(devices.back().get(), sc.frames[0], sc.mesh.tris); },
                                [&] { scene.reset(); });
      rep.steps.push_back({cfg.suite, label, backend, "build", info.triangles, 0, tb, load_average()});
    } else {
      scenes.push_back(create_scene(devices.back().get(), sc.frames[0], sc.mesh.tris));
    }
    // The library must number edges as derive_edges does, or the oracle's pairs mean other edges.
    std::vector<int32_t> edges(2 * minkq_scene_edge_count(scenes.back().get()));
    check(minkq_scene_edges(scenes.back().get(), edges.data(), edges.size() / 2), "minkq_scene_edges");
    if (edges != sc.mesh.edges) throw std::runtime_error(label + ": the library's edge numbering differs from derive_edges");
    results.emplace_back();
    for (size_t m = 0; m < std::size(kModes); ++m) results.back().push_back(new_result());
  }
  std::unique_ptr<EmbreeVT> em;
  std::vector<int32_t> embree_pairs;
  const bool with_embree = cfg.embree && opt.embree;
  if (with_embree) {
    const Timing tb = measure(cfg.warmup, cfg.repeats, [&] { em = std::make_unique<EmbreeVT>(sc.frames[0], sc.mesh.tris); },
                              [&] { em.reset(); });
    if (cfg.steps) rep.steps.push_back({cfg.suite, label, "embree", "build", info.triangles, 0, tb, load_average()});
  }

  for (size_t k = 0; k < sc.frames.size(); ++k) {
    if (k > 0) {
      const minkq_buffer vb{sc.frames[k].data(), 12, sc.frames[k].size() / 3, MINKQ_MEMORY_HOST};
      for (size_t b = 0; b < opt.backends.size(); ++b) {
        minkq_scene* scene = scenes[b].get();
        const Timing tr = measure(cfg.warmup, cfg.repeats, [&] { check(minkq_scene_refit(scene, vb), "minkq_scene_refit"); });
        if (cfg.steps) rep.steps.push_back({cfg.suite, label, opt.backends[b], "refit", info.triangles, int(k), tr, load_average()});
      }
      if (with_embree) {
        const Timing tr = measure(cfg.warmup, cfg.repeats, [&] { em->refit(sc.frames[k]); });
        if (cfg.steps) rep.steps.push_back({cfg.suite, label, "embree", "refit", info.triangles, int(k), tr, load_average()});
      }
    }
    std::vector<Contestant> cs;
    for (size_t b = 0; b < opt.backends.size(); ++b)
      for (size_t m = 0; m < std::size(kModes); ++m) {
        minkq_scene* scene = scenes[b].get();
        minkq_result* res = results[b][m].get();
        const ModeSpec* mode = &kModes[m];
        cs.push_back({opt.backends[b], mode,
                      [scene, res, mode, r] {
                        const minkq_query_desc q{mode->kind, mode->mode, mode->flags, r};
                        check(minkq_scene_query_result(scene, &q, res), "minkq_scene_query_result");
                      },
                      [res] { return to_set(minkq_result_pairs(res), minkq_result_count(res)); }, {},
                      [scene, res, mode, r] {
                        const minkq_query_desc q{mode->kind, mode->mode, mode->flags | MINKQ_QUERY_STATS, r};
                        check(minkq_scene_query_result(scene, &q, res), "minkq_scene_query_result");
                        return minkq_result_stats(res);
                      }});
      }
    if (with_embree)
      cs.push_back({"embree", nullptr, [&] { em->query(r, embree_pairs); },
                    [&] { return to_set(embree_pairs.data(), embree_pairs.size() / 2); }, {}, {}});
    for (int w = 0; w < cfg.warmup; ++w)
      for (auto& c : cs) c.run();
    for (int round = 0; round < cfg.repeats; ++round)
      for (auto& c : cs) {
        const double start = now_ms();
        c.run();
        c.times.push_back(now_ms() - start);
      }
    if (cfg.warmup == 0 && cfg.repeats == 0)
      for (auto& c : cs) c.run();
    PairSet leaf_vt;  // minkq's cpu leaf_exact VT set, for the Embree comparison
    for (auto& c : cs) {
      std::sort(c.times.begin(), c.times.end());
      Timing t;
      t.repeats = int(c.times.size());
      t.min = c.times.front(), t.max = c.times.back();
      t.median = t.repeats % 2 ? c.times[size_t(t.repeats) / 2] : 0.5 * (c.times[size_t(t.repeats) / 2 - 1] + c.times[size_t(t.repeats) / 2]);
      const PairSet got = c.pairs();
      const bool vt = !c.mode || c.mode->kind == MINKQ_QUERY_VT;
      const PairSet& truth = vt ? vt_truth[k] : ee_truth[k];
      QueryRow row;
      row.suite = cfg.suite, row.scene = label, row.backend = c.backend, row.kind = vt ? "VT" : "EE";
      row.mode = c.mode ? c.mode->name : "point_query+exact_leaf";
      row.vertices = info.vertices, row.triangles = info.triangles, row.edges = info.edges;
      row.frame = int(k), row.factor = factor, row.r = r, row.t = t;
      row.candidates = got.size(), row.truth = truth.size(), row.fn = missing(truth, got), row.load = load_average();
      if (c.work) row.work = c.work();
      if (c.backend == "cpu" && c.mode && vt && (c.mode->flags & MINKQ_QUERY_LEAF_EXACT)) leaf_vt = got;
      if (!c.mode && (!leaf_vt.empty() || got.empty())) row.diff_vs_leaf = int64_t(missing(leaf_vt, got) + missing(got, leaf_vt));
      // The box candidates (box mode without the leaf test) feed the narrow-phase measurement.
      if (c.backend == "cpu" && c.mode && k + 1 == sc.frames.size() && c.mode->mode == MINKQ_MODE_BOX &&
          !(c.mode->flags & MINKQ_QUERY_LEAF_EXACT)) {
        std::vector<int32_t>& dst = vt ? box_vt : box_ee;
        dst.clear();
        for (uint64_t x : got) {
          const minkq::Pair pair = minkq::unpack_pair(x);
          dst.insert(dst.end(), {pair.first, pair.second});
        }
      }
      rep.false_negatives += row.fn;
      if (row.fn)
        std::fprintf(stderr, "FALSE NEGATIVES: %s frame %zu %s %s %s: %" PRIu64 " true contacts missing\n", label.c_str(), k,
                     c.backend.c_str(), row.kind.c_str(), row.mode.c_str(), row.fn);
      rep.queries.push_back(row);
    }
  }

  if (cfg.narrow) {
    const auto& last = sc.frames.back();
    rep.narrow.push_back({cfg.suite, label, "VT", measure_narrow(sc, last, true, box_vt, r, cfg.warmup, cfg.repeats), box_vt.size() / 2});
    rep.narrow.push_back({cfg.suite, label, "EE", measure_narrow(sc, last, false, box_ee, r, cfg.warmup, cfg.repeats), box_ee.size() / 2});
  }
  info.load_end = load_average();
  rep.scenes.push_back(info);
}

// ---- Tables -------------------------------------------------------------------------------------

struct Sum {  // a (scene, backend, kind, mode) summed over frames
  double ms = 0, ms_min = 0, ms_max = 0;
  uint64_t candidates = 0, truth = 0, fn = 0;
  uint64_t nodes = 0, node_tests = 0, prim_tests = 0, queries = 0;  // work (minkq rows)
  int frames = 0;
  int64_t diff = 0;
  double fp() const { return truth ? (double(candidates) - double(truth)) / double(truth) : NAN; }
};
using SumKey = std::tuple<std::string, std::string, std::string, std::string>;  // scene, backend, kind, mode

std::map<SumKey, Sum> sums(const Report& rep, const std::string& suite) {
  std::map<SumKey, Sum> out;
  for (const QueryRow& q : rep.queries) {
    if (q.suite != suite) continue;
    Sum& s = out[{q.scene, q.backend, q.kind, q.mode}];
    s.ms += q.t.median, s.ms_min += q.t.min, s.ms_max += q.t.max;
    s.candidates += q.candidates, s.truth += q.truth, s.fn += q.fn, ++s.frames;
    s.nodes += q.work.nodes_visited, s.node_tests += q.work.node_tests, s.prim_tests += q.work.primitive_tests;
    s.queries += uint64_t(q.kind == "VT" ? q.vertices : q.edges);
    if (q.diff_vs_leaf > 0) s.diff += q.diff_vs_leaf;
  }
  return out;
}

double narrow_ns(const Report& rep, const std::string& suite, const std::string& scene, const std::string& kind) {
  for (const auto& n : rep.narrow)
    if (n.suite == suite && n.scene == scene && n.kind == kind) return n.ns_per_candidate;
  return NAN;
}

std::string header(const std::string& title, const std::string& machine, const Options& opt, double load_start) {
  std::ostringstream o;
  char when[64];
  const std::time_t now = std::time(nullptr);
  std::strftime(when, sizeof when, "%Y-%m-%d %H:%M UTC", std::gmtime(&now));
  o << "# " << title << "\n\n";
  o << "Machine: " << machine << ". TBB threads: " << (opt.threads > 0 ? std::to_string(opt.threads) : "all") << ". ";
  o << "Load average (1 min) at start " << fmt(load_start, 3) << ", at write " << fmt(load_average(), 3) << ". ";
  o << "Written " << when << " by `minkq_bench`" << (opt.quick ? " --quick" : "") << "; repeats " << opt.repeats
    << " after " << opt.warmup << " warm-up; times are medians in ms with the range of the repeats in brackets.\n\n";
  return o.str();
}

void write_file(const std::string& path, const std::string& text) {
  std::ofstream f(path);
  f << text;
  if (!f) throw std::runtime_error("cannot write " + path);
  std::fprintf(stderr, "wrote %s\n", path.c_str());
}

std::string scene_line(const SceneInfo& s) {
  std::ostringstream o;
  o << s.vertices << " vertices, " << s.triangles << " triangles, " << s.edges << " edges; r = " << fmt(s.r, 4) << " = "
    << fmt(s.factor, 3) << " x mean edge " << fmt(s.mean_edge, 4) << "; oracle " << fmt(s.oracle_ms / 1000, 3)
    << " s; load " << fmt(s.load_start, 3) << " -> " << fmt(s.load_end, 3);
  return o.str();
}

// scenes.md / real.md / scale.md: per scene, per frame, every mode.
std::string detail_tables(const Report& rep, const std::string& suite) {
  std::ostringstream o;
  for (const SceneInfo& s : rep.scenes) {
    if (s.suite != suite) continue;
    o << "## " << s.scene << "\n\n" << s.recipe << ".\n\n" << scene_line(s) << ".\n\n";
    // build / refit
    bool any_step = false;
    for (const StepRow& st : rep.steps)
      if (st.suite == suite && st.scene == s.scene) any_step = true;
    if (any_step) {
      o << "| backend | step | frame | ms |\n|---|---|---|---|\n";
      for (const StepRow& st : rep.steps)
        if (st.suite == suite && st.scene == s.scene)
          o << "| " << st.backend << " | " << st.step << (st.backend == "embree" ? " (VT tree only)" : " (VT + EE trees)") << " | "
            << st.frame << " | " << st.t.text() << " |\n";
      o << "\n";
    }
    o << "| frame | backend | kind | mode | candidates | true contacts | FP ratio | FN | query ms | vs box |\n"
         "|---|---|---|---|---|---|---|---|---|---|\n";
    for (const QueryRow& q : rep.queries) {
      if (q.suite != suite || q.scene != s.scene) continue;
      double box_ms = NAN;
      for (const QueryRow& b : rep.queries)
        if (b.suite == suite && b.scene == q.scene && b.frame == q.frame && b.kind == q.kind && b.mode == "box" &&
            b.backend == (q.backend == "embree" ? "cpu" : q.backend))
          box_ms = b.t.median;
      std::string mode = q.mode;
      if (q.diff_vs_leaf >= 0) mode += q.diff_vs_leaf == 0 ? " (= minkq leaf_exact set)" : " (differs from leaf_exact by " + std::to_string(q.diff_vs_leaf) + ")";
      o << "| " << q.frame << " | " << q.backend << " | " << q.kind << " | " << mode << " | " << q.candidates << " | " << q.truth
        << " | " << fmt(q.fp(), 3) << " | " << q.fn << " | " << q.t.text() << " | " << fmt(box_ms / q.t.median, 3) << "x |\n";
    }
    o << "\n";
  }
  return o.str();
}

double geomean(const std::vector<double>& v) {
  double s = 0;
  int n = 0;
  for (double x : v)
    if (std::isfinite(x) && x > 0) s += std::log(x), ++n;
  return n ? std::exp(s / n) : NAN;
}

// Error against run time: per scene (summed over frames) each mode's candidates, FP ratio,
// query time, the narrow phase at the measured cost per candidate, and the end-to-end sum.
std::string error_vs_time(const Report& rep, const std::string& suite, std::string& csv) {
  std::ostringstream o;
  const auto S = sums(rep, suite);
  o << "End to end = query time + candidates x the narrow phase's measured cost per candidate (the "
       "double-precision distance test of predicates.h run over the box candidates of the last frame, same threads). "
       "leaf_exact already ran that test at the leaves; its contacts still pass through the narrow phase (a simulator "
       "needs their closest points), so they are counted too. Times and counts are sums over the scene's frames.\n\n";
  for (const SceneInfo& s : rep.scenes) {
    if (s.suite != suite) continue;
    for (const std::string& backend : std::vector<std::string>{"cpu", "cuda"}) {
      if (!S.count({s.scene, backend, "VT", "box"})) continue;
      o << "### " << s.scene << " (" << backend << ")\n\n| kind | mode | candidates | FP ratio | FN | query ms | narrow ns/cand | narrow ms | end-to-end ms | vs box end-to-end |\n|---|---|---|---|---|---|---|---|---|---|\n";
      for (const std::string kind : {"VT", "EE"}) {
        const double ns = narrow_ns(rep, suite, s.scene, kind);
        const Sum& box = S.at({s.scene, backend, kind, "box"});
        const double box_e2e = box.ms + double(box.candidates) * ns * 1e-6;
        std::string best;
        double best_e2e = INFINITY;
        for (const ModeSpec& m : kModes) {
          if ((m.kind == MINKQ_QUERY_VT) != (kind == "VT")) continue;
          const Sum& x = S.at({s.scene, backend, kind, m.name});
          const double narrow = double(x.candidates) * ns * 1e-6, e2e = x.ms + narrow;
          if (e2e < best_e2e) best_e2e = e2e, best = m.name;
          o << "| " << kind << " | " << m.name << " | " << x.candidates << " | " << fmt(x.fp(), 3) << " | " << x.fn << " | "
            << fmt(x.ms, 3) << " | " << fmt(ns, 3) << " | " << fmt(narrow, 3) << " | " << fmt(e2e, 3) << " | "
            << fmt(box_e2e / e2e, 3) << "x |\n";
          char line[512];
          std::snprintf(line, sizeof line, "%s,%s,%s,%s,%s,%" PRIu64 ",%" PRIu64 ",%.6g,%.6g,%.6g,%.6g,%.6g\n", suite.c_str(),
                        s.scene.c_str(), backend.c_str(), kind.c_str(), m.name, x.candidates, x.truth, x.fp(), x.ms, ns, narrow, e2e);
          csv += line;
        }
        o << "| " << kind << " | **fastest end to end: " << best << "** | | | | | | | | |\n";
      }
      o << "\n";
    }
  }
  return o.str();
}

std::string summary(const Report& rep, const Options& opt, const std::string& machine) {
  std::ostringstream o;
  o << header("minkq benchmark summary", machine, opt, rep.scenes.empty() ? 0 : rep.scenes.front().load_start);
  o << "Ratios are taken within one run on one machine (times summed over each scene's frames, medians of the "
       "repeats). `VT sphere` = sphere / box query time; `EE ray`, `EE exact` = capsule_ray, capsule_exact / box; "
       "`leaf` = leaf_exact: the box node test and the leaf distance test (its output is the contact set; "
       "ablation's contacts.md: faster than behind the finer node tests); `Embree / minkq` = "
       "Embree point query with the same exact leaf test over minkq's leaf_exact VT query, both producing "
       "the same pair set. > 1 means minkq (or the finer mode) is faster. Drop = fewer candidates than box.\n\n";
  for (const std::string suite : {"scenes", "real", "scale"}) {
    const auto S = sums(rep, suite);
    bool any = false;
    for (const auto& s : rep.scenes) any |= s.suite == suite;
    if (!any) continue;
    o << "## " << (suite == "scenes" ? "Reference scenes (every frame)" : suite == "real" ? "Real meshes (r = 0.25 x mean edge)" : "Large instances") << "\n\n";
    for (const std::string backend : {"cpu", "cuda"}) {
      if (!S.count({rep.scenes.front().scene, backend, "VT", "box"}) && backend == "cuda") continue;
      o << "| scene (" << backend << ") | triangles | r/mean edge | VT true | VT box cand | VT sphere drop | VT sphere speed | VT leaf speed | "
           "EE true | EE box cand | EE ray drop | EE exact drop | EE ray speed | EE exact speed | EE leaf speed | Embree / minkq | FN |\n"
           "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
      std::vector<double> g[8];
      for (const SceneInfo& s : rep.scenes) {
        if (s.suite != suite || !S.count({s.scene, backend, "VT", "box"})) continue;
        auto get = [&](const char* k, const char* m) { return S.at({s.scene, backend, k, m}); };
        const Sum vb = get("VT", "box"), vs = get("VT", "sphere"), vl = get("VT", "leaf_exact");
        const Sum eb = get("EE", "box"), er = get("EE", "capsule_ray"), ex = get("EE", "capsule_exact"), el = get("EE", "leaf_exact");
        double embree = NAN;
        if (backend == "cpu" && S.count({s.scene, "embree", "VT", "point_query+exact_leaf"}))
          embree = S.at({s.scene, "embree", "VT", "point_query+exact_leaf"}).ms / vl.ms;
        uint64_t fn = vb.fn + vs.fn + vl.fn + eb.fn + er.fn + ex.fn + el.fn;
        if (S.count({s.scene, "embree", "VT", "point_query+exact_leaf"})) fn += S.at({s.scene, "embree", "VT", "point_query+exact_leaf"}).fn;
        auto drop = [](const Sum& a, const Sum& b) { return b.candidates ? 100.0 * (1 - double(a.candidates) / double(b.candidates)) : NAN; };
        const double v[8] = {vb.ms / vs.ms, vb.ms / vl.ms, eb.ms / er.ms, eb.ms / ex.ms, eb.ms / el.ms, embree,
                             drop(vs, vb), drop(ex, eb)};
        for (int i = 0; i < 8; ++i) g[i].push_back(v[i]);
        o << "| " << s.scene << " | " << s.triangles << " | " << fmt(s.factor, 3) << " | " << vb.truth << " | " << vb.candidates << " | "
          << fmt(drop(vs, vb), 3) << "% | " << fmt(v[0], 3) << "x | " << fmt(v[1], 3) << "x | " << eb.truth << " | "
          << eb.candidates << " | " << fmt(drop(er, eb), 3) << "% | " << fmt(drop(ex, eb), 3) << "% | " << fmt(v[2], 3) << "x | "
          << fmt(v[3], 3) << "x | " << fmt(v[4], 3) << "x | " << fmt(embree, 3) << "x | " << fn << " |\n";
      }
      o << "| **geomean** | | | | | " << fmt(geomean(g[6]), 3) << "% | " << fmt(geomean(g[0]), 3) << "x | " << fmt(geomean(g[1]), 3)
        << "x | | | | " << fmt(geomean(g[7]), 3) << "% | " << fmt(geomean(g[2]), 3) << "x | " << fmt(geomean(g[3]), 3) << "x | "
        << fmt(geomean(g[4]), 3) << "x | " << fmt(geomean(g[5]), 3) << "x | |\n\n";
    }
  }
  return o.str();
}

// Targets of issue 7 (and of the query-performance issue) beside the measured figures.
std::string targets(const Report& rep, const Options& opt, const std::string& machine) {
  std::ostringstream o;
  o << header("Targets against measured figures", machine, opt, rep.scenes.empty() ? 0 : rep.scenes.front().load_start);
  o << "The targets are for an H100-class GPU (except the Embree and memory ones); the figures here are from this run's "
       "backends. The H100 reference numbers are from ../shared/REFERENCES.md (Warp 1.19 / Newton 1.8 and a plain LBVH "
       "prototype on the same twisted sheet).\n\n";
  o << "| target | measured here | backend | met? |\n|---|---|---|---|\n";
  // 1M twisted sheet: refit + VT + EE.
  for (const std::string backend : {"cpu", "cuda"}) {
    for (const SceneInfo& s : rep.scenes) {
      if (s.scene.rfind("twist_target", 0) != 0 || s.suite != "scale") continue;
      double refit = NAN, vt = INFINITY, ee = INFINITY;
      std::string vt_mode, ee_mode;
      for (const StepRow& st : rep.steps)
        if (st.suite == s.suite && st.scene == s.scene && st.backend == backend && st.step == "refit" && st.frame == 1) refit = st.t.median;
      for (const QueryRow& q : rep.queries) {
        if (q.suite != s.suite || q.scene != s.scene || q.backend != backend || q.frame != 0) continue;
        if (q.mode != "leaf_exact") continue;  // the targets count contacts: the exact output
        if (q.kind == "VT") vt = q.t.median, vt_mode = q.mode; else ee = q.t.median, ee_mode = q.mode;
      }
      if (!std::isfinite(refit) || !std::isfinite(vt)) continue;
      const double total = refit + vt + ee;
      o << "| refit + VT + EE of the " << fmt_count(double(s.triangles)) << "-triangle twisted sheet, r = 0.25x: <= 0.5 ms (H100) | "
        << fmt(refit, 3) << " + " << fmt(vt, 3) << " + " << fmt(ee, 3) << " = " << fmt(total, 4) << " ms (leaf_exact: contacts) | "
        << backend << " | " << (total <= 0.5 ? "yes" : "no") << " |\n";
    }
  }
  // Embree.
  {
    std::vector<double> ratios;
    for (const std::string suite : {"scenes", "real", "scale"}) {
      const auto S = sums(rep, suite);
      for (const auto& [key, sum] : S)
        if (std::get<1>(key) == "embree" && S.count({std::get<0>(key), "cpu", "VT", "leaf_exact"}))
          ratios.push_back(sum.ms / S.at({std::get<0>(key), "cpu", "VT", "leaf_exact"}).ms);
    }
    if (!ratios.empty()) {
      const double lo = *std::min_element(ratios.begin(), ratios.end()), hi = *std::max_element(ratios.begin(), ratios.end());
      o << "| CPU VT throughput >= Embree's point query on the same cores | minkq is " << fmt(geomean(ratios), 3)
        << "x Embree's speed (geomean over " << ratios.size() << " scenes; range " << fmt(lo, 3) << "–" << fmt(hi, 3)
        << "x), same pair sets | cpu | " << (geomean(ratios) >= 1 ? "yes (geomean)" : "no") << " |\n";
    }
  }
  // Memory: the largest scene (per-tree constants vanish there), and the range over scenes of
  // at least 1000 triangles.
  {
    const SceneInfo* largest = nullptr;
    double lo = INFINITY, hi = 0;
    for (const SceneInfo& s : rep.scenes) {
      if (s.triangles < 1000 || s.suite == "sweep") continue;
      const double b = s.layout_bytes / double(s.triangles);
      lo = std::min(lo, b), hi = std::max(hi, b);
      if (!largest || s.triangles > largest->triangles) largest = &s;
    }
    if (largest) {
      const double b = largest->layout_bytes / double(largest->triangles);
      o << "| memory <= 128 B per triangle for a VT+EE scene (trees + scene data) | " << fmt(b, 4) << " B/triangle on "
        << largest->scene << "; " << fmt(lo, 4) << "–" << fmt(hi, 4)
        << " over scenes of >= 1000 triangles (memory.md) | cpu layout | " << (b <= 128 ? "yes" : "no") << " |\n";
    }
  }
  o << "| EE >= 5x faster than Warp's padded-box query, VT >= 3x faster than Warp's sphere query, same device, "
       "identical contacts | see warp.md (Warp's CPU kernels beside minkq's CPU backend) | | GPU not measured here |\n\n";
  return o.str();
}

std::string memory_table(const Report& rep, const Options& opt, const std::string& machine) {
  std::ostringstream o;
  o << header("Memory per triangle (VT + EE scene)", machine, opt, rep.scenes.empty() ? 0 : rep.scenes.front().load_start);
  o << "Layout bytes from the library's structures (CPU backend; the CUDA backend keeps the same arrays in device "
       "memory): vertices 12 B plus a 4 B query-order entry, triangles 12 B, edges 8 B (the store's copy is the only "
       "one) and 8 B more in the edge tree's leaf order (the EE and EV incidence filters read them four at a time); "
       "per tree its node records (64 B and a 4 B refit counter each, one per internal node above leaf ranges of up "
       "to 32 primitives) and per primitive a sorted-order id and its box in leaf order (4 + 24 B). Output buffers "
       "excluded. "
       "RSS delta: resident memory before and after minkq_scene_create (malloc_trim first; includes allocator slack, "
       "excludes pages freed after the build).\n\n";
  o << "| suite | scene | vertices | triangles | edges | layout B/triangle | RSS delta B/triangle | target |\n|---|---|---|---|---|---|---|---|\n";
  for (const SceneInfo& s : rep.scenes) {
    if (s.suite == "sweep") continue;
    const double t = double(s.triangles);
    o << "| " << s.suite << " | " << s.scene << " | " << s.vertices << " | " << s.triangles << " | " << s.edges << " | "
      << fmt(s.layout_bytes / t, 4) << " | "
      << (s.rss_bytes > 0 ? fmt(s.rss_bytes / t, 4) : "–") << " | 128 |\n";
  }
  return o.str();
}

std::string sweep_table(const Report& rep) {
  std::ostringstream o;
  o << "Last frame of each scene (the most contact-rich), every radius; candidates and median query ms (cpu). Cases "
       "whose box mode would return more than 2e7 pairs are skipped (memory and time on this machine)";
  if (rep.skipped.empty()) o << ".\n\n";
  else {
    o << ": ";
    for (size_t i = 0; i < rep.skipped.size(); ++i) o << (i ? ", " : "") << rep.skipped[i];
    o << ".\n\n";
  }
  std::vector<std::string> scenes;
  for (const SceneInfo& s : rep.scenes)
    if (s.suite == "sweep") {
      const std::string base = s.scene.substr(0, s.scene.find('@'));
      if (std::find(scenes.begin(), scenes.end(), base) == scenes.end()) scenes.push_back(base);
    }
  for (const std::string& base : scenes) {
    o << "### " << base << "\n\n| r/mean edge | VT true | VT box | VT sphere | VT leaf | EE true | EE box | EE ray | EE exact | EE leaf | VT sphere speed | EE ray speed | EE exact speed | FN | load |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const SceneInfo& s : rep.scenes) {
      if (s.suite != "sweep" || s.scene.substr(0, s.scene.find('@')) != base) continue;
      std::map<std::string, const QueryRow*> m;
      uint64_t fn = 0;
      for (const QueryRow& q : rep.queries)
        if (q.suite == "sweep" && q.scene == s.scene && q.backend == "cpu") m[q.kind + q.mode] = &q, fn += q.fn;
      auto cell = [&](const std::string& k) {
        const QueryRow* q = m.count(k) ? m[k] : nullptr;
        return q ? fmt_count(double(q->candidates)) + " / " + fmt(q->t.median, 3) : std::string("–");
      };
      auto speed = [&](const std::string& a, const std::string& b) {
        return m.count(a) && m.count(b) ? fmt(m[b]->t.median / m[a]->t.median, 3) + "x" : std::string("–");
      };
      o << "| " << fmt(s.factor, 3) << " | " << fmt_count(double(s.vt_truth.back())) << " | " << cell("VTbox") << " | " << cell("VTsphere")
        << " | " << cell("VTleaf_exact") << " | " << fmt_count(double(s.ee_truth.back())) << " | " << cell("EEbox") << " | "
        << cell("EEcapsule_ray") << " | " << cell("EEcapsule_exact") << " | " << cell("EEleaf_exact") << " | "
        << speed("VTsphere", "VTbox") << " | " << speed("EEcapsule_ray", "EEbox") << " | " << speed("EEcapsule_exact", "EEbox")
        << " | " << fn << " | " << fmt(s.load_start, 3) << " |\n";
    }
    o << "\n";
  }
  return o.str();
}

// Work per query (MINKQ_QUERY_STATS) per scene and mode, summed over frames: what each mode's
// traversal does, the same on every backend for the same tree; the cpu rows are shown.
std::string work_table(const Report& rep, const std::string& suite) {
  const auto all = sums(rep, suite);
  std::ostringstream o;
  o << "| scene | kind | mode | nodes / query | node tests / query | primitive tests / query | candidates / query | "
       "nodes / true contact | nodes vs box | query ms |\n|---|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& [key, x] : all) {
    const auto& [scene, backend, kind, mode] = key;
    if (backend != "cpu" || x.queries == 0) continue;
    const auto box = all.find({scene, backend, kind, "box"});
    const double q = double(x.queries);
    o << "| " << scene << " | " << kind << " | " << mode << " | " << fmt(double(x.nodes) / q, 3) << " | "
      << fmt(double(x.node_tests) / q, 3) << " | " << fmt(double(x.prim_tests) / q, 3) << " | "
      << fmt(double(x.candidates) / q, 3) << " | " << (x.truth ? fmt(double(x.nodes) / double(x.truth), 3) : std::string("–"))
      << " | " << (box != all.end() && box->second.nodes ? fmt(double(x.nodes) / double(box->second.nodes), 3) : std::string("–"))
      << " | " << fmt(x.ms, 3) << " |\n";
  }
  return o.str();
}

std::string rows_csv(const Report& rep) {
  std::ostringstream o;
  o << "suite,scene,backend,kind,mode,vertices,triangles,edges,frame,radius_factor,r,ms_median,ms_min,ms_max,repeats,candidates,true_contacts,fp_ratio,false_negatives,diff_vs_leaf,load1,nodes_visited,node_tests,primitive_tests\n";
  for (const QueryRow& q : rep.queries) {
    char b[640];
    std::snprintf(b, sizeof b, "%s,%s,%s,%s,%s,%" PRId64 ",%" PRId64 ",%" PRId64 ",%d,%.6g,%.9g,%.6g,%.6g,%.6g,%d,%" PRIu64 ",%" PRIu64 ",%.6g,%" PRIu64 ",%" PRId64 ",%.3g,%" PRIu64 ",%" PRIu64 ",%" PRIu64 "\n",
                  q.suite.c_str(), q.scene.c_str(), q.backend.c_str(), q.kind.c_str(), q.mode.c_str(), q.vertices, q.triangles, q.edges,
                  q.frame, q.factor, q.r, q.t.median, q.t.min, q.t.max, q.t.repeats, q.candidates, q.truth, q.fp(), q.fn, q.diff_vs_leaf, q.load,
                  q.work.nodes_visited, q.work.node_tests, q.work.primitive_tests);
    o << b;
  }
  return o.str();
}
std::string steps_csv(const Report& rep) {
  std::ostringstream o;
  o << "suite,scene,backend,step,triangles,frame,ms_median,ms_min,ms_max,load1\n";
  for (const StepRow& s : rep.steps)
    o << s.suite << "," << s.scene << "," << s.backend << "," << s.step << "," << s.triangles << "," << s.frame << "," << s.t.median
      << "," << s.t.min << "," << s.t.max << "," << s.load << "\n";
  return o.str();
}

int run(int argc, char** argv) {
  Options opt;
  bool repeats_given = false, frames_given = false, suites_given = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw std::invalid_argument(a + " needs a value");
      return argv[++i];
    };
    if (a == "--help" || a == "-h") { std::fputs(kUsage, stdout); return 0; }
    else if (a == "--data") opt.data_dir = value();
    else if (a == "--out") opt.out_dir = value();
    else if (a == "--quick") opt.quick = true;
    else if (a == "--frames") opt.frames = std::stoi(value()), frames_given = true;
    else if (a == "--repeats") opt.repeats = std::stoi(value()), repeats_given = true;
    else if (a == "--warmup") opt.warmup = std::stoi(value());
    else if (a == "--threads") opt.threads = std::stoi(value());
    else if (a == "--backends") opt.backends = split(value());
    else if (a == "--scenes") opt.scenes = split(value());
    else if (a == "--suites") { const auto v = split(value()); opt.suites = {v.begin(), v.end()}; suites_given = true; }
    else if (a == "--scale-scenes") opt.scale_scenes = split(value());
    else if (a == "--scale-triangles") { opt.scale_triangles.clear(); for (const auto& s : split(value())) opt.scale_triangles.push_back(std::stod(s)); }
    else if (a == "--no-embree") opt.embree = false;
    else if (a == "--export") opt.export_dir = value();
    else if (a == "--export-only") opt.export_dir = value(), opt.export_only = true;
    else if (a == "--list") opt.list = true;
    else if (a == "--list-at") opt.list = true, opt.list_at = std::stod(value());
    else throw std::invalid_argument("unknown option " + a);
  }
  if (opt.quick) {
    if (!repeats_given) opt.repeats = 1;
    if (!frames_given) opt.frames = 2;
    if (!suites_given) opt.suites = {"scenes"};
    opt.warmup = 0;
  }
  if (opt.frames < 1 || opt.repeats < 1 || opt.warmup < 0) throw std::invalid_argument("--frames, --repeats >= 1; --warmup >= 0");
  std::unique_ptr<tbb::global_control> limit;
  if (opt.threads > 0) limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, size_t(opt.threads));
  if (opt.backends.empty()) {
    opt.backends = {"cpu"};
    if (minkq_cuda_device_count() > 0) opt.backends.push_back("cuda");
  }
  std::vector<std::string> scene_names = opt.scenes.empty() ? procedural_scene_names() : opt.scenes;

  if (opt.list) {
    std::printf("| scene | vertices | triangles | edges | Newton margin | mean edge (frame 0) | r / mean edge | r |\n|---|---|---|---|---|---|---|---|\n");
    std::vector<std::string> all = scene_names;
    all.push_back("twist_target");
    for (const auto& name : all) {
      const SceneFrames sc = make_scene(name, opt.list_at, 2, opt.data_dir);  // frame 0 and the last
      std::printf("| %s | %zu | %zu | %zu | %g | %.4g | %.3g | %.4g |\n", name.c_str(), sc.mesh.vertex_count(), sc.mesh.triangle_count(),
                  sc.mesh.edge_count(), sc.reference_radius, sc.mean_edge, sc.radius_factor, sc.radius_factor * sc.mean_edge);
    }
    for (const auto& m : available_real_meshes(opt.data_dir)) {
      if (opt.list_at > 0) break;
      const SceneFrames sc = load_real_scene(m, opt.data_dir);
      std::printf("| %s | %zu | %zu | %zu | – | %.4g | 0.25 | %.4g |\n", m.name.c_str(), sc.mesh.vertex_count(), sc.mesh.triangle_count(),
                  sc.mesh.edge_count(), sc.mean_edge, 0.25 * sc.mean_edge);
    }
    return 0;
  }

  std::string device_names;
  for (const auto& b : opt.backends) {
    Device d = open_device(b);
    device_names += (device_names.empty() ? "" : ", ") + std::string(minkq_device_name(d.get()));
  }
  const std::string machine = machine_line(device_names) + "; Embree " + EmbreeVT::version();
  std::fprintf(stderr, "machine: %s\n", machine.c_str());
  fs::create_directories(opt.out_dir);
  Report rep;
  const double load_start = load_average();

  if (opt.suites.count("scenes")) {
    std::vector<std::string> names = scene_names;
    if (!opt.quick && opt.scenes.empty()) names.push_back("twist_target");
    for (const auto& name : names) {
      CaseConfig cfg;
      cfg.suite = "scenes", cfg.repeats = opt.repeats, cfg.warmup = opt.warmup;
      run_scene(make_scene(name, 0, opt.frames, opt.data_dir), cfg, opt, rep);
    }
  }
  if (opt.suites.count("real")) {
    for (const auto& m : available_real_meshes(opt.data_dir)) {
      CaseConfig cfg;
      cfg.suite = "real", cfg.repeats = opt.repeats, cfg.warmup = opt.warmup;
      run_scene(load_real_scene(m, opt.data_dir), cfg, opt, rep);
    }
  }
  if (opt.suites.count("sweep")) {
    const std::vector<double> factors = {0.1, 0.25, 0.5, 1, 2, 4, 8};
    for (const auto& name : scene_names) {
      const SceneFrames sc = make_scene(name, 0, 1, opt.data_dir);  // one frame: the last phase (s = 1)
      for (double f : factors) {
        CaseConfig cfg;
        cfg.suite = "sweep", cfg.factor = f, cfg.tag = name + "@" + fmt(f, 3), cfg.embree = false, cfg.narrow = false, cfg.steps = false;
        cfg.max_pairs = 2e7;
        cfg.repeats = std::min(opt.repeats, 3), cfg.warmup = opt.warmup;
        run_scene(sc, cfg, opt, rep);
      }
    }
    for (const std::string real : {"unisex_shirt", "multilayer_drape"})
      for (const auto& m : available_real_meshes(opt.data_dir)) {
        if (m.name != real) continue;
        const SceneFrames sc = load_real_scene(m, opt.data_dir);
        for (double f : {0.1, 0.25, 0.5, 1.0, 2.0}) {
          CaseConfig cfg;
          cfg.suite = "sweep", cfg.factor = f, cfg.tag = m.name + "@" + fmt(f, 3), cfg.embree = false, cfg.narrow = false, cfg.steps = false;
          cfg.max_pairs = 2e7;
          cfg.repeats = std::min(opt.repeats, 3), cfg.warmup = opt.warmup;
          run_scene(sc, cfg, opt, rep);
        }
      }
  }
  if (opt.suites.count("scale")) {
    for (double target : opt.scale_triangles)
      for (const auto& name : opt.scale_scenes) {
        const SceneFrames sc = make_scene(name, target, 2, opt.data_dir);
        CaseConfig cfg;
        cfg.suite = "scale", cfg.tag = name + "@" + fmt_count(double(sc.mesh.triangle_count()));
        cfg.repeats = std::min(opt.repeats, 3), cfg.warmup = opt.warmup;
        run_scene(sc, cfg, opt, rep);
      }
  }

  if (opt.export_only) return 0;
  // ---- write ----
  const std::string& out = opt.out_dir;
  if (opt.suites.count("scenes"))
    write_file(out + "/scenes.md", header("Reference scenes: every frame, backend and mode", machine, opt, load_start) +
                                       detail_tables(rep, "scenes"));
  if (opt.suites.count("real"))
    write_file(out + "/real.md", header("Real meshes (data/meshes.tar.xz and ../shared/data), r = 0.25 x mean edge", machine, opt, load_start) +
                                     detail_tables(rep, "real"));
  if (opt.suites.count("scale"))
    write_file(out + "/scale.md", header("Large instances", machine, opt, load_start) + detail_tables(rep, "scale"));
  if (opt.suites.count("sweep"))
    write_file(out + "/sweep.md", header("Radius sweep: 0.1x to 8x mean edge", machine, opt, load_start) + sweep_table(rep));
  std::string evt_csv = "suite,scene,backend,kind,mode,candidates,true_contacts,fp_ratio,query_ms,narrow_ns_per_candidate,narrow_ms,end_to_end_ms\n";
  std::string evt;
  for (const std::string suite : {"scenes", "real", "scale"}) {
    bool any = false;
    for (const auto& s : rep.scenes) any |= s.suite == suite;
    if (any) evt += "## " + suite + "\n\n" + error_vs_time(rep, suite, evt_csv);
  }
  std::string work;
  for (const std::string suite : {"scenes", "real", "sweep", "scale"}) {
    const std::string table = work_table(rep, suite);
    if (table.find("\n|", table.find("|---")) != std::string::npos) work += "## " + suite + "\n\n" + table + "\n";
  }
  if (!work.empty())
    write_file(out + "/work.md",
               header("Traversal work per query (MINKQ_QUERY_STATS)", machine, opt, load_start) +
                   "Counts from one untimed run of each query with MINKQ_QUERY_STATS, summed over frames; they depend "
                   "only on the tree and the queries, so they are the same on every backend. Nodes are internal node "
                   "records read; node tests are child boxes tested against the query shape; primitive tests are "
                   "leaves reached (handed to the leaf filter). EE queries meet each pair once (a query reaches only "
                   "the leaves after its own in the tree's order). Query ms: the median of the timed runs, summed "
                   "over frames.\n\n" + work);
  if (!evt.empty()) {
    write_file(out + "/error_vs_time.md", header("Error against run time, and end to end with the narrow phase", machine, opt, load_start) +
                                              "Plots: error_vs_time_<scene>.png (bench/plot.py).\n\n" + evt);
    write_file(out + "/error_vs_time.csv", evt_csv);
  }
  write_file(out + "/summary.md", summary(rep, opt, machine));
  write_file(out + "/targets.md", targets(rep, opt, machine));
  write_file(out + "/memory.md", memory_table(rep, opt, machine));
  write_file(out + "/rows.csv", rows_csv(rep));
  write_file(out + "/steps.csv", steps_csv(rep));
  if (rep.false_negatives) {
    std::fprintf(stderr, "FAIL: %" PRIu64 " false negatives in total\n", rep.false_negatives);
    return 1;
  }
  std::fprintf(stderr, "no false negatives\n");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "minkq_bench: %s\n(run 'minkq_bench --help')\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "minkq_bench: %s\n", e.what());
    return 3;
  }
}
