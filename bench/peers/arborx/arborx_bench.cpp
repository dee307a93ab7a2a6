// arborx_bench: minkq beside ArborX v2.1 (Kokkos 4.6.01, OpenMP backend) on the same threads,
// scenes and radii (issue 27, item 4; REFERENCES.md "ArborX v2.1"). Built by
// bench/peers/arborx/build.sh, not part of the library's build or tests.
//
// Per scene, in one process and one run:
//   1. both libraries build their trees, and every ArborX pair set is checked against minkq's,
//      pair for pair, before anything is timed (exit 2 naming the scene and kind if one differs);
//   2. the timed contestants run round-robin (every contestant once per round, `--repeats`
//      rounds after `--warmup` untimed ones), so a change of machine load hits all alike; the
//      tables give medians and ranges; every timed run's count is checked against the set.
//
// What is compared (minkq's definitions in capi/minkq.h; ArborX's in REFERENCES.md):
//   build triangle / edge tree   minkq: CpuTree::build over TriangleBoxes / EdgeBoxes, as
//                                minkq_bench's layout count builds single
//                                trees (minkq_scene_create builds both plus copies); ArborX: the
//                                element boxes computed into a View, then the BVH over them.
//   rebuild ..., scratch kept    minkq: the same build into one tree that keeps its scratch
//                                (CpuTree::reserve_build, a scene reserved with
//                                MINKQ_RESERVE_REBUILD; revisions without it skip the rows);
//                                ArborX: a fresh build again (it has no rebuild in place).
//   VT box (count)               minkq: minkq_scene_query, box mode, with MINKQ_QUERY_COUNT where
//                                the measured library has it, else into capacity 0 (the exact
//                                count, nothing written); ArborX: intersects(Box(v +- r)) against
//                                the triangle boxes, a callback dropping v's own triangles and
//                                counting per query.
//   VT sphere (count)            minkq: sphere mode, counted alike; ArborX: intersects(Sphere(v, r)).
//   EE box, each pair once       minkq: box mode, counted alike; ArborX: its internal
//                                ArborX::Details::HalfTraversal as DBSCAN uses it (each leaf
//                                meets only the leaves after it), and its public query over every
//                                edge (each pair met twice, f <= e dropped in the callback).
//   EE pairs stored              minkq: box mode into a host buffer that holds them; ArborX: the
//                                public CSR query (offsets + values) with the largest per-query
//                                count as its buffer hint (one traversal), without a hint (two),
//                                and the half traversal run twice (count, then fill).
// Box queries: minkq keeps a pair when, per axis, the float gap between the two boxes is <= r
// (box_gap_within). ArborX's closed-box overlap test gets the query box [lo', hi'] with hi' the
// largest float x with fl(x - hi) <= r and lo' the smallest with fl(lo - x) <= r, so that it
// accepts a box exactly when minkq's test does. The plain rounding fl(hi + r), fl(lo - r) is
// also run in the check and its difference reported. Sphere: minkq accepts float d^2 <= r^2
// rounded up (1 + 2^-18, conservative), ArborX float sqrt(d^2) <= r; pairs that differ are
// reported and must lie at the boundary (|d / r - 1| <= 2^-16 in double), else the check fails.
//
// The program is split by concern: arborx_bench.h (shared declarations), arborx_peer.h/.cpp (the
// ArborX side), arborx_scenes.cpp (scenes), arborx_run.cpp (checks and timed contestants of one
// scene), arborx_report.cpp (the result file); this file holds the options and main.
#include <Kokkos_Core.hpp>
#include <omp.h>
#include <tbb/global_control.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

#include "arborx_bench.h"

namespace {

using namespace peer;

const char* kUsage = R"(arborx_bench: minkq beside ArborX v2.1 (Kokkos 4.6.01, OpenMP) on the same threads, scenes, radii
  --threads N        OpenMP threads for ArborX and TBB threads for minkq (default 2)
  --repeats N        timed rounds (default 11); --warmup N untimed rounds first (default 2)
  --suites LIST      reference (301^2 twisted sheet at 0.25x mean edge, CGAL's elephant-with-holes
                     at 1x), scenes (the eight procedural scenes, last of 4 frames, their radius),
                     real (the real meshes at 0.25x), scale (the 1M twisted sheet, 708^2);
                     default reference,scenes,real
  --only LIST        only these scenes (names as in the tables)
  --data DIR         the benchmark-only meshes (default ../shared/data beside the repository)
  --elephant PATH    CGAL's elephant-with-holes.off (default: where build.sh put it)
  --mesh PATH[:F]    one more mesh (.off, .obj, .ply) at F x mean edge (default 0.25); repeatable
  --gap-ms N         idle time between contestants, so OpenMP and TBB workers stop spinning (default 5)
  --wait-policy P    OMP_WAIT_POLICY for ArborX's OpenMP threads: passive (default), active, or
                     default (libgomp's own: spin, then sleep)
  --quick            reference suite, 3 rounds, 1 warm-up
  --out FILE         result file (default bench/results/arborx.md)
Exit status: 2 when an ArborX pair set differs from minkq's (the scene and kind are named), 1 on errors.
)";

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  bool quick = false;
  try {
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      auto value = [&]() -> std::string {
        if (i + 1 >= argc) throw std::invalid_argument(a + " needs a value");
        return argv[++i];
      };
      if (a == "--threads") opt.threads = std::stoi(value());
      else if (a == "--repeats") opt.repeats = std::stoi(value());
      else if (a == "--warmup") opt.warmup = std::stoi(value());
      else if (a == "--suites") opt.suites = split(value());
      else if (a == "--only") opt.only = value();
      else if (a == "--data") opt.data_dir = value();
      else if (a == "--elephant") opt.elephant = value();
      else if (a == "--gap-ms") opt.gap_ms = std::stoi(value());
      else if (a == "--wait-policy") opt.wait_policy = value();
      else if (a == "--out") opt.out = value();
      else if (a == "--quick") quick = true;
      else if (a == "--mesh") {
        const std::string v = value();
        const size_t colon = v.rfind(':');
        if (colon != std::string::npos && colon > 0 && v.find('/', colon) == std::string::npos)
          opt.meshes.push_back({v.substr(0, colon), std::stod(v.substr(colon + 1))});
        else
          opt.meshes.push_back({v, 0.25});
      } else if (a == "-h" || a == "--help") {
        std::fputs(kUsage, stdout);
        return 0;
      } else
        throw std::invalid_argument("unknown option " + a);
    }
    if (quick) {
      opt.suites = {"reference"};
      opt.repeats = 3;
      opt.warmup = 1;
    }
    if (opt.wait_policy != "passive" && opt.wait_policy != "active" && opt.wait_policy != "default")
      throw std::invalid_argument("--wait-policy is passive, active or default");
    if (opt.threads < 1 || opt.repeats < 1 || opt.warmup < 0) throw std::invalid_argument("bad --threads/--repeats/--warmup");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "arborx_bench: %s\n%s", e.what(), kUsage);
    return 1;
  }

  // libgomp reads its environment when it loads, before main: set it and start again (once).
  // OMP_NUM_THREADS from --threads; OMP_PROC_BIND=false (unbound threads, as minkq's TBB
  // workers) unless the caller set it; OMP_WAIT_POLICY from --wait-policy: passive by default,
  // because on a shared machine libgomp's default (workers spin at every barrier before they
  // sleep) stalled ArborX calls by 100+ ms in a third to a half of the rounds, whatever their
  // size, while passive waits gave tight ranges; "default" leaves libgomp's default.
  if (!std::getenv("ARBORX_BENCH_ENV_SET")) {
    setenv("ARBORX_BENCH_ENV_SET", "1", 1);
    setenv("OMP_NUM_THREADS", std::to_string(opt.threads).c_str(), 1);
    setenv("OMP_PROC_BIND", "false", 0);
    if (opt.wait_policy == "default")
      unsetenv("OMP_WAIT_POLICY");
    else
      setenv("OMP_WAIT_POLICY", opt.wait_policy.c_str(), 1);
    execv("/proc/self/exe", argv);
    std::perror("arborx_bench: execv");
    return 1;
  }
  const std::string nthreads = std::to_string(opt.threads);

  Kokkos::ScopeGuard kokkos(Kokkos::InitializationSettings().set_num_threads(opt.threads).set_disable_warnings(true));
  tbb::global_control tbb_threads(tbb::global_control::max_allowed_parallelism, size_t(opt.threads));
  int status = 0;
  try {
    const Exec space;
    if (space.concurrency() != opt.threads || omp_get_max_threads() != opt.threads)
      throw std::runtime_error("Kokkos runs " + std::to_string(space.concurrency()) + " threads, not " + nthreads);
    mb::Device device = mb::open_device("cpu");
    const std::string machine = mb::machine_line(minkq_device_name(device.get()));
    const double load_start = mb::load_average();
    const std::string started = mb::utc_now();
    std::fprintf(stderr, "arborx_bench: %s; %d threads; load %.2f\n", machine.c_str(), opt.threads, load_start);
    std::vector<SceneResult> results;
    for (const auto& make : scene_list(opt)) {
      results.push_back(run_scene(make(), opt, space, device.get()));
      const SceneResult& s = results.back();
      for (const Check& c : s.checks)
        if (!c.ok) {
          std::fprintf(stderr, "arborx_bench: %s: %s: %s\n", s.scene.name.c_str(), c.kind.c_str(), c.verdict.c_str());
          status = 2;
        }
      for (const Contestant& c : s.contestants)
        std::fprintf(stderr, "  %-32s %-7s %-48s %s ms\n", c.row.c_str(), c.lib.c_str(), c.variant.c_str(), ms_text(c.t).c_str());
    }
    write_report(results, opt, machine, load_start, started);
    std::fprintf(stderr, "arborx_bench: wrote %s%s\n", opt.out.c_str(), status ? " (a pair set differs: exit 2)" : "");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "arborx_bench: error: %s\n", e.what());
    status = 1;
  }
  return status;
}
