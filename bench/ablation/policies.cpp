// minkq_ablation's rebuild-policy study (policies.md, issue 8), end to end through the C API.
#include <cstdio>
#include <iterator>
#include <vector>

#include "ablation/ablation.h"

namespace minkq::bench::ablation {
namespace {

// Rebuild policies end to end, through the C API as a simulator calls it: a scene created at
// frame 0, then per step minkq_scene_refit or minkq_scene_rebuild to the next frame, the
// growth read back (minkq_scene_tree_growth), and the VT and EE queries (box mode, incident
// pairs dropped, into reused results). Every policy's pairs are checked equal step by step
// (digests) and its work counted in a separate, untimed STATS pass; the policies' whole
// sequences run round-robin, `rounds` times; ms = median over rounds of the sequence's sum.
struct Policy {
  const char* label;
  int every;         // rebuild every `every` steps (0: not by count)
  double threshold;  // rebuild when the growth read after the last step exceeds it (0: never)
};
constexpr Policy kPolicies[] = {{"refit every step (the default)", 0, 0.0},
                                {"rebuild every step", 1, 0.0},
                                {"rebuild every 5th step", 5, 0.0},
                                {"rebuild when growth > 1.5 (minkq.h's advice)", 0, 1.5},
                                {"rebuild when growth > 1.2", 0, 1.2}};

struct PolicyRun {
  double update_ms = 0, query_ms = 0, growth_max = 1.0;
  int rebuilds = 0;
  uint64_t vt_nodes = 0, ee_nodes = 0;
  std::vector<uint64_t> digests;  // VT, EE per step (counted runs only)
};

PolicyRun run_policy(minkq_device* device, const SceneFrames& sc, const Policy& policy, float r, bool counted) {
  PolicyRun run;
  Scene scene = create_scene(device, sc.frames[0], sc.mesh.tris);
  Result vt = new_result(), ee = new_result();
  double growth = 1.0;
  for (size_t k = 1; k < sc.frames.size(); ++k) {
    const minkq_buffer vb{sc.frames[k].data(), 12, sc.frames[k].size() / 3, MINKQ_MEMORY_HOST};
    const int step = int(k);
    const bool rebuild = (policy.every > 0 && step % policy.every == 0) || (policy.threshold > 0 && growth > policy.threshold);
    double start = now_ms();
    check(rebuild ? minkq_scene_rebuild(scene.get(), vb) : minkq_scene_refit(scene.get(), vb), "minkq_scene_refit/rebuild");
    check(minkq_scene_tree_growth(scene.get(), &growth), "minkq_scene_tree_growth");
    run.update_ms += now_ms() - start;
    run.rebuilds += rebuild ? 1 : 0;
    run.growth_max = std::max(run.growth_max, growth);
    const minkq_query_desc qvt{MINKQ_QUERY_VT, MINKQ_MODE_BOX, 0, r}, qee{MINKQ_QUERY_EE, MINKQ_MODE_BOX, 0, r};
    start = now_ms();
    check(minkq_scene_query_result(scene.get(), &qvt, vt.get()), "minkq_scene_query_result");
    check(minkq_scene_query_result(scene.get(), &qee, ee.get()), "minkq_scene_query_result");
    run.query_ms += now_ms() - start;
    if (!counted) continue;
    const uint32_t stats = MINKQ_QUERY_STATS | MINKQ_QUERY_DIGEST;
    const minkq_query_desc cvt{MINKQ_QUERY_VT, MINKQ_MODE_BOX, stats, r}, cee{MINKQ_QUERY_EE, MINKQ_MODE_BOX, stats, r};
    check(minkq_scene_query_result(scene.get(), &cvt, vt.get()), "minkq_scene_query_result");
    run.vt_nodes += minkq_result_stats(vt.get()).nodes_visited;
    run.digests.push_back(minkq_result_digest(vt.get()));
    check(minkq_scene_query_result(scene.get(), &cee, ee.get()), "minkq_scene_query_result");
    run.ee_nodes += minkq_result_stats(ee.get()).nodes_visited;
    run.digests.push_back(minkq_result_digest(ee.get()));
  }
  return run;
}

}  // namespace

std::string compare_policies(const SceneFrames& sc, int rounds, bool& ok) {
  const float r = float(sc.radius_factor * sc.mean_edge);
  const int32_t nv = int32_t(sc.mesh.vertex_count()), ne = int32_t(sc.mesh.edge_count());
  const int steps = int(sc.frames.size()) - 1;
  std::fprintf(stderr, "%s (policies): %d V, %d T, %d steps, r = %.4g\n", sc.name.c_str(), nv,
               int(sc.mesh.triangle_count()), steps, double(r));
  Device device = open_device("cpu");
  const size_t n = std::size(kPolicies);
  std::vector<PolicyRun> counted(n);
  for (size_t i = 0; i < n; ++i) {
    counted[i] = run_policy(device.get(), sc, kPolicies[i], r, true);
    ok &= counted[i].digests == counted[0].digests;
  }
  std::vector<std::vector<double>> update(n), query(n), total(n);
  for (int round = 0; round < rounds; ++round)
    for (size_t i = 0; i < n; ++i) {
      const PolicyRun run = run_policy(device.get(), sc, kPolicies[i], r, false);
      update[i].push_back(run.update_ms);
      query[i].push_back(run.query_ms);
      total[i].push_back(run.update_ms + run.query_ms);
    }
  std::string out;
  const double base = median(total[0]);
  for (size_t i = 0; i < n; ++i) {
    const PolicyRun& c = counted[i];
    const double t = median(total[i]);
    out += "| " + sc.name + " | " + std::to_string(steps) + " | " + kPolicies[i].label + " | " + std::to_string(c.rebuilds) +
           " | " + fmt(c.growth_max, 3) + " | " + fmt(double(c.vt_nodes) / (double(nv) * steps), 4) + " | " +
           fmt(double(c.ee_nodes) / (double(ne) * steps), 4) + " | " + fmt(median(update[i]), 4) + " | " +
           fmt(median(query[i]), 4) + " | " + fmt(t, 4) + " | " + fmt(base / t, 3) + "x |\n";
  }
  return out;
}

}  // namespace minkq::bench::ablation
