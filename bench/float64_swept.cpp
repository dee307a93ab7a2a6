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
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include "common.h"
#include "scenes.h"

namespace ref = minkq::reference;
using namespace minkq::bench;

namespace {

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double geomean(const std::vector<double>& v) {
  if (v.empty()) return NAN;
  double s = 0;
  for (double x : v) s += std::log(x);
  return std::exp(s / double(v.size()));
}

std::string utc_now() {
  char when[64];
  const std::time_t now = std::time(nullptr);
  std::strftime(when, sizeof when, "%Y-%m-%d %H:%M UTC", std::gmtime(&now));
  return when;
}

float scene_radius(const SceneFrames& sc) { return float(sc.radius_factor * sc.mean_edge); }

// ---- Scenes through the C API ----------------------------------------------------------------

constexpr uint32_t kFlags = MINKQ_SCENE_VT | MINKQ_SCENE_EE | MINKQ_SCENE_DROP_INCIDENT;

minkq_buffer buffer_of(const std::vector<float>& x) { return host_buffer(x.data(), x.size() / 3, 12); }
minkq_buffer buffer_of(const std::vector<double>& x) { return host_buffer(x.data(), x.size() / 3, 24); }

template <class T>
Scene create(minkq_device* device, const std::vector<T>& xyz, const std::vector<int32_t>& tris) {
  minkq_scene_desc desc{};
  desc.flags = kFlags | (std::is_same<T, double>::value ? uint32_t(MINKQ_SCENE_FLOAT64) : 0u);
  desc.vertices = buffer_of(xyz);
  desc.triangles = host_buffer(tris.data(), tris.size() / 3, 12);
  desc.edges = host_buffer(nullptr, 0);
  return new_scene(device, desc);
}

PairSet pairs_of(const minkq_result* r) { return to_set(minkq_result_pairs(r), minkq_result_count(r)); }

void query(minkq_scene* scene, minkq_query_kind kind, minkq_mode mode, uint32_t flags, float r, minkq_result* out) {
  const minkq_query_desc q{kind, mode, flags, r};
  check(minkq_scene_query_result(scene, &q, out), "minkq_scene_query_result");
}

bool includes(const PairSet& big, const PairSet& small) {
  return std::includes(big.begin(), big.end(), small.begin(), small.end());
}

// splitmix64 -> [0, 1)
struct Random {
  uint64_t state;
  double next() {
    uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return double((z ^ (z >> 31)) >> 11) * 0x1p-53;
  }
};

// ---- float64 ------------------------------------------------------------------------------

// The floats as doubles, each coordinate moved by a uniform fraction in (-0.49, 0.49) of the gap
// to its neighbouring float on that side: rounding to nearest gives the floats back.
std::vector<double> perturbed(const std::vector<float>& x, uint64_t seed) {
  Random rng{seed};
  std::vector<double> d(x.size());
  for (size_t i = 0; i < x.size(); ++i) {
    const double u = 0.98 * rng.next() - 0.49;
    const float f = x[i];
    const double gap = u >= 0 ? double(std::nextafter(f, HUGE_VALF)) - double(f) : double(f) - double(std::nextafter(f, -HUGE_VALF));
    d[i] = double(f) + u * gap;
    if (float(d[i]) != f) throw std::logic_error("perturbed: a coordinate rounds elsewhere");
  }
  return d;
}

// The farthest rounding to float moves a vertex (Euclidean; the library rounds its rho up).
double rho_of(const std::vector<double>& d) {
  double rho = 0;
  for (size_t i = 0; i < d.size(); i += 3) {
    double s = 0;
    for (int k = 0; k < 3; ++k) {
      const double e = d[i + size_t(k)] - double(float(d[i + size_t(k)]));
      s += e * e;
    }
    rho = std::max(rho, std::sqrt(s));
  }
  return rho;
}

struct Float64Row {
  std::string variant;
  double rho = 0;
  double create_ms = 0, refit_ms = 0, box_ms = 0, exact_ms = 0;
  uint64_t vt_box = 0, ee_box = 0, vt_contacts = 0, ee_contacts = 0;
};

struct Float64Summary {  // ratios float64 / float32 per scene, for the geomeans
  std::vector<double> create[2], refit[2], box[2], exact[2], candidates[2], contacts[2];
};

// One scene: created at its first frame, refit to its last, queried there (real meshes: the one
// frame twice). Variants: float32, float64 = the floats, float64 = the floats + sub-ulp.
std::string compare_float64(minkq_device* device, const SceneFrames& sc, int repeats, bool oracle, Float64Summary& sum,
                            bool& ok) {
  const float r = scene_radius(sc);
  const std::vector<float>& f0 = sc.frames.front();
  const std::vector<float>& f1 = sc.frames.back();
  std::fprintf(stderr, "%s (float64): %zu V, %zu T, r = %.4g\n", sc.name.c_str(), sc.mesh.vertex_count(),
               sc.mesh.triangle_count(), double(r));
  const std::vector<double> d0(f0.begin(), f0.end()), d1(f1.begin(), f1.end());
  const std::vector<double> p0 = perturbed(f0, 17), p1 = perturbed(f1, 29);
  const double rho = std::max(rho_of(p0), rho_of(p1));
  constexpr int kVariants = 3;
  const char* labels[kVariants] = {"float32", "float64, doubles = the floats (rho = 0)", "float64, floats + sub-ulp"};
  struct Timed {
    std::vector<double> create, refit, box, exact;
  } times[kVariants];
  Result vt[kVariants], ee[kVariants];
  for (int i = 0; i < kVariants; ++i) vt[i] = new_result(), ee[i] = new_result();
  // One run of variant i: create (timed), refit (timed), VT + EE box, VT + EE leaf_exact.
  Scene kept[kVariants];
  auto once = [&](int i, bool record) {
    double t = now_ms();
    Scene s = i == 0 ? create(device, f0, sc.mesh.tris) : create(device, i == 1 ? d0 : p0, sc.mesh.tris);
    const double create_ms = now_ms() - t;
    t = now_ms();
    check(minkq_scene_refit(s.get(), i == 0 ? buffer_of(f1) : buffer_of(i == 1 ? d1 : p1)), "minkq_scene_refit");
    const double refit_ms = now_ms() - t;
    t = now_ms();
    query(s.get(), MINKQ_QUERY_VT, MINKQ_MODE_BOX, 0, r, vt[i].get());
    query(s.get(), MINKQ_QUERY_EE, MINKQ_MODE_BOX, 0, r, ee[i].get());
    const double box_ms = now_ms() - t;
    t = now_ms();
    query(s.get(), MINKQ_QUERY_VT, MINKQ_MODE_BOX, MINKQ_QUERY_LEAF_EXACT, r, vt[i].get());
    query(s.get(), MINKQ_QUERY_EE, MINKQ_MODE_BOX, MINKQ_QUERY_LEAF_EXACT, r, ee[i].get());
    const double exact_ms = now_ms() - t;
    if (record) {
      times[i].create.push_back(create_ms);
      times[i].refit.push_back(refit_ms);
      times[i].box.push_back(box_ms);
      times[i].exact.push_back(exact_ms);
    }
    kept[i] = std::move(s);
  };
  for (int round = 0; round <= repeats; ++round)
    for (int i = 0; i < kVariants; ++i) {
      kept[i].reset();
      once(i, round > 0);  // round 0: the warm-up
    }
  // Counts and pair sets, untimed.
  Float64Row rows[kVariants];
  PairSet sets[kVariants][4];  // VT box, EE box, VT contacts, EE contacts
  for (int i = 0; i < kVariants; ++i) {
    minkq_scene* s = kept[i].get();
    int k = 0;
    for (const uint32_t flags : {0u, uint32_t(MINKQ_QUERY_LEAF_EXACT)}) {
      query(s, MINKQ_QUERY_VT, MINKQ_MODE_BOX, flags, r, vt[i].get());
      sets[i][k] = pairs_of(vt[i].get());
      query(s, MINKQ_QUERY_EE, MINKQ_MODE_BOX, flags, r, ee[i].get());
      sets[i][k + 1] = pairs_of(ee[i].get());
      k += 2;
    }
    Float64Row& row = rows[i];
    row.variant = labels[i];
    row.rho = i == 2 ? rho : 0;
    row.create_ms = median(times[i].create);
    row.refit_ms = median(times[i].refit);
    row.box_ms = median(times[i].box);
    row.exact_ms = median(times[i].exact);
    row.vt_box = sets[i][0].size();
    row.ee_box = sets[i][1].size();
    row.vt_contacts = sets[i][2].size();
    row.ee_contacts = sets[i][3].size();
  }
  for (int k = 0; k < 4; ++k) {
    if (sets[1][k] != sets[0][k]) {
      std::fprintf(stderr, "FAIL %s: float64 (rho = 0) pairs differ from float32 (query %d)\n", sc.name.c_str(), k);
      ok = false;
    }
    if (!includes(sets[2][k], sets[0][k])) {
      std::fprintf(stderr, "FAIL %s: float64 (rho > 0) pairs miss float32 ones (query %d)\n", sc.name.c_str(), k);
      ok = false;
    }
  }
  std::string oracle_text = "not run";
  if (oracle) {
    ref::Mesh m = sc.mesh;
    ref::set_float64(m, p1);
    const double start = now_ms();
    const PairSet vt_true = to_set(ref::vt_contacts(m, double(r), true)), ee_true = to_set(ref::ee_contacts(m, double(r), true));
    const uint64_t fn = missing(vt_true, sets[2][2]) + missing(ee_true, sets[2][3]);
    if (fn) {
      std::fprintf(stderr, "FAIL %s: %llu double contacts missing from the float64 leaf_exact sets\n", sc.name.c_str(),
                   static_cast<unsigned long long>(fn));
      ok = false;
    }
    oracle_text = std::to_string(vt_true.size()) + " VT + " + std::to_string(ee_true.size()) + " EE, " +
                  std::to_string(fn) + " missing (" + fmt((now_ms() - start) / 1000, 3) + " s)";
  }
  // Rows.
  auto ratio = [](double a, double b, int digits = 3) { return b > 0 ? fmt(a / b, digits) + "x" : std::string("–"); };
  std::ostringstream o;
  const Float64Row& base = rows[0];
  for (int i = 0; i < kVariants; ++i) {
    const Float64Row& x = rows[i];
    const double cand = double(x.vt_box + x.ee_box), cand0 = double(base.vt_box + base.ee_box);
    const double cont = double(x.vt_contacts + x.ee_contacts), cont0 = double(base.vt_contacts + base.ee_contacts);
    o << "| " << sc.name << " | " << x.variant << " | " << (i == 0 ? "–" : fmt(x.rho / double(r), 3)) << " | "
      << fmt(x.create_ms, 3) << " | " << (i ? ratio(x.create_ms, base.create_ms) : "1x") << " | " << fmt(x.refit_ms, 3)
      << " | " << (i ? ratio(x.refit_ms, base.refit_ms) : "1x") << " | " << fmt(x.box_ms, 3) << " | "
      << (i ? ratio(x.box_ms, base.box_ms) : "1x") << " | " << fmt(x.exact_ms, 3) << " | "
      << (i ? ratio(x.exact_ms, base.exact_ms) : "1x") << " | " << x.vt_box << " + " << x.ee_box << " | "
      << (i ? ratio(cand, cand0, 4) : "1x") << " | " << x.vt_contacts << " + " << x.ee_contacts << " | "
      << (i ? ratio(cont, cont0, 4) : "1x") << " | " << (i == 2 ? oracle_text : "") << " |\n";
    if (i) {
      const int j = i - 1;
      sum.create[j].push_back(x.create_ms / base.create_ms);
      sum.refit[j].push_back(x.refit_ms / base.refit_ms);
      sum.box[j].push_back(x.box_ms / base.box_ms);
      sum.exact[j].push_back(x.exact_ms / base.exact_ms);
      if (cand0 > 0) sum.candidates[j].push_back(cand / cand0);
      if (cont0 > 0) sum.contacts[j].push_back(cont / cont0);
    }
  }
  return o.str();
}

std::string float64_summary_rows(const std::string& set, const Float64Summary& s) {
  std::ostringstream o;
  const char* variants[2] = {"float64, rho = 0", "float64, floats + sub-ulp"};
  for (int j = 0; j < 2; ++j)
    o << "| " << set << " (" << s.create[j].size() << ") | " << variants[j] << " | " << fmt(geomean(s.create[j]), 3)
      << "x | " << fmt(geomean(s.refit[j]), 3) << "x | " << fmt(geomean(s.box[j]), 3) << "x | "
      << fmt(geomean(s.exact[j]), 3) << "x | " << fmt(geomean(s.candidates[j]), 4) << "x | "
      << fmt(geomean(s.contacts[j]), 4) << "x |\n";
  return o.str();
}

// The twisted sheet moved away from the origin: x -> x + offset, in double, rounded to float.
SceneFrames offset_scene(SceneFrames sc, double offset) {
  for (auto& f : sc.frames)
    for (float& x : f) x = float(double(x) + offset);
  sc.mesh.xyz = sc.frames.front();
  char name[64];
  std::snprintf(name, sizeof name, "%s + %g", sc.name.c_str(), offset);
  sc.name = name;
  return sc;  // mean edge and r kept from the sheet at the origin
}

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
      const double load0 = load_average(), started = now_ms();
      std::ostringstream o;
      Float64Summary proc, real, offsets;
      std::string rows;
      for (const std::string& name : procedural_scene_names())
        rows += compare_float64(device.get(), make_scene(name, 0, 2, data), repeats, true, proc, ok);
      if (!quick) {
        const SceneFrames sheet = make_scene("twist_target", 0, 2, data);
        rows += compare_float64(device.get(), sheet, repeats, true, proc, ok);
        for (const RealMesh& m : available_real_meshes(data))
          rows += compare_float64(device.get(), load_real_scene(m, data), repeats, true, real, ok);
        for (const double offset : {1e3, 1e4})
          rows += compare_float64(device.get(), offset_scene(sheet, offset), repeats, true, offsets, ok);
      }
      o << "# The double path's cost against float32 on the same scenes\n\nMachine: " << machine
        << ". Load average (1 min) at start " << fmt(load0, 3) << ", at write " << fmt(load_average(), 3) << ". Written "
        << utc_now() << " by " << by << ".\n\n"
        << "Each scene three ways through the C API on the CPU device (all threads), VT + EE scenes with incident pairs "
        << "dropped, r = the scene's radius (procedural scenes: the Newton margin; real meshes: 0.25 x mean edge): "
        << "**float32**, the benchmark's float positions; **float64 = the floats**, those floats as doubles "
        << "(MINKQ_SCENE_FLOAT64; rounding moves nothing, rho = 0, r kept); **float64, floats + sub-ulp**, each "
        << "coordinate moved by a uniform fraction in (-0.49, 0.49) of the gap to the neighbouring float on that side "
        << "(rounding gives the same floats back, so the trees are the float32 ones and only the double input and the "
        << "radius r + 2 rho differ). Each scene is created at its first frame and refit to its last (real meshes: "
        << "their one frame, refit to itself), then queried there: VT + EE in box mode (candidates) and with "
        << "MINKQ_QUERY_LEAF_EXACT (contacts), two calls each into reused results. The three run round-robin, one "
        << "warm-up round then " << repeats << " rounds (each round: create, refit, box queries, leaf_exact queries of "
        << "every variant); ms = the median over the rounds; 'x f32' = this variant's ms (or count) over float32's in the "
        << "same run (> 1: the double path costs more). rho / r: the farthest the rounding moved a vertex (Euclidean, "
        << "over both frames), over r. Checked: rho = 0 gives exactly float32's pairs (every query), rho > 0 a superset, "
        << "and the double oracle's contacts (reference::vt/ee_contacts, long double on the perturbed doubles at r) all "
        << "lie in the float64 leaf_exact set" << (quick ? " (--quick: the eight procedural scenes only)" : "")
        << ". The last two rows move the twisted sheet to x + 1e3 and x + 1e4 (floats there, same r), where a float "
        << "ulp is no longer small against r.\n\n"
        << "## Geomeans of the ratios float64 / float32\n\n"
        << "| scenes | variant | create | refit | VT+EE box | VT+EE leaf_exact | box candidates | contacts |\n"
        << "|---|---|---|---|---|---|---|---|\n"
        << float64_summary_rows("procedural + twisted sheet", proc);
      if (!real.create[0].empty()) o << float64_summary_rows("real meshes", real);
      if (!offsets.create[0].empty()) o << float64_summary_rows("twisted sheet at +1e3, +1e4", offsets);
      o << "\n## Per scene\n\n"
        << "| scene | variant | rho / r | create ms | x f32 | refit ms | x f32 | VT+EE box ms | x f32 | VT+EE leaf_exact ms | "
           "x f32 | box candidates VT + EE | x f32 | contacts VT + EE | x f32 | double oracle (at r) |\n"
        << "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n"
        << rows << "\nLoad average at end " << fmt(load_average(), 3) << ".\n";
      write("float64.md", o.str());
      std::fprintf(stderr, "float64: %.1f s\n", (now_ms() - started) / 1000);
    }

    if (sections == "all" || sections == "swept") {
      const double load0 = load_average(), started = now_ms();
      // Procedural scenes: 21 frames (20 steps of 5% of the motion); the twisted sheet: 4 frames
      // (its frame k has 3 - 0.05 k turns: 3 steps of 0.05 turns). --quick: the first step of
      // each procedural scene, and the rigid step on a 8k-triangle sheet.
      const int frames = 21, sheet_frames = 4, samples = 16;
      SweptSummary summary;
      std::string vt_rows, ee_rows;
      std::vector<std::string> names = procedural_scene_names();
      if (!quick) names.push_back("twist_target");
      for (const std::string& name : names) {
        const SceneFrames sc = make_scene(name, 0, name == "twist_target" ? sheet_frames : frames, data);
        std::vector<Step> steps;
        for (size_t k = 0; k + 1 < sc.frames.size() && !(quick && k > 0); ++k) steps.push_back({&sc.frames[k], &sc.frames[k + 1]});
        const SweptTotals t = compare_swept(device.get(), sc, steps, repeats, samples, ok);
        const std::string what = "frames k -> k + 1 of " + std::to_string(sc.frames.size());
        vt_rows += swept_rows(sc.name, what, t, scene_radius(sc), summary, ee_rows);
      }
      SweptSummary rigid;
      {
        SceneFrames sheet = make_scene("twist_target", quick ? 8000 : 0, 1, data);
        const float r = scene_radius(sheet);
        const int n = int(std::lround(std::sqrt(double(sheet.mesh.vertex_count()))));
        for (const double m : quick ? std::vector<double>{2} : std::vector<double>{0.5, 2, 8}) {
          const std::vector<float> x1 = rigid_step(sheet.frames[0], m, r);
          const std::vector<Step> steps = {{&sheet.frames[0], &x1}};
          SceneFrames named = sheet;
          named.name = "twisted sheet " + std::to_string(n) + "^2, rigid step " + fmt(m, 3) + " r";
          const SweptTotals t = compare_swept(device.get(), named, steps, repeats, samples, ok);
          vt_rows += swept_rows(named.name, "rotation + translation, one step", t, r, rigid, ee_rows);
        }
      }
      std::ostringstream o;
      o << "# Swept queries: what the capsule path test saves\n\nMachine: " << machine << ". Load average (1 min) at start "
        << fmt(load0, 3) << ", at write " << fmt(load_average(), 3) << ". Written " << utc_now() << " by " << by << ".\n\n"
        << "Swept steps through the C API on the CPU device (all threads): a VT + EE scene (incident pairs dropped) "
        << "created at the first position and refit to each step with minkq_scene_refit_swept(x0, x1); its queries "
        << "report the pairs that come within r at some t in [0, 1]. The procedural scenes over " << frames
        << " frames of their motion (every consecutive pair of frames a step: 5% of the motion; figures summed over "
        << "the steps" << (quick ? "; --quick: the first step only" : "") << "), "
        << (quick ? "" : "REFERENCES.md's twisted sheet over its frames 0-3 (3 - 0.05 k turns: 3 steps), ")
        << "and the twisted sheet (3 turns" << (quick ? ", 8k triangles in --quick" : "") << ") under one rigid step (rotation about the axis (1, 2, 3) "
        << "through (0.5, 0, 0) and translation along (1, 1, 1), each moving a vertex by at most m r / 2). r = the "
        << "scene's radius. VT modes: box (the path's box grown by r), capsule_ray (the path against the r-inflated "
        << "boxes, slab test) and capsule_exact (segment-box distance; the sphere mode gives the same pairs, checked); "
        << "EE: box. For context the static box queries (VT + EE) of a second scene refit to x0 and to x1. Per step, "
        << "every contestant runs round-robin, one warm-up round then " << repeats << " rounds (the refits in each "
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
      write("swept.md", o.str());
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
