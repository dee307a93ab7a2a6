// minkq_bench's swept suite (swept.md): swept steps (minkq_scene_refit_swept, x0 -> x1)
// on the procedural scenes' frames and on the twisted sheet under rigid steps, VT in box,
// capsule_ray and capsule_exact modes and EE box timed round-robin against the static box
// queries at x0 and x1; checked: the VT sets nest (capsule_exact = sphere within capsule_ray
// within box) and a sampled-time oracle's confirmed pairs are in every capsule mode's set. It
// shares only the helpers of suites.h with the other suites.
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "suites/suites.h"

namespace minkq::bench::suites {
namespace {

// ---- swept ----------------------------------------------------------------------------------

// A step of a scene: positions at t = 0 and t = 1 (floats, same topology).
struct Step {
  const std::vector<float>* x0;
  const std::vector<float>* x1;
};

struct Motion {
  double max = 0, mean = 0;  // vertex displacement over the step
};
Motion motion_of(const Step& s) {
  Motion m;
  const size_t n = s.x0->size() / 3;
  for (size_t i = 0; i < n; ++i) {
    double d2 = 0;
    for (int k = 0; k < 3; ++k) {
      const double d = double((*s.x1)[3 * i + size_t(k)]) - double((*s.x0)[3 * i + size_t(k)]);
      d2 += d * d;
    }
    m.max = std::max(m.max, std::sqrt(d2));
    m.mean += std::sqrt(d2);
  }
  m.mean /= double(std::max<size_t>(n, 1));
  return m;
}

// Which of the candidates come within r at one of samples + 1 evenly spaced times (long double
// distances of the reference oracle on the positions x0 + t (x1 - x0) in double).
std::vector<char> sampled_confirm(const ref::Mesh& mesh, const Step& s, const PairSet& cands, bool vt, double r,
                                  int samples) {
  std::vector<char> hit(cands.size(), 0);
  const std::vector<float>&x0 = *s.x0, &x1 = *s.x1;
  auto at = [&](int32_t v, double t, double p[3]) {
    for (int k = 0; k < 3; ++k) {
      const double a = double(x0[3 * size_t(v) + size_t(k)]), b = double(x1[3 * size_t(v) + size_t(k)]);
      p[k] = a + t * (b - a);
    }
  };
  // The gap between the boxes of two point sets at one time: a lower bound of their distance,
  // so a pair whose boxes lie beyond r (with a margin for the double arithmetic) is skipped
  // without the oracle's distance.
  auto apart = [r](const double (*p)[3], int np, const double (*q)[3], int nq) {
    double g2 = 0;
    for (int k = 0; k < 3; ++k) {
      double plo = p[0][k], phi = p[0][k], qlo = q[0][k], qhi = q[0][k];
      for (int i = 1; i < np; ++i) plo = std::min(plo, p[i][k]), phi = std::max(phi, p[i][k]);
      for (int i = 1; i < nq; ++i) qlo = std::min(qlo, q[i][k]), qhi = std::max(qhi, q[i][k]);
      const double g = std::max({0.0, qlo - phi, plo - qhi});
      g2 += g * g;
    }
    return std::sqrt(g2) > r * (1 + 1e-9);
  };
  tbb::parallel_for(size_t(0), cands.size(), [&](size_t i) {
    const int32_t a = int32_t(cands[i] >> 32), b = int32_t(cands[i] & 0xffffffffu);
    for (int k = 0; k <= samples; ++k) {
      const double t = double(k) / samples;
      long double d;
      if (vt) {
        double p[1][3], q[3][3];
        at(a, t, p[0]);
        for (int j = 0; j < 3; ++j) at(mesh.tris[3 * size_t(b) + size_t(j)], t, q[j]);
        if (apart(p, 1, q, 3)) continue;
        d = ref::point_triangle_distance(p[0], q[0], q[1], q[2]);
      } else {
        double p[2][3], q[2][3];
        for (int j = 0; j < 2; ++j) at(mesh.edges[2 * size_t(a) + size_t(j)], t, p[j]);
        for (int j = 0; j < 2; ++j) at(mesh.edges[2 * size_t(b) + size_t(j)], t, q[j]);
        if (apart(p, 2, q, 2)) continue;
        d = ref::segment_segment_distance(p[0], p[1], q[0], q[1]);
      }
      if (d <= (long double)r) {
        hit[i] = 1;
        break;
      }
    }
  });
  return hit;
}

// The contestants of a swept step, in round-robin order.
enum Contestant { kVtBox, kVtRay, kVtExact, kEeBox, kStatic0, kStatic1, kContestants };

struct SweptTotals {
  int steps = 0;
  Motion motion;  // max over steps, mean of the steps' means
  double refit_swept_ms = 0, refit_ms = 0;
  double ms[kContestants] = {};
  uint64_t vt[kContestants] = {}, ee[kContestants] = {};  // candidates (static: box at x0, x1)
  uint64_t vt_confirmed = 0, ee_confirmed = 0;
  uint64_t fn = 0;                  // confirmed pairs missing from a mode's set
  bool oracle = false;
};

// One step through the C API: `swept` refit to (x0, x1) and `fixed` refit to x0 then x1 in every
// round (the refits timed), the six contestants round-robin; then counts, checks and the
// sampled oracle (untimed).
void run_step(minkq_scene* swept, minkq_scene* fixed, const SceneFrames& sc, const Step& s, float r, int repeats,
              int samples, SweptTotals& tot, bool& ok) {
  Result res[2] = {new_result(), new_result()};
  std::vector<double> times[kContestants], refit_swept, refit;
  auto vt_query = [&](minkq_scene* scene, minkq_mode mode, int slot) {
    query(scene, MINKQ_QUERY_VT, mode, 0, r, res[slot].get());
  };
  for (int round = 0; round <= repeats; ++round) {
    double t = now_ms();
    check(minkq_scene_refit_swept(swept, buffer_of(*s.x0), buffer_of(*s.x1)), "minkq_scene_refit_swept");
    const double rs = now_ms() - t;
    double got[kContestants];
    const minkq_mode modes[3] = {MINKQ_MODE_BOX, MINKQ_MODE_CAPSULE_RAY, MINKQ_MODE_CAPSULE_EXACT};
    for (int c = kVtBox; c <= kVtExact; ++c) {
      t = now_ms();
      vt_query(swept, modes[c], 0);
      got[c] = now_ms() - t;
    }
    t = now_ms();
    query(swept, MINKQ_QUERY_EE, MINKQ_MODE_BOX, 0, r, res[1].get());
    got[kEeBox] = now_ms() - t;
    double rf = 0;
    for (int c = kStatic0; c <= kStatic1; ++c) {
      t = now_ms();
      check(minkq_scene_refit(fixed, buffer_of(c == kStatic0 ? *s.x0 : *s.x1)), "minkq_scene_refit");
      rf += now_ms() - t;
      t = now_ms();
      query(fixed, MINKQ_QUERY_VT, MINKQ_MODE_BOX, 0, r, res[0].get());
      query(fixed, MINKQ_QUERY_EE, MINKQ_MODE_BOX, 0, r, res[1].get());
      got[c] = now_ms() - t;
    }
    if (round == 0) continue;  // warm-up
    refit_swept.push_back(rs);
    refit.push_back(rf / 2);
    for (int c = 0; c < kContestants; ++c) times[c].push_back(got[c]);
  }
  // Counts and sets (untimed).
  PairSet vt_sets[3];
  const minkq_mode modes[3] = {MINKQ_MODE_BOX, MINKQ_MODE_CAPSULE_RAY, MINKQ_MODE_CAPSULE_EXACT};
  for (int c = 0; c < 3; ++c) {
    vt_query(swept, modes[c], 0);
    vt_sets[c] = pairs_of(res[0].get());
  }
  vt_query(swept, MINKQ_MODE_SPHERE, 0);
  const PairSet sphere = pairs_of(res[0].get());
  query(swept, MINKQ_QUERY_EE, MINKQ_MODE_BOX, 0, r, res[1].get());
  const PairSet ee_box = pairs_of(res[1].get());
  if (sphere != vt_sets[2] || !includes(vt_sets[1], vt_sets[2]) || !includes(vt_sets[0], vt_sets[1])) {
    std::fprintf(stderr, "FAIL %s: swept VT sets not nested (box > capsule_ray > capsule_exact = sphere)\n", sc.name.c_str());
    ok = false;
  }
  uint64_t stat_vt[2], stat_ee[2];
  for (int c = 0; c < 2; ++c) {
    check(minkq_scene_refit(fixed, buffer_of(c == 0 ? *s.x0 : *s.x1)), "minkq_scene_refit");
    query(fixed, MINKQ_QUERY_VT, MINKQ_MODE_BOX, 0, r, res[0].get());
    query(fixed, MINKQ_QUERY_EE, MINKQ_MODE_BOX, 0, r, res[1].get());
    stat_vt[c] = minkq_result_count(res[0].get());
    stat_ee[c] = minkq_result_count(res[1].get());
  }
  if (samples > 0) {
    const std::vector<char> vt_hit = sampled_confirm(sc.mesh, s, vt_sets[0], true, double(r), samples);
    const std::vector<char> ee_hit = sampled_confirm(sc.mesh, s, ee_box, false, double(r), samples);
    for (size_t i = 0; i < vt_hit.size(); ++i)
      if (vt_hit[i]) {
        ++tot.vt_confirmed;
        for (int c = 1; c < 3; ++c)
          if (!std::binary_search(vt_sets[c].begin(), vt_sets[c].end(), vt_sets[0][i])) ++tot.fn;
      }
    for (char h : ee_hit) tot.ee_confirmed += uint64_t(h);
    tot.oracle = true;
  }
  const Motion m = motion_of(s);
  tot.motion.max = std::max(tot.motion.max, m.max);
  tot.motion.mean += m.mean;
  ++tot.steps;
  tot.refit_swept_ms += median(refit_swept);
  tot.refit_ms += median(refit);
  for (int c = 0; c < kContestants; ++c) tot.ms[c] += median(times[c]);
  for (int c = 0; c < 3; ++c) tot.vt[c] += vt_sets[c].size();
  tot.ee[kEeBox] += ee_box.size();
  tot.vt[kStatic0] += stat_vt[0];
  tot.ee[kStatic0] += stat_ee[0];
  tot.vt[kStatic1] += stat_vt[1];
  tot.ee[kStatic1] += stat_ee[1];
}

struct SweptSummary {
  std::vector<double> cand[2], speed[2], ee_static;  // capsule_ray, capsule_exact against box; EE swept / static
};

std::string swept_rows(const std::string& name, const std::string& what, const SweptTotals& t, float r, SweptSummary& sum,
                       std::string& ee_row) {
  const double box = double(t.vt[kVtBox]);
  auto rel = [&](int c) { return box > 0 ? fmt(double(t.vt[c]) / box, 3) + "x" : std::string("–"); };
  auto speed = [&](int c) { return fmt(t.ms[kVtBox] / t.ms[c], 3) + "x"; };
  std::ostringstream o;
  o << "| " << name << " | " << what << " | " << t.steps << " | " << fmt(t.motion.max / double(r), 3) << " / "
    << fmt(t.motion.mean / double(t.steps) / double(r), 3) << " | " << t.vt[kVtBox] << " | " << fmt(t.ms[kVtBox], 3)
    << " | " << t.vt[kVtRay] << " (" << rel(kVtRay) << ") | " << fmt(t.ms[kVtRay], 3) << " (" << speed(kVtRay) << ") | "
    << t.vt[kVtExact] << " (" << rel(kVtExact) << ") | " << fmt(t.ms[kVtExact], 3) << " (" << speed(kVtExact) << ") | "
    << (t.oracle ? std::to_string(t.vt_confirmed) + " (" + (box > 0 ? fmt(double(t.vt_confirmed) / box, 3) : "–") + " of box, " +
                       (t.vt[kVtExact] ? fmt(double(t.vt_confirmed) / double(t.vt[kVtExact]), 3) : "–") +
                       " of capsule_exact; " + std::to_string(t.fn) + " missing)"
                 : std::string("not run"))
    << " |\n";
  if (box > 0)
    for (int j = 0; j < 2; ++j) {
      sum.cand[j].push_back(double(t.vt[kVtRay + j]) / box);
      sum.speed[j].push_back(t.ms[kVtBox] / t.ms[kVtRay + j]);
    }
  std::ostringstream e;
  const double ee = double(t.ee[kEeBox]), ee1 = double(t.ee[kStatic1]);
  e << "| " << name << " | " << t.steps << " | " << fmt(t.refit_swept_ms, 3) << " (" << fmt(t.refit_swept_ms / t.refit_ms, 3)
    << "x) | " << t.ee[kEeBox] << " | " << fmt(t.ms[kEeBox], 3) << " | "
    << (t.oracle ? std::to_string(t.ee_confirmed) + " (" + (ee > 0 ? fmt(double(t.ee_confirmed) / ee, 3) : "–") + ")"
                 : std::string("not run"))
    << " | " << t.vt[kStatic0] << " + " << t.ee[kStatic0] << " | " << fmt(t.ms[kStatic0], 3) << " | " << t.vt[kStatic1]
    << " + " << t.ee[kStatic1] << " | " << fmt(t.ms[kStatic1], 3) << " | "
    << (t.vt[kStatic1] ? fmt(box / double(t.vt[kStatic1]), 3) + "x" : "–") << " / " << (ee1 > 0 ? fmt(ee / ee1, 3) + "x" : "–")
    << " | " << fmt((t.ms[kVtBox] + t.ms[kEeBox]) / t.ms[kStatic1], 3) << "x |\n";
  if (ee1 > 0) sum.ee_static.push_back(ee / ee1);
  ee_row += e.str();
  return o.str();
}

// Every step of a scene's frames (frame k -> k + 1); scenes created at frame 0 and refit, as
// the other tables do.
SweptTotals compare_swept(minkq_device* device, const SceneFrames& sc, const std::vector<Step>& steps, int repeats,
                          int samples, bool& ok) {
  const float r = scene_radius(sc);
  std::fprintf(stderr, "%s (swept): %zu V, %zu T, %zu steps, r = %.4g\n", sc.name.c_str(), sc.mesh.vertex_count(),
               sc.mesh.triangle_count(), steps.size(), double(r));
  Scene swept = create(device, *steps.front().x0, sc.mesh.tris), fixed = create(device, *steps.front().x0, sc.mesh.tris);
  SweptTotals tot;
  for (const Step& s : steps) run_step(swept.get(), fixed.get(), sc, s, r, repeats, samples, tot, ok);
  if (tot.fn) {
    std::fprintf(stderr, "FAIL %s: %llu sampled swept contacts missing from capsule modes\n", sc.name.c_str(),
                 static_cast<unsigned long long>(tot.fn));
    ok = false;
  }
  return tot;
}

// The twisted sheet (256^2, 3 turns) under one rigid step: a rotation about the axis (1, 2, 3)
// through its centre and a translation along (1, 1, 1), each moving a vertex by at most m r / 2.
std::vector<float> rigid_step(const std::vector<float>& x, double m, double r) {
  const double c[3] = {0.5, 0.0, 0.0};
  double a[3] = {1, 2, 3};
  const double al = std::sqrt(14.0);
  for (double& v : a) v /= al;
  double far = 0;  // largest distance from the axis
  const size_t n = x.size() / 3;
  for (size_t i = 0; i < n; ++i) {
    double p[3], d = 0;
    for (int k = 0; k < 3; ++k) p[k] = double(x[3 * i + size_t(k)]) - c[k];
    const double along = p[0] * a[0] + p[1] * a[1] + p[2] * a[2];
    for (int k = 0; k < 3; ++k) d += (p[k] - along * a[k]) * (p[k] - along * a[k]);
    far = std::max(far, std::sqrt(d));
  }
  const double half = 0.5 * m * r, theta = 2 * std::asin(std::min(1.0, half / (2 * far)));  // chord = half
  const double ct = std::cos(theta), st = std::sin(theta), tr = half / std::sqrt(3.0);
  std::vector<float> y(x.size());
  for (size_t i = 0; i < n; ++i) {
    double p[3];
    for (int k = 0; k < 3; ++k) p[k] = double(x[3 * i + size_t(k)]) - c[k];
    const double dot = p[0] * a[0] + p[1] * a[1] + p[2] * a[2];
    const double cr[3] = {a[1] * p[2] - a[2] * p[1], a[2] * p[0] - a[0] * p[2], a[0] * p[1] - a[1] * p[0]};
    for (int k = 0; k < 3; ++k)  // Rodrigues
      y[3 * i + size_t(k)] = float(p[k] * ct + cr[k] * st + a[k] * dot * (1 - ct) + c[k] + tr);
  }
  return y;
}

}  // namespace

std::string swept_report(const SuiteRun& run, bool& ok) {
  const double load0 = load_average();
  // Procedural scenes: 21 frames (20 steps of 5% of the motion); the twisted sheet: 4 frames
  // (its frame k has 3 - 0.05 k turns: 3 steps of 0.05 turns). --quick: the first step of
  // each procedural scene, and the rigid step on a 8k-triangle sheet.
  const int frames = 21, sheet_frames = 4, samples = 16;
  SweptSummary summary;
  std::string vt_rows, ee_rows;
  std::vector<std::string> names = procedural_scene_names();
  if (!run.quick) names.push_back("twist_target");
  for (const std::string& name : names) {
    const SceneFrames sc = make_scene(name, 0, name == "twist_target" ? sheet_frames : frames, run.data);
    std::vector<Step> steps;
    for (size_t k = 0; k + 1 < sc.frames.size() && !(run.quick && k > 0); ++k) steps.push_back({&sc.frames[k], &sc.frames[k + 1]});
    const SweptTotals t = compare_swept(run.device, sc, steps, run.repeats, samples, ok);
    const std::string what = "frames k -> k + 1 of " + std::to_string(sc.frames.size());
    vt_rows += swept_rows(sc.name, what, t, scene_radius(sc), summary, ee_rows);
  }
  SweptSummary rigid;
  {
    SceneFrames sheet = make_scene("twist_target", run.quick ? 8000 : 0, 1, run.data);
    const float r = scene_radius(sheet);
    const int n = int(std::lround(std::sqrt(double(sheet.mesh.vertex_count()))));
    for (const double m : run.quick ? std::vector<double>{2} : std::vector<double>{0.5, 2, 8}) {
      const std::vector<float> x1 = rigid_step(sheet.frames[0], m, r);
      const std::vector<Step> steps = {{&sheet.frames[0], &x1}};
      SceneFrames named = sheet;
      named.name = "twisted sheet " + std::to_string(n) + "^2, rigid step " + fmt(m, 3) + " r";
      const SweptTotals t = compare_swept(run.device, named, steps, run.repeats, samples, ok);
      vt_rows += swept_rows(named.name, "rotation + translation, one step", t, r, rigid, ee_rows);
    }
  }
  std::ostringstream o;
  o << "# Swept queries: what the capsule path test saves\n\nMachine: " << run.machine << ". Load average (1 min) at start "
    << fmt(load0, 3) << ", at write " << fmt(load_average(), 3) << ". Written " << utc_now() << " by " << run.by << ".\n\n"
    << "Swept steps through the C API on the CPU device (all threads): a VT + EE scene (incident pairs dropped) "
    << "created at the first position and refit to each step with minkq_scene_refit_swept(x0, x1); its queries "
    << "report the pairs that come within r at some t in [0, 1]. The procedural scenes over " << frames
    << " frames of their motion (every consecutive pair of frames a step: 5% of the motion; figures summed over "
    << "the steps" << (run.quick ? "; --quick: the first step only" : "") << "), "
    << (run.quick ? "" : "REFERENCES.md's twisted sheet over its frames 0-3 (3 - 0.05 k turns: 3 steps), ")
    << "and the twisted sheet (3 turns" << (run.quick ? ", 8k triangles in --quick" : "") << ") under one rigid step (rotation about the axis (1, 2, 3) "
    << "through (0.5, 0, 0) and translation along (1, 1, 1), each moving a vertex by at most m r / 2). r = the "
    << "scene's radius. VT modes: box (the path's box grown by r), capsule_ray (the path against the r-inflated "
    << "boxes, slab test) and capsule_exact (segment-box distance; the sphere mode gives the same pairs, checked); "
    << "EE: box. For context the static box queries (VT + EE) of a second scene refit to x0 and to x1. Per step, "
    << "every contestant runs round-robin, one warm-up round then " << run.repeats << " rounds (the refits in each "
    << "round too); ms = the sum over the steps of each step's median. 'x box' = candidates over VT box's; speed = "
    << "VT box ms / this ms (> 1: faster than box). Motion = the largest and the mean vertex displacement of a "
    << "step, over r. Sampled oracle: each box candidate's distance (reference oracle, long double) at " << samples + 1
    << " evenly spaced t, positions x0 + t (x1 - x0) in double: a candidate within r at one of them surely comes "
    << "within r during the step (a lower bound of the true swept contacts); every such VT pair must be in the "
    << "capsule modes' sets (checked: 'missing'), and capsule_exact within capsule_ray within box.\n\n"
    << "## Geomeans\n\n| scenes | VT capsule_ray candidates / box | VT capsule_ray speed over box | "
       "VT capsule_exact candidates / box | VT capsule_exact speed over box | EE swept box candidates / static at x1 |\n"
    << "|---|---|---|---|---|---|\n";
  for (const auto& [label, s] : {std::pair<std::string, const SweptSummary*>{"procedural scenes, their frames", &summary},
                                 {"twisted sheet, rigid steps", &rigid}})
    o << "| " << label << " (" << s->cand[0].size() << ") | " << fmt(geomean(s->cand[0]), 3) << "x | "
      << fmt(geomean(s->speed[0]), 3) << "x | " << fmt(geomean(s->cand[1]), 3) << "x | " << fmt(geomean(s->speed[1]), 3)
      << "x | " << fmt(geomean(s->ee_static), 3) << "x |\n";
  o << "\n## VT: box, capsule_ray, capsule_exact\n\n"
    << "| scene | step | steps | motion / r (max / mean) | VT box candidates | VT box ms | capsule_ray candidates (x box) "
       "| capsule_ray ms (speed) | capsule_exact candidates (x box) | capsule_exact ms (speed) | sampled oracle: VT box "
       "candidates confirmed |\n|---|---|---|---|---|---|---|---|---|---|---|\n"
    << vt_rows
    << "\n## EE box, refits, and the static queries at x0 and x1\n\n"
    << "refit: minkq_scene_refit_swept ms (over minkq_scene_refit's, the mean of the refits to x0 and x1). "
       "Static: box candidates VT + EE and the two queries' ms. Last columns: swept box candidates over static at "
       "x1 (VT / EE), and swept VT + EE box ms over static at x1.\n\n"
    << "| scene | steps | refit_swept ms (x refit) | EE swept box candidates | EE swept box ms | sampled oracle: EE "
       "confirmed (share) | static at x0: candidates | ms | static at x1: candidates | ms | swept / static "
       "candidates (VT / EE) | swept / static ms |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n"
    << ee_rows << "\nLoad average at end " << fmt(load_average(), 3) << ".\n";
  return o.str();
}

}  // namespace minkq::bench::suites
