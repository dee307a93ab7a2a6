// minkq_bench's float64 suite (float64.md): each scene as float32, as MINKQ_SCENE_FLOAT64
// doubles equal to the floats (rho = 0) and as the floats plus a sub-ulp perturbation (rho > 0),
// timed round-robin (create, refit, VT + EE box and leaf_exact queries), with the checks that
// rho = 0 gives float32's pairs, rho > 0 a superset, and the double oracle's contacts lie in the
// float64 leaf_exact set. It shares only the helpers of suites.h with the other suites.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "suites/suites.h"

namespace minkq::bench::suites {
namespace {

// ---- float64 ------------------------------------------------------------------------------

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

}  // namespace

std::string float64_report(const SuiteRun& run, bool& ok) {
  const double load0 = load_average();
  std::ostringstream o;
  Float64Summary proc, real, offsets;
  std::string rows;
  for (const std::string& name : procedural_scene_names())
    rows += compare_float64(run.device, make_scene(name, 0, 2, run.data), run.repeats, true, proc, ok);
  if (!run.quick) {
    const SceneFrames sheet = make_scene("twist_target", 0, 2, run.data);
    rows += compare_float64(run.device, sheet, run.repeats, true, proc, ok);
    for (const RealMesh& m : available_real_meshes(run.data))
      rows += compare_float64(run.device, load_real_scene(m, run.data), run.repeats, true, real, ok);
    for (const double offset : {1e3, 1e4})
      rows += compare_float64(run.device, offset_scene(sheet, offset), run.repeats, true, offsets, ok);
  }
  o << "# The double path's cost against float32 on the same scenes\n\nMachine: " << run.machine
    << ". Load average (1 min) at start " << fmt(load0, 3) << ", at write " << fmt(load_average(), 3) << ". Written "
    << utc_now() << " by " << run.by << ".\n\n"
    << "Each scene three ways through the C API on the CPU device (all threads), VT + EE scenes with incident pairs "
    << "dropped, r = the scene's radius (procedural scenes: the Newton margin; real meshes: 0.25 x mean edge): "
    << "**float32**, the benchmark's float positions; **float64 = the floats**, those floats as doubles "
    << "(MINKQ_SCENE_FLOAT64; rounding moves nothing, rho = 0, r kept); **float64, floats + sub-ulp**, each "
    << "coordinate moved by a uniform fraction in (-0.49, 0.49) of the gap to the neighbouring float on that side "
    << "(rounding gives the same floats back, so the trees are the float32 ones and only the double input and the "
    << "radius r + 2 rho differ). Each scene is created at its first frame and refit to its last (real meshes: "
    << "their one frame, refit to itself), then queried there: VT + EE in box mode (candidates) and with "
    << "MINKQ_QUERY_LEAF_EXACT (contacts), two calls each into reused results. The three run round-robin, one "
    << "warm-up round then " << run.repeats << " rounds (each round: create, refit, box queries, leaf_exact queries of "
    << "every variant); ms = the median over the rounds; 'x f32' = this variant's ms (or count) over float32's in the "
    << "same run (> 1: the double path costs more). rho / r: the farthest the rounding moved a vertex (Euclidean, "
    << "over both frames), over r. Checked: rho = 0 gives exactly float32's pairs (every query), rho > 0 a superset, "
    << "and the double oracle's contacts (reference::vt/ee_contacts, long double on the perturbed doubles at r) all "
    << "lie in the float64 leaf_exact set" << (run.quick ? " (--quick: the eight procedural scenes only)" : "")
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
  return o.str();
}

}  // namespace minkq::bench::suites
