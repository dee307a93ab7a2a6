// minkq_hr_study: candidate drop of the sphere and capsule node tests against the padded box,
// as a function of h/r (primitive box half-size over query radius), on 3-D-spread synthetic
// boxes (the user-box BVH API) and on cloth (the scene API), beside the reference figures of
// the prototype (46.8% sphere and 51.7% capsule drop on 3-D-spread inputs).
#include <tbb/global_control.h>

#include <cinttypes>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "common.h"
#include "scenes.h"

namespace fs = std::filesystem;
namespace ref = minkq::reference;
using namespace minkq::bench;

namespace {

constexpr double kPi = 3.14159265358979323846;

struct Rng {
  uint64_t state;
  double uniform() {  // splitmix64 -> [0, 1)
    uint64_t z = (state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return double((z ^ (z >> 31)) >> 11) * 0x1p-53;
  }
};

// Padded-box volume and sphere-swept volume of a cube of side a = 2h: Steiner's formula. The
// expected sphere/box candidate ratio for uniformly spread points is their quotient.
double theory_sphere_drop(double h_over_r) {
  const double a = 2 * h_over_r, r = 1;
  const double swept = a * a * a + 6 * a * a * r + 3 * kPi * a * r * r + 4.0 / 3.0 * kPi * r * r * r;
  const double padded = (a + 2 * r) * (a + 2 * r) * (a + 2 * r);
  return 100.0 * (1 - swept / padded);
}

struct Line {
  std::string input, query, mode;
  double h_over_r, drop_percent, ms, box_ms;
  uint64_t candidates, box_candidates;
};

// One user-box query, timed; returns the candidate count. Output through the capacity
// protocol into a host buffer that grows once.
uint64_t bvh_query(minkq_bvh* bvh, minkq_shape shape, minkq_mode mode, float r, const std::vector<float>& a,
                   const std::vector<float>& b, std::vector<int32_t>& out, double& ms, int repeats) {
  minkq_bvh_query_desc q{};
  q.shape = shape, q.mode = mode, q.flags = 0, q.radius = r;
  q.first = {a.data(), 12, a.size() / 3, MINKQ_MEMORY_HOST};
  q.second = {b.empty() ? nullptr : b.data(), 12, b.size() / 3, MINKQ_MEMORY_HOST};
  uint64_t count = 0;
  const Timing t = measure(1, repeats, [&] {
    minkq_query_info info{};
    if (out.size() < 2) out.resize(2);
    minkq_status s = minkq_bvh_query(bvh, &q, out.data(), out.size() / 2, MINKQ_MEMORY_HOST, &info);
    if (s == MINKQ_ERROR_CAPACITY) {
      out.resize(2 * info.count + 2);
      s = minkq_bvh_query(bvh, &q, out.data(), out.size() / 2, MINKQ_MEMORY_HOST, &info);
    }
    check(s, "minkq_bvh_query");
    count = info.count;
  });
  ms = t.median;
  return count;
}

// 3-D spread: n cubes of half-size h, centres uniform in [0,1]^3; queries uniform points
// (spheres) and segments of length 2 sqrt(3) h (a cube's diagonal) in uniform random
// directions (capsules). r follows h/r so that a padded-box query meets about 8 boxes whatever
// the ratio: (2h + 2r)^3 n = 8.
void synthetic(minkq_device* dev, const std::vector<double>& ratios, int n, int queries, int repeats, std::vector<Line>& out) {
  for (double hr : ratios) {
    const double s = std::cbrt(8.0 / n) / (2 * (1 + hr));
    const double r = s, h = hr * s;
    Rng rng{uint64_t(hr * 1e6) + 12345};
    std::vector<float> boxes;
    boxes.reserve(6 * size_t(n));
    for (int i = 0; i < n; ++i) {
      const double c[3] = {rng.uniform(), rng.uniform(), rng.uniform()};
      for (int k = 0; k < 3; ++k) boxes.push_back(float(c[k] - h));
      for (int k = 0; k < 3; ++k) boxes.push_back(float(c[k] + h));
    }
    Bvh bvh = new_bvh(dev, host_buffer(boxes.data(), size_t(n), 24));
    std::vector<float> points, p0, p1;
    const double len = 2 * std::sqrt(3.0) * h;
    for (int i = 0; i < queries; ++i) {
      for (int k = 0; k < 3; ++k) points.push_back(float(rng.uniform()));
      const double th = std::acos(2 * rng.uniform() - 1), ph = 2 * kPi * rng.uniform();
      const double d[3] = {std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)};
      const double c[3] = {rng.uniform(), rng.uniform(), rng.uniform()};
      for (int k = 0; k < 3; ++k) p0.push_back(float(c[k] - 0.5 * len * d[k]));
      for (int k = 0; k < 3; ++k) p1.push_back(float(c[k] + 0.5 * len * d[k]));
    }
    std::vector<int32_t> res;
    double box_ms, ms;
    const uint64_t box = bvh_query(bvh.get(), MINKQ_SHAPE_SPHERE, MINKQ_MODE_BOX, float(r), points, {}, res, box_ms, repeats);
    const uint64_t sph = bvh_query(bvh.get(), MINKQ_SHAPE_SPHERE, MINKQ_MODE_SPHERE, float(r), points, {}, res, ms, repeats);
    out.push_back({"3-D spread cubes", "sphere", "sphere", hr, 100.0 * (1 - double(sph) / double(box)), ms, box_ms, sph, box});
    double cbox_ms;
    const uint64_t cbox = bvh_query(bvh.get(), MINKQ_SHAPE_CAPSULE, MINKQ_MODE_BOX, float(r), p0, p1, res, cbox_ms, repeats);
    for (auto [mode, name] : {std::pair{MINKQ_MODE_CAPSULE_RAY, "capsule_ray"}, std::pair{MINKQ_MODE_CAPSULE_EXACT, "capsule_exact"}}) {
      const uint64_t c = bvh_query(bvh.get(), MINKQ_SHAPE_CAPSULE, mode, float(r), p0, p1, res, ms, repeats);
      out.push_back({"3-D spread cubes", "capsule", name, hr, 100.0 * (1 - double(c) / double(cbox)), ms, cbox_ms, c, cbox});
    }
    std::fprintf(stderr, "[synthetic] h/r %.3g: box %" PRIu64 " sphere %" PRIu64 " capsule box %" PRIu64 ", load %.2f\n", hr, box, sph,
                 cbox, load_average());
  }
}

// Cloth: a scene's VT and EE queries over a radius sweep; h = mean over primitives of the
// largest half-extent of the primitive's box (triangles for VT, edges for EE).
void cloth(minkq_device* dev, const SceneFrames& sc, const std::vector<double>& factors, int repeats, std::vector<Line>& out) {
  const ref::Mesh& m = sc.mesh;
  auto half = [&](const std::vector<int32_t>& idx, int per) {
    double sum = 0;
    for (size_t i = 0; i < idx.size(); i += per) {
      double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
      for (int j = 0; j < per; ++j)
        for (int k = 0; k < 3; ++k) {
          const double x = m.xyz[3 * size_t(idx[i + j]) + k];
          lo[k] = std::min(lo[k], x), hi[k] = std::max(hi[k], x);
        }
      sum += 0.5 * std::max({hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]});
    }
    return sum / double(idx.size() / per);
  };
  const double h_tri = half(m.tris, 3), h_edge = half(m.edges, 2);
  Scene scene = create_scene(dev, m.xyz, m.tris);
  Result res = new_result();
  for (double f : factors) {
    const float r = float(f * sc.mean_edge);
    {  // skip radii whose box candidates would not fit this machine's time and memory
      bool skip = false;
      for (minkq_query_kind kind : {MINKQ_QUERY_VT, MINKQ_QUERY_EE}) {
        const minkq_query_desc q{kind, MINKQ_MODE_BOX, 0, r};
        minkq_query_info qi{};
        const minkq_status st = minkq_scene_query(scene.get(), &q, nullptr, 0, MINKQ_MEMORY_HOST, &qi);
        if (st != MINKQ_SUCCESS && st != MINKQ_ERROR_CAPACITY) check(st, "minkq_scene_query");
        skip |= qi.count > 10000000;
      }
      if (skip) {
        std::fprintf(stderr, "[cloth] %s r = %.3g x mean edge: skipped (> 1e7 box candidates)\n", sc.name.c_str(), f);
        continue;
      }
    }
    auto run = [&](minkq_query_kind kind, minkq_mode mode, uint32_t flags, double& ms) {
      const minkq_query_desc q{kind, mode, flags, r};
      const Timing t = measure(1, repeats, [&] { check(minkq_scene_query_result(scene.get(), &q, res.get()), "query"); });
      ms = t.median;
      return minkq_result_count(res.get());
    };
    double box_ms, ms;
    const uint64_t vbox = run(MINKQ_QUERY_VT, MINKQ_MODE_BOX, 0, box_ms);
    for (auto [mode, flags, name] : {std::tuple{MINKQ_MODE_SPHERE, 0u, "sphere"}, std::tuple{MINKQ_MODE_SPHERE, uint32_t(MINKQ_QUERY_LEAF_EXACT), "leaf_exact"}}) {
      const uint64_t c = run(MINKQ_QUERY_VT, mode, flags, ms);
      out.push_back({sc.name, "VT (sphere)", name, h_tri / r, vbox ? 100.0 * (1 - double(c) / double(vbox)) : NAN, ms, box_ms, c, vbox});
    }
    const uint64_t ebox = run(MINKQ_QUERY_EE, MINKQ_MODE_BOX, 0, box_ms);
    for (auto [mode, flags, name] : {std::tuple{MINKQ_MODE_CAPSULE_RAY, 0u, "capsule_ray"}, std::tuple{MINKQ_MODE_CAPSULE_EXACT, 0u, "capsule_exact"},
                                     std::tuple{MINKQ_MODE_CAPSULE_EXACT, uint32_t(MINKQ_QUERY_LEAF_EXACT), "leaf_exact"}}) {
      const uint64_t c = run(MINKQ_QUERY_EE, mode, flags, ms);
      out.push_back({sc.name, "EE (capsule)", name, h_edge / r, ebox ? 100.0 * (1 - double(c) / double(ebox)) : NAN, ms, box_ms, c, ebox});
    }
    std::fprintf(stderr, "[cloth] %s r = %.3g x mean edge: VT box %" PRIu64 ", EE box %" PRIu64 ", load %.2f\n", sc.name.c_str(), f, vbox, ebox,
                 load_average());
  }
}

int run(int argc, char** argv) {
  std::string out_dir = MINKQ_BENCH_RESULTS_DIR, data_dir = MINKQ_BENCH_DATA_DIR;
  bool quick = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--quick") quick = true;
    else if (a == "--out" && i + 1 < argc) out_dir = argv[++i];
    else if (a == "--data" && i + 1 < argc) data_dir = argv[++i];
    else if (a == "--help" || a == "-h") {
      std::puts("usage: minkq_hr_study [--quick] [--out DIR] [--data DIR]\nWrites DIR/hr_study.md and DIR/hr_study.csv.");
      return 0;
    } else {
      std::fprintf(stderr, "minkq_hr_study: unknown option %s\n", a.c_str());
      return 2;
    }
  }
  Device dev = open_device("cpu");
  const double load_start = load_average();
  std::vector<Line> lines;
  const std::vector<double> ratios = quick ? std::vector<double>{0.01, 1, 10} : std::vector<double>{0.003, 0.01, 0.03, 0.1, 0.2, 0.5, 1, 2, 5, 10, 30, 100};
  synthetic(dev.get(), ratios, quick ? 5000 : 200000, quick ? 5000 : 200000, quick ? 1 : 3, lines);
  const std::vector<double> factors = quick ? std::vector<double>{0.25, 1} : std::vector<double>{0.05, 0.1, 0.25, 0.5, 1, 2, 4, 8};
  if (!quick) cloth(dev.get(), make_scene("twist_target", 2e4, 1, data_dir), factors, 3, lines);  // 101^2 grid
  cloth(dev.get(), make_scene("cloth_hanging", 0, 1, data_dir), factors, quick ? 1 : 3, lines);  // folded: last phase

  std::ostringstream o, csv;
  csv << "input,query,mode,h_over_r,drop_percent,candidates,box_candidates,ms,box_ms\n";
  for (const Line& l : lines)
    csv << l.input << "," << l.query << "," << l.mode << "," << l.h_over_r << "," << l.drop_percent << "," << l.candidates << ","
        << l.box_candidates << "," << l.ms << "," << l.box_ms << "\n";
  o << "# h/r study: candidate drop against the padded box\n\n";
  o << "Machine: " << machine_line(minkq_device_name(dev.get())) << ". Load average (1 min) " << fmt(load_start, 3) << " -> "
    << fmt(load_average(), 3) << ". Written by `minkq_hr_study`" << (quick ? " --quick" : "") << ". Plot: hr_study.png (bench/plot.py).\n\n";
  o << "Drop = 1 - candidates / box candidates for the same queries. h = primitive box half-size, r = query radius.\n\n"
       "**3-D spread**: cubes of half-size h with centres uniform in [0,1]^3 (user-box BVH, `minkq_bvh_query`); sphere "
       "queries at uniform points; capsule queries along uniform segments of length 2 sqrt(3) h (a cube diagonal) in "
       "uniform directions; r set from h/r so a padded-box query meets about 8 boxes. For spheres the expected drop is "
       "1 - (Minkowski sum of cube and ball) / (padded cube) (Steiner's formula; 47.6% as h/r -> 0), shown beside. "
       "**Cloth**: the scene API's VT (sphere) and EE (capsule) queries on a twisted sheet (101 x 101 vertices, 3 "
       "turns) and on the folded hanging cloth over r = 0.05x..8x mean edge (radii with more than 1e7 box candidates skipped); h is the mean over primitives of the box's largest half-extent. "
       "leaf_exact adds the primitive distance test, its drop is the ceiling (candidates = contacts).\n\n"
       "Reference (prototype, 3-D-spread inputs): **46.8%** sphere, **51.7%** capsule candidate drop.\n\n";
  for (const std::string input : {"3-D spread cubes", "twist_target", "cloth_hanging"}) {
    o << "## " << input << "\n\n| query | mode | h/r | candidates | box candidates | drop | theory (sphere) | query ms | box ms | speed vs box |\n|---|---|---|---|---|---|---|---|---|---|\n";
    for (const Line& l : lines) {
      if (l.input != input) continue;
      o << "| " << l.query << " | " << l.mode << " | " << fmt(l.h_over_r, 3) << " | " << l.candidates << " | " << l.box_candidates << " | "
        << fmt(l.drop_percent, 3) << "% | " << (l.mode == "sphere" && input == "3-D spread cubes" ? fmt(theory_sphere_drop(l.h_over_r), 3) + "%" : "–")
        << " | " << fmt(l.ms, 3) << " | " << fmt(l.box_ms, 3) << " | " << fmt(l.box_ms / l.ms, 3) << "x |\n";
    }
    o << "\n";
  }
  fs::create_directories(out_dir);
  for (const auto& [name, text] : {std::pair{"/hr_study.md", o.str()}, std::pair{"/hr_study.csv", csv.str()}}) {
    std::ofstream f(out_dir + name);
    f << text;
    if (!f) throw std::runtime_error("cannot write " + out_dir + name);
  }
  std::fprintf(stderr, "wrote %s/hr_study.md and hr_study.csv\n", out_dir.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "minkq_hr_study: %s\n", e.what());
    return 3;
  }
}
