// minkq_bench: the product benchmark (issue 7). For each scene, frame, backend and mode it
// measures BVH build, refit, VT and EE query time (warm-up, repeats, median and range),
// candidates, true contacts (the double-precision reference oracle), false-positive ratio and
// false negatives (any non-zero count fails the run), the speedup against box mode and against
// Embree's point query on the CPU, and a measured narrow-phase cost per candidate for the
// end-to-end estimate; the C API suites of bench/suites/ (count-only queries, the float64 input
// path, swept queries) each set one path against its baseline. Writes Markdown tables and CSV
// files naming the machine; see bench/README.md and `minkq_bench --help`.
// The command line, the suites and the writing of every file are here; the options and the
// measured records are in minkq_bench.h, one scene's measurement in minkq_bench_measure.cpp, the
// tables in minkq_bench_tables.cpp.
#include <tbb/global_control.h>

#include <cinttypes>
#include <filesystem>
#include <memory>
#include <stdexcept>

#include "peers/embree.h"
#include "minkq_bench.h"
#include "scenes.h"
#include "suites/suites.h"

namespace fs = std::filesystem;
using namespace minkq::bench;
using namespace minkq_bench;

namespace {

const char* const kUsage = R"(usage: minkq_bench [options]

Runs the benchmark suites and writes Markdown tables and CSV files to --out.

suites (--suites, comma separated; default all of them):
  scenes  the eight Newton scenes at reference size plus REFERENCES.md's twisted sheet
          (256^2), every frame: build, refit, VT/EE in every mode, Embree VT and rtcCollide (box
          mode, the whole step; collide.md), narrow phase
  real    the real meshes (data/meshes.tar.xz, the larger ones from --data) at r = 0.25 x mean edge
  sweep   radius sweep 0.1x-8x mean edge on the last frame of each scene (real meshes to 2x)
  scale   large instances (--scale-triangles) of --scale-scenes
  count   MINKQ_QUERY_COUNT against the same queries storing their pairs, every procedural
          scene and the 130k twisted sheet (--large: also the 1M sheet), each backend;
          count.md (count_cuda.md on CUDA); counts checked equal
  float64 MINKQ_SCENE_FLOAT64 scenes against float32 ones of the same floats (procedural
          scenes, the 130k sheet, also at +1e3 / +1e4, the real meshes), CPU; float64.md;
          pairs checked against float32's and the double oracle
  swept   swept steps (minkq_scene_refit_swept) by VT mode against box mode and the static
          queries, CPU; swept.md; modes' nesting and a sampled-time oracle checked
  geometries  scenes of many geometries, CPU: a cloth on Newton's bunny (1x, 4x, 16x) against the
          concatenated mesh and Embree's rtcCollide, and batched worlds (16, 256, 1024) against one
          scene per world; geometries.md; the ways' pairs checked equal
  scenes, real, sweep and scale write scenes.md, real.md, sweep.md, scale.md and, over all
  of them, summary.md, targets.md, memory.md, work.md, error_vs_time.md/.csv, rows.csv,
  steps.csv, collide.md

options:
  --data DIR              the benchmark-only meshes (default: ../shared/data beside the source tree;
                          a mesh in neither it nor data/meshes.tar.xz is skipped, by name)
  --out DIR               result folder (default: bench/results in the source tree)
  --quick                 smoke run (seconds): reference scenes, 2 frames, 1 repeat, no
                          warm-up, suites scenes only unless --suites is given, small
                          scenes for count, float64 and swept; written to --out (give one!)
  --frames N              frames per scene in the scenes suite (default 4)
  --repeats N             timed repeats per measurement (default 5; sweep/scale use fewer;
                          count 15, float64 and swept 7)
  --large                 count suite: add the 1M-triangle twisted sheet
  --warmup N              untimed runs before them (default 1)
  --threads N             limit TBB (minkq CPU backend, oracle, Embree loop) to N threads
  --backends LIST         cpu,cuda (default: cpu, and cuda where a GPU is usable)
  --scenes LIST           only these procedural scenes (scenes, sweep suites)
  --scale-scenes LIST     scenes of the scale suite (default twist_target; any scene name)
  --scale-triangles LIST  target sizes (default 1e6,2e6)
  --no-embree             skip the Embree baselines (point query, rtcCollide)
  --export DIR            also write every scene's frames as binary files for warp_baseline.py
  --export-only DIR       write them and measure nothing (the oracle is not run either)
  --list                  print the scenes (vertices, triangles, edges, radius) and exit
  --list-at T             the same for the procedural scenes scaled to about T triangles

exit status: 0 success, 1 false negatives found (or a suite's check failed), 2 bad
arguments, 3 failure
)";

// The C API suites (bench/suites/), each writing its own file; false when a check failed.
bool run_api_suites(const Options& opt) {
  bool ok = true;
  const std::string by = std::string("`minkq_bench") + (opt.quick ? " --quick" : "") + (opt.large ? " --large" : "");
  auto run_of = [&](minkq_device* device, int repeats, const std::string& suite) {
    return suites::SuiteRun{device, opt.data_dir, opt.quick ? 1 : (opt.suite_repeats > 0 ? opt.suite_repeats : repeats),
                            opt.quick, machine_line(minkq_device_name(device)), by + " --suites " + suite + "`"};
  };
  if (opt.suites.count("count"))
    for (const auto& backend : opt.backends) {
      Device device = open_device(backend.c_str());
      const std::string name = backend == "cpu" ? "count.md" : "count_" + backend.substr(0, backend.find(':')) + ".md";
      write_file(opt.out_dir + "/" + name, suites::count_report(run_of(device.get(), 15, "count"), opt.large, ok));
    }
  Device cpu = open_device("cpu");
  if (opt.suites.count("float64"))
    write_file(opt.out_dir + "/float64.md", suites::float64_report(run_of(cpu.get(), 7, "float64"), ok));
  if (opt.suites.count("swept"))
    write_file(opt.out_dir + "/swept.md", suites::swept_report(run_of(cpu.get(), 7, "swept"), ok));
  if (opt.suites.count("geometries"))
    write_file(opt.out_dir + "/geometries.md", suites::geometries_report(run_of(cpu.get(), 7, "geometries"), ok));
  if (!ok) std::fprintf(stderr, "FAIL: a check of the count, float64, swept or geometries suite failed (see above)\n");
  return ok;
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
    else if (a == "--repeats") opt.repeats = opt.suite_repeats = std::stoi(value()), repeats_given = true;
    else if (a == "--large") opt.large = true;
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
  const bool suites_ok = run_api_suites(opt);
  if (rep.scenes.empty()) return suites_ok ? 0 : 1;
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
  const std::string collide = collide_table(rep, opt, machine);
  if (!collide.empty()) write_file(out + "/collide.md", collide);
  if (rep.false_negatives || rep.failed_checks) {
    std::fprintf(stderr, "FAIL: %" PRIu64 " false negatives, %" PRIu64 " failed checks in total\n", rep.false_negatives, rep.failed_checks);
    return 1;
  }
  std::fprintf(stderr, "no false negatives\n");
  return suites_ok ? 0 : 1;
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
