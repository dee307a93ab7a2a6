// minkq_ablation's one-pass study (fused.md, issue 8): minkq_scene_query_vt_ee against two
// minkq_scene_query calls.
#include <cstdio>
#include <iterator>
#include <utility>
#include <vector>

#include "ablation/ablation.h"

namespace minkq::bench::ablation {

// The scene created at the first frame and refit to the last (a simulator's refit-only step),
// then per variant one step's queries: VT and EE by two calls, or by one fused call; the box
// candidates and the contacts (box + leaf_exact). Pairs checked equal by digest.
std::string compare_fused(const SceneFrames& sc, minkq_device* device, int rounds, bool& ok) {
  const float r = float(sc.radius_factor * sc.mean_edge);
  std::fprintf(stderr, "%s (fused): %d V, %d T, r = %.4g\n", sc.name.c_str(), int(sc.mesh.vertex_count()),
               int(sc.mesh.triangle_count()), double(r));
  Scene scene = create_scene(device, sc.frames[0], sc.mesh.tris);
  const std::vector<float>& last = sc.frames.back();
  check(minkq_scene_refit(scene.get(), {last.data(), 12, last.size() / 3, MINKQ_MEMORY_HOST}), "minkq_scene_refit");
  Result vt = new_result(), ee = new_result();
  struct Variant {
    const char* output;
    uint32_t flags;
    bool fused;
  };
  const Variant variants[] = {{"box candidates", 0, false}, {"box candidates", 0, true},
                              {"contacts (leaf_exact)", MINKQ_QUERY_LEAF_EXACT, false},
                              {"contacts (leaf_exact)", MINKQ_QUERY_LEAF_EXACT, true}};
  auto run = [&](const Variant& v, uint32_t extra) {
    const minkq_query_desc qvt{MINKQ_QUERY_VT, MINKQ_MODE_BOX, v.flags | extra, r};
    const minkq_query_desc qee{MINKQ_QUERY_EE, MINKQ_MODE_BOX, v.flags | extra, r};
    if (v.fused) {
      check(minkq_scene_query_vt_ee_result(scene.get(), &qvt, &qee, vt.get(), ee.get()), "minkq_scene_query_vt_ee_result");
    } else {
      check(minkq_scene_query_result(scene.get(), &qvt, vt.get()), "minkq_scene_query_result");
      check(minkq_scene_query_result(scene.get(), &qee, ee.get()), "minkq_scene_query_result");
    }
  };
  const size_t n = std::size(variants);
  std::vector<std::pair<uint64_t, uint64_t>> digests(n), counts(n);
  for (size_t i = 0; i < n; ++i) {
    run(variants[i], MINKQ_QUERY_DIGEST);  // also the warm-up, growing the results
    digests[i] = {minkq_result_digest(vt.get()), minkq_result_digest(ee.get())};
    counts[i] = {minkq_result_count(vt.get()), minkq_result_count(ee.get())};
    ok &= digests[i] == digests[i & ~size_t(1)];
  }
  std::vector<std::vector<double>> times(n);
  for (int round = 0; round < rounds; ++round)
    for (size_t i = 0; i < n; ++i) {
      const double start = now_ms();
      run(variants[i], 0);
      times[i].push_back(now_ms() - start);
    }
  std::string out;
  for (size_t i = 0; i < n; ++i) {
    const double ms = median(times[i]), before = median(times[i & ~size_t(1)]);
    out += "| " + sc.name + " | " + std::to_string(sc.mesh.triangle_count()) + " | " + variants[i].output + " | " +
           (variants[i].fused ? "one call (minkq_scene_query_vt_ee)" : "two calls (VT, then EE)") + " | " +
           std::to_string(counts[i].first) + " | " + std::to_string(counts[i].second) + " | " + fmt(ms, 4) + " | " +
           fmt(before / ms, 3) + "x |\n";
  }
  return out;
}

}  // namespace minkq::bench::ablation
