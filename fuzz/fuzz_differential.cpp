// Differential fuzzer: decodes the input into a structured scene (scene_decoder.h), runs every
// mode through the C API on the CPU backend (and every CUDA device, where one exists), and
// checks it against the brute-force definition, the Embree reference and the long-double
// oracle (scene_checks.h), float64 input and swept steps included; or decodes a scene of many
// geometries (geometry_decoder.h) and checks it against the oracle (geometry_scene_checks.h). A mismatch prints the scene
// as C++ and aborts, so libFuzzer keeps (and with -minimize_crash=1 shrinks) the input.
//
// Environment: MINKQ_FUZZ_THREADS (TBB threads, default 1: the campaign machine is shared),
// MINKQ_FUZZ_VERBOSE=1 (print every scene), MINKQ_FUZZ_STATS_EVERY=N (progress line every N),
// MINKQ_FUZZ_INJECT=1 (self-test: drop one pair from minkq's answer; the fuzzer must fail),
// MINKQ_FUZZ_STRICT=1 (report the contacts of known, unfixed library bugs too; scene_oracle.h).
#include <tbb/global_control.h>

#include <cstdio>
#include <cstdlib>
#include <memory>

#include "embree_reference.h"
#include "geometry_decoder.h"
#include "scene_checks.h"
#include "scene_decoder.h"

namespace {

using namespace minkq::fuzz;

struct Harness {
  std::unique_ptr<tbb::global_control> threads;
  std::vector<minkq::cxx::Device> devices;
  std::unique_ptr<EmbreeReference> embree;
  Stats stats;
  GeometryStats geometry;
  uint64_t inputs = 0;
  uint64_t every = 0;
  bool verbose = false;
};
Harness* harness = nullptr;

void print_stats(const char* when) {
  const Stats& s = harness->stats;
  std::fprintf(stderr,
               "minkq_fuzz_differential %s: inputs %llu, scenes checked %llu (mesh %llu, of which refit %llu, "
               "float64 %llu, swept %llu (still %llu); user-box %llu), queries %llu, Embree sets compared %llu, pairs "
               "compared %llu, oracle contacts %llu (swept steps: %llu at sampled times), "
               "mismatches 0\n",
               when, (unsigned long long)harness->inputs, (unsigned long long)(s.mesh_scenes + s.box_scenes),
               (unsigned long long)s.mesh_scenes, (unsigned long long)s.refit_scenes,
               (unsigned long long)s.float64_scenes, (unsigned long long)s.swept_scenes,
               (unsigned long long)s.still_steps, (unsigned long long)s.box_scenes, (unsigned long long)s.queries,
               (unsigned long long)s.independent, (unsigned long long)s.pairs, (unsigned long long)s.true_contacts,
               (unsigned long long)s.sampled_contacts);
  const GeometryStats& g = harness->geometry;
  std::fprintf(stderr,
               "minkq_fuzz_differential %s: geometry scenes %llu (steps %llu, of which swept %llu; refused %llu; "
               "one-mesh equalities %llu; oracle contacts %llu, at swept steps' sampled times %llu)\n",
               when, (unsigned long long)g.scenes, (unsigned long long)g.steps, (unsigned long long)g.swept,
               (unsigned long long)g.refused, (unsigned long long)g.one_mesh, (unsigned long long)g.contacts,
               (unsigned long long)g.sampled);
}

void at_exit() { print_stats("at exit"); }

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  harness = new Harness();
  const char* threads = std::getenv("MINKQ_FUZZ_THREADS");
  const int n = threads ? std::atoi(threads) : 1;
  if (n > 0) harness->threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, n);
  harness->devices = open_devices();
  if (harness->devices.empty()) {
    std::fprintf(stderr, "minkq_device_create(\"cpu\") failed: %s\n", minkq_last_error_message());
    std::abort();
  }
  harness->embree = std::make_unique<EmbreeReference>();
  harness->verbose = std::getenv("MINKQ_FUZZ_VERBOSE") != nullptr;
  inject_fault() = std::getenv("MINKQ_FUZZ_INJECT") != nullptr;
  if (const char* every = std::getenv("MINKQ_FUZZ_STATS_EVERY")) harness->every = std::strtoull(every, nullptr, 10);
  std::fprintf(stderr, "minkq_fuzz_differential: devices:");
  for (const auto& d : harness->devices) std::fprintf(stderr, " [%s]", minkq_device_name(d.get()));
  std::fprintf(stderr, "; reference: Embree %d.%d.%d (isa=sse2)\n", RTC_VERSION_MAJOR, RTC_VERSION_MINOR,
               RTC_VERSION_PATCH);
  std::atexit(at_exit);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  // The last bytes are the scene's parameters, the rest its geometry (see scene_decoder.h).
  const size_t header = std::min<size_t>(size, 32);
  FuzzedDataProvider params(data + size - header, header);
  FuzzedDataProvider in(data, size - header);
  SceneDecoder decoder(in, params);
  Report report;
  std::string description;
  harness->inputs++;
  // The parameters' first byte picks the kind of scene: by its value mod 4 (as before scenes
  // of many geometries came, so the committed corpus keeps its kinds) a mesh scene (VT and EE)
  // or, for 0, a user-box BVH scene; by its next bits, which that choice leaves unread, a scene
  // of many geometries instead: 1 in 4 of the mesh inputs and 1 in 2 of the box inputs.
  const uint8_t pick = header ? data[size - 1] : 0;
  const bool geometries = pick % 4 != 0 ? (pick >> 2) % 4 == 3 : (pick >> 2) % 2 == 1;
  const bool mesh = params.ConsumeIntegralInRange<int>(0, 3) != 0;
  if (geometries) {
    GeometryDecoder geometry_decoder(in, params);
    const GeometryScene scene = geometry_decoder.scene();
    if (harness->verbose) std::fprintf(stderr, "%s\n", describe(scene).c_str());
    for (const auto& device : harness->devices) check_geometry_fuzz_scene(device.get(), scene, report, harness->geometry);
    if (!report.ok()) description = describe(scene);
  } else if (mesh) {
    const MeshScene scene = decoder.mesh();
    if (harness->verbose) std::fprintf(stderr, "%s\n", describe(scene).c_str());
    check_mesh_scene(harness->devices, scene, harness->embree.get(), report, harness->stats);
    if (!report.ok()) description = describe(scene);
  } else {
    const BoxScene scene = decoder.boxes();
    if (harness->verbose) std::fprintf(stderr, "%s\n", describe(scene).c_str());
    check_box_scene(harness->devices, scene, harness->embree.get(), report, harness->stats);
    if (!report.ok()) description = describe(scene);
  }
  harness->embree->reset();
  if (!report.ok()) {
    std::fprintf(stderr, "\n==== minkq differential fuzzer: MISMATCH ====\n%s\n---- scene (paste into "
                         "tests/test_fuzz_regressions.cpp) ----\n%s\n",
                 report.text().c_str(), description.c_str());
    std::fflush(stderr);
    std::abort();
  }
  if (harness->every && harness->inputs % harness->every == 0) print_stats("progress");
  return 0;
}
