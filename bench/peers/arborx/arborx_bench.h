// arborx_bench's shared declarations: the options, a scene, a timed contestant, the checks and
// the results of one scene, and the functions each part of the program provides (scenes in
// arborx_scenes.cpp, the checks and timed contestants of one scene in arborx_run.cpp, the result
// file in arborx_report.cpp, main in arborx_bench.cpp; the ArborX side in arborx_peer.h/.cpp).
#pragma once

#include <Kokkos_Core.hpp>

#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "common.h"
#include "scenes.h"

namespace peer {

namespace mb = minkq::bench;
namespace ref = minkq::reference;

using Exec = Kokkos::OpenMP;
using mb::PairSet;
using mb::split;
using mb::Timing;

struct Options {
  int threads = 2, repeats = 11, warmup = 2;
  std::vector<std::string> suites = {"reference", "scenes", "real"};
  std::string data_dir = MINKQ_BENCH_DATA_DIR;
  std::string elephant;  // default: ARBORX_BENCH_CGAL_DIR/elephant-with-holes.off
  std::vector<std::pair<std::string, double>> meshes;  // --mesh PATH[:FACTOR]
  std::string out = std::string(MINKQ_BENCH_RESULTS_DIR) + "/arborx.md";
  std::string only;  // comma-separated scene names
  int gap_ms = 5;
  std::string wait_policy = "passive";  // OMP_WAIT_POLICY: passive, active, or default (unset)
};

struct Scene {
  std::string suite, name, what;
  ref::Mesh mesh;           // topology and edges (derive_edges: the C API's numbering)
  std::vector<float> xyz;   // the positions measured
  double factor = 0;        // r / mean edge
  float r = 0;
};

// One timed contestant: before() untimed, run() timed, returning the count it produced.
struct Contestant {
  Contestant(std::string row_, std::string lib_, std::string variant_, std::function<void()> before_,
             std::function<uint64_t()> run_, uint64_t expect_)
      : row(std::move(row_)), lib(std::move(lib_)), variant(std::move(variant_)), before(std::move(before_)),
        run(std::move(run_)), expect(expect_) {}
  std::string row, lib, variant;
  std::function<void()> before;
  std::function<uint64_t()> run;
  uint64_t expect = 0;
  std::vector<double> ms;
  Timing t;
};

struct Check {
  std::string kind, verdict;
  bool ok = true;
};

struct SceneResult {
  Scene scene;
  uint64_t vt_box = 0, vt_sphere = 0, ee = 0;
  std::vector<Check> checks;
  std::vector<Contestant> contestants;
  double load_start = 0, load_end = 0;
};

// arborx_scenes.cpp: the scenes, in table order; each missing mesh is named on stderr and skipped.
std::vector<std::function<Scene()>> scene_list(const Options& opt);

// arborx_run.cpp: checks one scene's pair sets, then times its contestants.
SceneResult run_scene(Scene sc, const Options& opt, const Exec& space, minkq_device* device);

// arborx_report.cpp
std::string ms_text(const Timing& t);
void write_report(const std::vector<SceneResult>& results, const Options& opt, const std::string& machine,
                  double load_start, const std::string& started);

}  // namespace peer
