// minkq_float64_swept: what two input paths of the C API cost, each against its baseline in the
// same run, through the C API on the CPU device (all threads):
//   float64  MINKQ_SCENE_FLOAT64 scenes (vertices as doubles, rounded by the scene, queries at
//            r + 2 rho) against float32 scenes of the same floats: create, refit, VT + EE box and
//            leaf_exact queries, candidates and contacts; doubles that are the floats exactly
//            (rho = 0) and the floats plus a sub-ulp perturbation (rho > 0, the same floats after
//            rounding, so only the radius and the double input differ). Checked: rho = 0 gives
//            the float32 pairs exactly, rho > 0 a superset of them, and the double oracle's
//            contacts (long double, on the doubles, at r) all lie in the float64 leaf_exact set.
//            Writes float64.md.
//   swept    swept steps (minkq_scene_refit_swept, consecutive frames as x0 -> x1) on the
//            procedural scenes and a twisted sheet under a rigid synthetic motion: VT in box,
//            capsule_ray and capsule_exact modes and EE box, candidates and time against box
//            mode, and the static box queries at x0 and at x1 for context. Checked: capsule_exact
//            (= sphere, checked) within capsule_ray within box; a sampled-time oracle (long
//            double distances at evenly spaced t) on the box candidates, whose confirmed pairs
//            every mode must report. Writes swept.md.
// Every contestant of a scene (or step) runs round-robin, one warm-up round then `repeats`
// rounds; times are the medians over the rounds, ratios taken within the run.
//
// This file reads the options and writes the files; the studies are float64.cpp and swept.cpp
// (bench/float64_swept/), their shared helpers float64_swept.h.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include "float64_swept/float64_swept.h"

using namespace minkq::bench;

int main(int argc, char** argv) {
  try {
    std::string data = MINKQ_BENCH_DATA_DIR, out = MINKQ_BENCH_RESULTS_DIR, sections = "all";
    int repeats = 7;
    bool quick = false;
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      if (a == "--quick") quick = true, repeats = 1;
      else if (a == "--out" && i + 1 < argc) out = argv[++i];
      else if (a == "--data" && i + 1 < argc) data = argv[++i];
      else if (a == "--repeats" && i + 1 < argc) repeats = std::max(1, std::stoi(argv[++i]));
      else if (a == "--only" && i + 1 < argc && (std::string(argv[i + 1]) == "float64" || std::string(argv[i + 1]) == "swept"))
        sections = argv[++i];
      else {
        std::fprintf(stderr, "usage: minkq_float64_swept [--quick] [--repeats N] [--out DIR] [--data DIR] "
                             "[--only float64|swept]\n");
        return 2;
      }
    }
    std::filesystem::create_directories(out);
    auto write = [&out](const std::string& name, const std::string& text) {
      std::ofstream f(out + "/" + name);
      f << text;
      if (!f) throw std::runtime_error("cannot write " + out + "/" + name);
      std::fprintf(stderr, "wrote %s/%s\n", out.c_str(), name.c_str());
    };
    Device device = open_device("cpu");
    const std::string machine = machine_line(minkq_device_name(device.get()));
    const std::string by = std::string("`minkq_float64_swept") + (quick ? " --quick" : "") + "`";
    bool ok = true;

    if (sections == "all" || sections == "float64") {
      const double started = now_ms();
      write("float64.md", float64_swept::float64_report(device.get(), data, repeats, quick, machine, by, ok));
      std::fprintf(stderr, "float64: %.1f s\n", (now_ms() - started) / 1000);
    }

    if (sections == "all" || sections == "swept") {
      const double started = now_ms();
      write("swept.md", float64_swept::swept_report(device.get(), data, repeats, quick, machine, by, ok));
      std::fprintf(stderr, "swept: %.1f s\n", (now_ms() - started) / 1000);
    }
    if (!ok) {
      std::fprintf(stderr, "FAIL: a check failed (see above)\n");
      return 1;
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "minkq_float64_swept: %s\n", e.what());
    return 3;
  }
}
