// The command line and the scenes the study programs share (minkq_build_study, minkq_traversal_study):
//   [--threads N] [--repeats N] [--quick] [--large] [--data DIR] [--out DIR]
#pragma once

#include <cstdio>
#include <cstdlib>
#include <string>

#include "common.h"
#include "scenes.h"

namespace minkq::bench {

struct StudyOptions {
  std::string data, out;  // the benchmark-only meshes, the results folder
  int threads = 2, repeats = 11;
  bool quick = false;  // small scenes, 3 repeats
  bool large = false;  // adds the 1M-triangle twisted sheet
};

// False (the usage printed, naming `program`) on an unknown or incomplete option.
inline bool parse_study_options(int argc, char** argv, const char* program, StudyOptions& o) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--threads" && i + 1 < argc) o.threads = std::atoi(argv[++i]);
    else if (a == "--repeats" && i + 1 < argc) o.repeats = std::atoi(argv[++i]);
    else if (a == "--data" && i + 1 < argc) o.data = argv[++i];
    else if (a == "--out" && i + 1 < argc) o.out = argv[++i];
    else if (a == "--quick") o.quick = true, o.repeats = 3;
    else if (a == "--large") o.large = true;
    else {
      std::fprintf(stderr, "usage: %s [--threads N] [--repeats N] [--quick] [--large] [--data DIR] [--out DIR]\n",
                   program);
      return false;
    }
  }
  return true;
}

// The line under a study's title: program, options, machine, threads, load at start and now.
inline std::string written_by(const StudyOptions& o, const char* program, double load_start) {
  return std::string("Written by `") + program + (o.large ? " --large" : "") + (o.quick ? " --quick" : "") +
         "` (bench/" + std::string(program).substr(6) + ".cpp). Machine: " + machine_line("cpu") + "; " +
         std::to_string(o.threads) + " TBB threads. Load average (1 min) at start " + fmt(load_start, 3) +
         ", at end " + fmt(load_average(), 3) + ".\n\n";
}

// Runs study(scene) on the studies' scenes, in order: the 180k-triangle twisted sheet (20k
// with --quick), the 1M one with --large, the procedural scenes when asked (only cloth_hanging
// with --quick), then the real meshes found (only the bunny with --quick). True when every
// study(scene) returned true.
template <class Study>
bool for_each_study_scene(const StudyOptions& o, bool procedural, Study&& study) {
  bool ok = study(make_scene("twist_target", o.quick ? 2e4 : 1.8e5, 1, o.data));
  if (o.large) ok = study(make_scene("twist_target", 1e6, 1, o.data)) && ok;
  if (procedural)
    for (const std::string& name : procedural_scene_names())
      if (!o.quick || name == "cloth_hanging") ok = study(make_scene(name, 0, 1, o.data)) && ok;
  for (const RealMesh& m : available_real_meshes(o.data))
    if (!o.quick || m.name == "bunny") ok = study(load_real_scene(m, o.data)) && ok;
  return ok;
}

}  // namespace minkq::bench
