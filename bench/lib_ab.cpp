// minkq_lib_ab: two builds of libminkq.so side by side in one process, for a change's before
// and after on a machine whose speed drifts between runs (a 2-vCPU VM moved by up to 1.5x
// between back-to-back runs of identical code): each library is loaded by path (dlopen,
// RTLD_LOCAL | RTLD_DEEPBIND: each calls its own code), and every step runs for both in every
// round, in the order A B, then B A, and so on, so that drift falls on both alike.
//
// Per scene (the procedural scenes at reference size, last of 4 frames, or --scenes), through
// the C API on the CPU device (all threads): a VT + EE scene with incident pairs dropped is
// created at frame 0 in each library, then each round times, for A and for B:
//   refit     minkq_scene_refit to the last frame
//   rebuild   minkq_scene_rebuild to the last frame
//   VT box, VT sphere, VT leaf_exact, EE box, EE capsule_exact, EE leaf_exact
//             minkq_scene_query_result at the scene's radius (pairs stored)
// Checked before timing: both libraries give the same pair count and digest for each query.
// Reported: each library's median ms, and the median over rounds of A ms / B ms (> 1: B faster).
//
//   minkq_lib_ab --a LIB --b LIB [--scenes LIST] [--steps LIST] [--rounds N] [--data DIR] [--out FILE]
//   (defaults: the eight procedural scenes, every step, 15 rounds, ../shared/data, stdout only;
//   --steps takes labels as above, comma-separated: "refit,EE leaf_exact")
#include <dlfcn.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "common.h"
#include "harness.h"
#include "scenes.h"

using namespace minkq::bench;

namespace {

// The C API functions this study calls, from one library.
struct Api {
  std::string path;
  void* handle = nullptr;
  decltype(&minkq_device_create) device_create;
  decltype(&minkq_device_release) device_release;
  decltype(&minkq_scene_create) scene_create;
  decltype(&minkq_scene_release) scene_release;
  decltype(&minkq_scene_refit) refit;
  decltype(&minkq_scene_rebuild) rebuild;
  decltype(&minkq_scene_query_result) query_result;
  decltype(&minkq_result_create) result_create;
  decltype(&minkq_result_release) result_release;
  decltype(&minkq_result_count) result_count;
  decltype(&minkq_result_digest) result_digest;
  decltype(&minkq_last_error_message) last_error;

  template <class F>
  void bind(F& f, const char* name) {
    f = reinterpret_cast<F>(dlsym(handle, name));
    if (!f) throw std::runtime_error(path + ": no symbol " + name);
  }
  explicit Api(const std::string& p) : path(p) {
    handle = dlopen(p.c_str(), RTLD_NOW | RTLD_LOCAL | RTLD_DEEPBIND);
    if (!handle) throw std::runtime_error("dlopen " + p + ": " + dlerror());
    bind(device_create, "minkq_device_create");
    bind(device_release, "minkq_device_release");
    bind(scene_create, "minkq_scene_create");
    bind(scene_release, "minkq_scene_release");
    bind(refit, "minkq_scene_refit");
    bind(rebuild, "minkq_scene_rebuild");
    bind(query_result, "minkq_scene_query_result");
    bind(result_create, "minkq_result_create");
    bind(result_release, "minkq_result_release");
    bind(result_count, "minkq_result_count");
    bind(result_digest, "minkq_result_digest");
    bind(last_error, "minkq_last_error_message");
  }
  void check(minkq_status s, const char* what) const {
    if (s != MINKQ_SUCCESS) throw std::runtime_error(path + ": " + what + ": " + last_error());
  }
};

// One library's device, scene (created at frame 0) and result.
struct Side {
  const Api& api;
  minkq_device* device = nullptr;
  minkq_scene* scene = nullptr;
  minkq_result* result = nullptr;
  Side(const Api& a, const SceneFrames& sc) : api(a) {
    api.check(api.device_create("cpu", &device), "minkq_device_create");
    minkq_scene_desc desc{};
    desc.flags = MINKQ_SCENE_VT | MINKQ_SCENE_EE | MINKQ_SCENE_DROP_INCIDENT;
    desc.vertices = minkq::cxx::host_buffer(sc.frames[0].data(), sc.frames[0].size() / 3, 12);
    desc.triangles = minkq::cxx::host_buffer(sc.mesh.tris.data(), sc.mesh.tris.size() / 3, 12);
    desc.edges = minkq::cxx::host_buffer(nullptr, 0);
    api.check(api.scene_create(device, &desc, &scene), "minkq_scene_create");
    api.check(api.result_create(&result), "minkq_result_create");
  }
  ~Side() {
    api.result_release(result);
    api.scene_release(scene);
    api.device_release(device);
  }
  Side(const Side&) = delete;
  Side& operator=(const Side&) = delete;
};

// The steps timed, in this order: the two updates to the last frame, then the queries.
struct Step {
  const char* label;
  enum { kRefit, kRebuild, kQuery } what;
  minkq_query_kind kind;  // queries only
  minkq_mode mode;
  uint32_t flags = 0;  // the query's own (leaf_exact)
};
constexpr Step kAllSteps[] = {{"refit", Step::kRefit, MINKQ_QUERY_VT, MINKQ_MODE_BOX},
                              {"rebuild", Step::kRebuild, MINKQ_QUERY_VT, MINKQ_MODE_BOX},
                              {"VT box", Step::kQuery, MINKQ_QUERY_VT, MINKQ_MODE_BOX},
                              {"VT sphere", Step::kQuery, MINKQ_QUERY_VT, MINKQ_MODE_SPHERE},
                              {"VT leaf_exact", Step::kQuery, MINKQ_QUERY_VT, MINKQ_MODE_BOX, MINKQ_QUERY_LEAF_EXACT},
                              {"EE box", Step::kQuery, MINKQ_QUERY_EE, MINKQ_MODE_BOX},
                              {"EE capsule_exact", Step::kQuery, MINKQ_QUERY_EE, MINKQ_MODE_CAPSULE_EXACT},
                              {"EE leaf_exact", Step::kQuery, MINKQ_QUERY_EE, MINKQ_MODE_BOX, MINKQ_QUERY_LEAF_EXACT}};

// One step on one side: vertices for the updates, radius r and query flags for the queries.
void run_step(const Step& step, Side& s, const minkq_buffer& vertices, float r, uint32_t flags) {
  switch (step.what) {
    case Step::kRefit: return s.api.check(s.api.refit(s.scene, vertices), "minkq_scene_refit");
    case Step::kRebuild: return s.api.check(s.api.rebuild(s.scene, vertices), "minkq_scene_rebuild");
    case Step::kQuery: {
      const minkq_query_desc q{step.kind, step.mode, flags | step.flags, r};
      return s.api.check(s.api.query_result(s.scene, &q, s.result), "minkq_scene_query_result");
    }
  }
}

// The items of a comma-separated option value, in order (empty ones kept: they name nothing).
std::vector<std::string> comma_list(const std::string& value) {
  std::vector<std::string> items;
  std::stringstream list(value);
  for (std::string item; std::getline(list, item, ',');) items.push_back(item);
  return items;
}

}  // namespace

int main(int argc, char** argv) try {
  std::string a_path, b_path, out, data = MINKQ_BENCH_DATA_DIR;
  std::vector<std::string> scenes = procedural_scene_names();
  std::vector<Step> steps(std::begin(kAllSteps), std::end(kAllSteps));
  int rounds = 15;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw std::runtime_error(arg + " needs a value");
      return argv[++i];
    };
    if (arg == "--a") a_path = value();
    else if (arg == "--b") b_path = value();
    else if (arg == "--rounds") rounds = std::max(1, std::atoi(value().c_str()));
    else if (arg == "--data") data = value();
    else if (arg == "--out") out = value();
    else if (arg == "--scenes") scenes = comma_list(value());
    else if (arg == "--steps") {
      steps.clear();
      for (const std::string& label : comma_list(value())) {
        const auto it = std::find_if(std::begin(kAllSteps), std::end(kAllSteps),
                                     [&](const Step& step) { return label == step.label; });
        if (it == std::end(kAllSteps)) throw std::runtime_error("--steps: no step named \"" + label + "\"");
        steps.push_back(*it);
      }
    } else {
      std::fprintf(stderr, "usage: minkq_lib_ab --a LIB --b LIB [--scenes LIST] [--steps LIST] [--rounds N] [--data DIR] [--out FILE]\n");
      return 1;
    }
  }
  if (a_path.empty() || b_path.empty()) throw std::runtime_error("--a and --b name the two libraries");
  const Api a(a_path), b(b_path);

  std::ostringstream md;
  md << "# minkq_lib_ab: A = `" << a_path << "`, B = `" << b_path << "`\n\n"
     << machine_line("cpu") << ". Per scene (last of 4 frames, the scene's radius, VT + EE with incident pairs dropped) "
     << "each step ran for A and B in every round, in the order A B, B A, ...; " << rounds
     << " rounds; ms = median over rounds; A / B = median over rounds of A ms / B ms (> 1: B faster). Pair counts and "
        "digests checked equal. Written by `minkq_lib_ab`.\n\n"
     << "| scene | step | A ms | B ms | A / B |\n|---|---|---|---|---|\n";
  std::vector<std::vector<double>> all_ratios;
  for (const std::string& name : scenes) {
    const SceneFrames sc = make_scene(name, 0, 4, data);
    const float r = float(sc.radius_factor * sc.mean_edge);
    const std::vector<float>& last = sc.frames.back();
    std::fprintf(stderr, "%s: %zu V, %zu T, r = %.4g\n", name.c_str(), last.size() / 3, sc.mesh.tris.size() / 3, double(r));
    Side sa(a, sc), sb(b, sc);
    const minkq_buffer vb = minkq::cxx::host_buffer(last.data(), last.size() / 3, 12);
    run_step(kAllSteps[0], sa, vb, r, 0), run_step(kAllSteps[0], sb, vb, r, 0);  // both at the last frame
    for (const Step& step : steps) {  // the same pairs from both
      if (step.what != Step::kQuery) continue;
      uint64_t digest[2], count[2];
      Side* sides[2] = {&sa, &sb};
      for (int j = 0; j < 2; ++j) {
        run_step(step, *sides[j], vb, r, MINKQ_QUERY_DIGEST);
        count[j] = sides[j]->api.result_count(sides[j]->result);
        digest[j] = sides[j]->api.result_digest(sides[j]->result);
      }
      if (count[0] != count[1] || digest[0] != digest[1])
        throw std::runtime_error(name + ", " + step.label + ": the libraries' pairs differ");
    }
    for (size_t k = 0; k < steps.size(); ++k) {
      std::vector<double> ta, tb, ratio;
      run_step(steps[k], sa, vb, r, 0), run_step(steps[k], sb, vb, r, 0);  // warm-up
      for (int round = 0; round < rounds; ++round) {
        double t[2];
        for (int j = 0; j < 2; ++j) {
          const bool first_a = round % 2 == 0;
          Side& s = (j == 0) == first_a ? sa : sb;
          const double start = now_ms();
          run_step(steps[k], s, vb, r, 0);
          t[&s == &sa ? 0 : 1] = now_ms() - start;
        }
        ta.push_back(t[0]), tb.push_back(t[1]), ratio.push_back(t[0] / t[1]);
      }
      if (all_ratios.size() <= k) all_ratios.resize(k + 1);
      all_ratios[k].push_back(median(ratio));
      md << "| " << name << " | " << steps[k].label << " | " << fmt(median(ta)) << " | " << fmt(median(tb)) << " | "
         << fmt(median(ratio)) << "x |\n";
    }
  }
  md << "\nGeometric mean of A / B over the scenes, per step:";
  for (size_t k = 0; k < all_ratios.size(); ++k) {
    double log_sum = 0;
    for (double x : all_ratios[k]) log_sum += std::log(x);
    md << (k ? ";" : "") << " " << steps[k].label << " " << fmt(std::exp(log_sum / double(all_ratios[k].size()))) << "x";
  }
  md << ".\n";
  std::fputs(md.str().c_str(), stdout);
  if (!out.empty()) std::ofstream(out) << md.str();
  return 0;
} catch (const std::exception& e) {
  std::fprintf(stderr, "minkq_lib_ab: %s\n", e.what());
  return 1;
}
