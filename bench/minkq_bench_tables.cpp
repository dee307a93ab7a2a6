// minkq_bench's tables, written from a run's Report as text: the per-scene detail tables
// (scenes.md, real.md, scale.md), error against time, the summary, the targets, memory, the
// radius sweep, the traversal work, and the CSV files (rows.csv, steps.csv); header() is the
// title and machine block atop every Markdown file (see minkq_bench.h for the other parts).
#include <algorithm>
#include <cinttypes>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <map>
#include <sstream>
#include <tuple>

#include "minkq_bench.h"

namespace minkq_bench {

namespace {

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

std::string scene_line(const SceneInfo& s) {
  std::ostringstream o;
  o << s.vertices << " vertices, " << s.triangles << " triangles, " << s.edges << " edges; r = " << fmt(s.r, 4) << " = "
    << fmt(s.factor, 3) << " x mean edge " << fmt(s.mean_edge, 4) << "; oracle " << fmt(s.oracle_ms / 1000, 3)
    << " s; load " << fmt(s.load_start, 3) << " -> " << fmt(s.load_end, 3);
  return o.str();
}

}  // namespace

std::string header(const std::string& title, const std::string& machine, const Options& opt, double load_start) {
  std::ostringstream o;
  o << "# " << title << "\n\n";
  o << "Machine: " << machine << ". TBB threads: " << (opt.threads > 0 ? std::to_string(opt.threads) : "all") << ". ";
  o << "Load average (1 min) at start " << fmt(load_start, 3) << ", at write " << fmt(load_average(), 3) << ". ";
  o << "Written " << utc_now() << " by `minkq_bench`" << (opt.quick ? " --quick" : "") << "; repeats " << opt.repeats
    << " after " << opt.warmup << " warm-up; times are medians in ms with the range of the repeats in brackets.\n\n";
  return o.str();
}

void write_file(const std::string& path, const std::string& text) {
  std::ofstream f(path);
  f << text;
  if (!f) throw std::runtime_error("cannot write " + path);
  std::fprintf(stderr, "wrote %s\n", path.c_str());
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
          o << "| " << st.backend << " | " << st.step << (st.backend == "embree" ? " (VT tree only)" : st.step == "step" ? " (refit + VT + EE box, pairs stored)" : " (VT + EE trees)") << " | "
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
            b.backend == (q.backend.rfind("embree", 0) == 0 ? "cpu" : q.backend))
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

// collide.md: Embree's rtcCollide against minkq's cpu box mode, same pair sets (checked), per scene
// summed over frames: VT, EE, refit (frames after the first) and the whole step; empty when no
// suite ran it.
std::string collide_table(const Report& rep, const Options& opt, const std::string& machine) {
  std::ostringstream o;
  for (const std::string suite : {"scenes", "real", "scale"}) {
    const auto S = sums(rep, suite);
    std::vector<double> g[4];
    std::ostringstream t;
    for (const SceneInfo& s : rep.scenes) {
      if (s.suite != suite || !S.count({s.scene, "embree_collide", "VT", "box"})) continue;
      double step[2][2] = {{0, 0}, {0, 0}};  // [embree_collide, cpu][refit, step]
      for (const StepRow& st : rep.steps)
        if (st.suite == suite && st.scene == s.scene && (st.step == "refit" || st.step == "step") &&
            (st.backend == "cpu" || st.backend == "embree_collide"))
          step[st.backend == "cpu"][st.step == "step"] += st.t.median;
      const Sum &ev = S.at({s.scene, "embree_collide", "VT", "box"}), &ee = S.at({s.scene, "embree_collide", "EE", "box"});
      const Sum &mv = S.at({s.scene, "cpu", "VT", "box"}), &me = S.at({s.scene, "cpu", "EE", "box"});
      const double v[4] = {ev.ms / mv.ms, ee.ms / me.ms, step[0][0] / step[1][0], step[0][1] / step[1][1]};
      t << "| " << s.scene << " | " << s.triangles << " | " << mv.candidates << " | " << me.candidates << " | " << fmt(mv.ms, 3)
        << " | " << fmt(me.ms, 3) << " | " << fmt(step[1][1], 3);
      for (int i = 0; i < 4; ++i) t << " | " << fmt(v[i], 3) << (std::isfinite(v[i]) ? "x" : ""), g[i].push_back(v[i]);
      t << " |\n";
    }
    if (g[0].empty()) continue;
    o << "## " << suite << "\n\n| scene | triangles | VT pairs | EE pairs | minkq VT ms | minkq EE ms | minkq step ms | "
         "VT | EE | refit | step |\n|---|---|---|---|---|---|---|---|---|---|---|\n" << t.str() << "| **geomean** | | | | | |";
    for (int i = 0; i < 4; ++i) o << " | " << fmt(geomean(g[i]), 3) << (std::isfinite(geomean(g[i])) ? "x" : "");
    o << " |\n\n";
  }
  if (o.str().empty()) return "";
  return header("Embree rtcCollide against minkq's box mode", machine, opt, rep.scenes.front().load_start) +
         "Ratios are Embree time / minkq time within the run (> 1: minkq faster), times summed over each scene's "
         "frames (medians of the repeats, round-robin). Both sides return the same box-mode pair sets, checked equal "
         "every frame: VT = rtcCollide of the vertices' boxes grown by r with the triangles' boxes, EE = the edges' "
         "boxes grown by r/2 collided with themselves (each pair once, (lower, higher)), incident pairs dropped and "
         "minkq's box test applied in the callback. minkq is the cpu backend in box mode. Refit: frames after the "
         "first (minkq_scene_refit against recomputing the three element scenes' boxes and refitting them: REFIT "
         "geometries in LOW-quality dynamic scenes, where Embree 3.13 refits rather than rebuilds); step: refit + VT + "
         "EE with the pairs stored, in one call each round. Pair counts and minkq ms: sums over frames.\n\n" + o.str();
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

}  // namespace minkq_bench
