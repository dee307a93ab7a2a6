// minkq_bench's shared declarations. The program is split by concern: this header holds the
// options, the measured records of a run (the modes measured, QueryRow, StepRow, NarrowRow,
// SceneInfo, Report) and one case of a suite (CaseConfig), and declares what each part provides:
// the measurement of one scene in minkq_bench_measure.cpp, the tables and CSV files in
// minkq_bench_tables.cpp; minkq_bench.cpp has the command line, the suites and main.
#pragma once

#include <cmath>
#include <cstdint>
#include <set>
#include <string>
#include <vector>

#include "common.h"
#include "scenes.h"

namespace minkq_bench {

using namespace minkq::bench;  // Timing, SceneFrames, fmt(), ...

// The command line (minkq_bench.cpp; the default folders come from bench/CMakeLists.txt).
struct Options {
  std::string data_dir = MINKQ_BENCH_DATA_DIR;
  std::string out_dir = MINKQ_BENCH_RESULTS_DIR;
  bool quick = false, embree = true, list = false;
  double list_at = 0;  // --list-at: list the scenes at this many triangles
  bool export_only = false;
  int frames = 4, repeats = 5, warmup = 1, threads = 0;
  std::set<std::string> suites = {"scenes", "real", "sweep", "scale", "count", "float64", "swept", "geometries"};
  int suite_repeats = 0;  // --repeats as given, else 0: the count, float64 and swept suites' own default
  bool large = false;     // --large: the count suite adds the 1M-triangle twisted sheet
  std::vector<std::string> backends;
  std::vector<std::string> scenes;
  std::vector<std::string> scale_scenes = {"twist_target"};
  std::vector<double> scale_triangles = {1e6, 2e6};
  std::string export_dir;
};

// ---- The measured records ----------------------------------------------------------------------

struct ModeSpec {
  minkq_query_kind kind;
  const char* name;
  minkq_mode mode;
  uint32_t flags;
};
// VT capsule_ray / capsule_exact are box / sphere for points (minkq.h), so they are not repeated.
// leaf_exact (the contacts) runs behind the box node test: 1.03-1.21x (VT) and 2.12-2.82x (EE)
// faster than behind sphere / capsule_exact (docs/design-notes.md).
inline const ModeSpec kModes[] = {
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
  uint64_t failed_checks = 0;  // pair sets that must be equal and are not (rtcCollide's against minkq's)
};

// One case of a suite: a scene, at its own radius or another, and what to measure of it.
struct CaseConfig {
  std::string suite;
  double factor = -1;  // < 0: the scene's own radius factor
  std::string tag;     // scene label in the tables (default: scene name)
  bool embree = true, narrow = true, steps = true;
  int repeats = 5, warmup = 1;
  double max_pairs = 0;  // > 0: skip the case when box mode would return more pairs than this
};

// minkq_bench_measure.cpp: measures one scene (the oracle, build and refit on every backend,
// every mode's queries, Embree, the narrow phase) into rep; writes its frames under
// opt.export_dir when that is set, and with opt.export_only measures nothing.
void run_scene(const SceneFrames& sc, const CaseConfig& cfg, const Options& opt, Report& rep);

// minkq_bench_tables.cpp: the Markdown tables and CSV files, as text (write_file writes one).
std::string header(const std::string& title, const std::string& machine, const Options& opt, double load_start);
void write_file(const std::string& path, const std::string& text);
std::string detail_tables(const Report& rep, const std::string& suite);
std::string error_vs_time(const Report& rep, const std::string& suite, std::string& csv);
std::string summary(const Report& rep, const Options& opt, const std::string& machine);
std::string targets(const Report& rep, const Options& opt, const std::string& machine);
std::string memory_table(const Report& rep, const Options& opt, const std::string& machine);
std::string sweep_table(const Report& rep);
std::string work_table(const Report& rep, const std::string& suite);
std::string collide_table(const Report& rep, const Options& opt, const std::string& machine);
std::string rows_csv(const Report& rep);
std::string steps_csv(const Report& rep);

}  // namespace minkq_bench
