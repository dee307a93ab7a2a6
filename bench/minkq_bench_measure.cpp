// minkq_bench's measurement of one scene (run_scene): the reference oracle once per frame, build
// and refit on every backend and Embree's, every mode's VT and EE queries timed round by round
// beside Embree's (point query; rtcCollide, box mode, and the whole step) and checked against the
// oracle, and the narrow phase's cost per candidate; with the helpers only it uses: the memory
// layout arithmetic (layout_bytes), the narrow-phase measurement and the frame export for
// warp_baseline.py (see minkq_bench.h for the other parts).
#include <malloc.h>
#include <tbb/parallel_reduce.h>
#include <tbb/blocked_range.h>

#include <cinttypes>
#include <filesystem>
#include <functional>
#include <fstream>

#include "cpu/tree.h"
#include "minkq/leaf_groups.h"
#include "peers/embree.h"
#include "minkq/predicates.h"
#include "minkq_bench.h"

namespace fs = std::filesystem;
namespace ref = minkq::reference;

namespace minkq_bench {

namespace {

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

}  // namespace

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
    std::string kind = "";  // mode-less contestants: "VT" (the default), "EE", or "step" (a StepRow)
    std::string mode_name = "point_query+exact_leaf";
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
  // Embree's rtcCollide (peers/embree.h) for minkq's box-mode sets: the vertices grown by r against
  // the triangles (VT), the edges against themselves (EE), incident pairs dropped in the callback;
  // built at frame 0, refit after. The whole step (refit + VT + EE, pairs stored) of it and of
  // minkq's cpu box mode are contestants too.
  struct Collide {
    EmbreeBoxes vertices{true}, triangles{true}, edges{true};
  };
  std::unique_ptr<Collide> ec;
  std::vector<uint64_t> ec_vt, ec_ee;
  const size_t cpu = size_t(std::find(opt.backends.begin(), opt.backends.end(), "cpu") - opt.backends.begin());
  const bool with_collide = with_embree && cpu < opt.backends.size();
  auto collide_set = [&](Collide& c, const std::vector<float>& xyz) {
    c.vertices.set(xyz, {}, 1, r, EmbreeBoxes::Side::query);
    c.triangles.set(xyz, sc.mesh.tris, 3, r, EmbreeBoxes::Side::tree);
    c.edges.set(xyz, sc.mesh.edges, 2, r, EmbreeBoxes::Side::self);
  };
  auto collide_vt = [&] { embree_collide(ec->vertices, ec->triangles, ec_vt, true, false); };
  auto collide_ee = [&] { embree_collide(ec->edges, ec->edges, ec_ee, true, false); };
  if (with_collide) {
    const Timing tb = measure(cfg.warmup, cfg.repeats, [&] { ec = std::make_unique<Collide>(), collide_set(*ec, sc.frames[0]); },
                              [&] { ec.reset(); });
    if (cfg.steps) rep.steps.push_back({cfg.suite, label, "embree_collide", "build", info.triangles, 0, tb, load_average()});
  }
  Result step_vt = new_result(), step_ee = new_result();

  for (size_t k = 0; k < sc.frames.size(); ++k) {
    if (k > 0) {
      const minkq_buffer vb{sc.frames[k].data(), 12, sc.frames[k].size() / 3, MINKQ_MEMORY_HOST};
      for (size_t b = 0; b < opt.backends.size(); ++b) {
        minkq_scene* scene = scenes[b].get();
        const Timing tr = measure(cfg.warmup, cfg.repeats, [&] { check(minkq_scene_refit(scene, vb), "minkq_scene_refit"); });
        if (cfg.steps) rep.steps.push_back({cfg.suite, label, opt.backends[b], "refit", info.triangles, int(k), tr, load_average()});
      }
      if (with_embree) {
        const Timing tr = measure(cfg.warmup, cfg.repeats, [&] { em->rebuild(sc.frames[k]); });
        if (cfg.steps) rep.steps.push_back({cfg.suite, label, "embree", "rebuild", info.triangles, int(k), tr, load_average()});
      }
      if (with_collide) {
        const Timing tr = measure(cfg.warmup, cfg.repeats, [&] { collide_set(*ec, sc.frames[k]); });
        if (cfg.steps) rep.steps.push_back({cfg.suite, label, "embree_collide", "refit", info.triangles, int(k), tr, load_average()});
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
    auto sorted = [](PairSet p) { return std::sort(p.begin(), p.end()), p; };
    if (with_collide) {
      const std::vector<float>& xyz = sc.frames[k];
      minkq_scene* scene = scenes[cpu].get();
      cs.push_back({"embree_collide", nullptr, collide_vt, [&] { return sorted(ec_vt); }, {}, {}, "VT", "box"});
      cs.push_back({"embree_collide", nullptr, collide_ee, [&] { return sorted(ec_ee); }, {}, {}, "EE", "box"});
      cs.push_back({"cpu", nullptr, [&, scene] {
                      check(minkq_scene_refit(scene, {xyz.data(), 12, xyz.size() / 3, MINKQ_MEMORY_HOST}), "minkq_scene_refit");
                      for (auto [kind, res] : {std::pair{MINKQ_QUERY_VT, step_vt.get()}, std::pair{MINKQ_QUERY_EE, step_ee.get()}}) {
                        const minkq_query_desc q{kind, MINKQ_MODE_BOX, 0, r};
                        check(minkq_scene_query_result(scene, &q, res), "minkq_scene_query_result");
                      }
                    }, {}, {}, {}, "step"});
      cs.push_back({"embree_collide", nullptr, [&] { collide_set(*ec, xyz), collide_vt(), collide_ee(); }, {}, {}, {}, "step"});
    }
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
    PairSet leaf_vt;        // minkq's cpu leaf_exact VT set, for the Embree comparison
    PairSet cpu_box[2];     // minkq's cpu box-mode VT and EE sets, for rtcCollide's
    for (auto& c : cs) {
      std::sort(c.times.begin(), c.times.end());
      Timing t;
      t.repeats = int(c.times.size());
      t.min = c.times.front(), t.max = c.times.back();
      t.median = t.repeats % 2 ? c.times[size_t(t.repeats) / 2] : 0.5 * (c.times[size_t(t.repeats) / 2 - 1] + c.times[size_t(t.repeats) / 2]);
      if (c.kind == "step") {
        if (cfg.steps) rep.steps.push_back({cfg.suite, label, c.backend, "step", info.triangles, int(k), t, load_average()});
        continue;
      }
      const PairSet got = c.pairs();
      const bool vt = c.mode ? c.mode->kind == MINKQ_QUERY_VT : c.kind != "EE";
      const PairSet& truth = vt ? vt_truth[k] : ee_truth[k];
      QueryRow row;
      row.suite = cfg.suite, row.scene = label, row.backend = c.backend, row.kind = vt ? "VT" : "EE";
      row.mode = c.mode ? c.mode->name : c.mode_name;
      row.vertices = info.vertices, row.triangles = info.triangles, row.edges = info.edges;
      row.frame = int(k), row.factor = factor, row.r = r, row.t = t;
      row.candidates = got.size(), row.truth = truth.size(), row.fn = missing(truth, got), row.load = load_average();
      if (c.work) row.work = c.work();
      if (c.backend == "cpu" && c.mode && vt && (c.mode->flags & MINKQ_QUERY_LEAF_EXACT)) leaf_vt = got;
      if (c.backend == "cpu" && c.mode && c.mode->mode == MINKQ_MODE_BOX && !c.mode->flags) cpu_box[vt ? 0 : 1] = got;
      if (c.backend == "embree_collide" && got != cpu_box[vt ? 0 : 1]) {
        std::fprintf(stderr, "FAIL: %s frame %zu rtcCollide %s: %zu pairs, minkq's cpu box mode %zu (%" PRIu64 " missing)\n",
                     label.c_str(), k, row.kind.c_str(), got.size(), cpu_box[vt ? 0 : 1].size(), missing(cpu_box[vt ? 0 : 1], got));
        ++rep.failed_checks;
      }
      if (c.backend == "embree" && (!leaf_vt.empty() || got.empty())) row.diff_vs_leaf = int64_t(missing(leaf_vt, got) + missing(got, leaf_vt));
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

}  // namespace minkq_bench
