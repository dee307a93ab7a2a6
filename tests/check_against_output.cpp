// Checks `minkq query A --against B [--self] [--thickness FILE]` on two generated meshes that
// cross each other (a wavy sheet through a twisted one), written as OBJ or as PLY and read back
// as the CLI reads them. In every mode, with and without a thickness per vertex (0 to 2 r):
//   - the pairs are those of the two meshes concatenated (B's vertices, triangles and edges after
//     A's): they contain every pair of the double oracle on the concatenated mesh whose distance
//     is <= r + t(a) + t(b), --leaf-exact keeps no other pair beyond that reach plus its slack, and
//     without --self every pair joins A and B;
//   - --self adds exactly the pairs `minkq query A` and `minkq query B` report (B's renumbered),
//     with their parts of the thickness file (--thickness on one mesh).
// `thickness-errors` checks that a thickness file with a wrong count, a non-number, a negative,
// non-finite or float-overflowing value exits with status 3 and a message naming the line.
// usage: check_against_output MINKQ_BINARY obj|ply|thickness-errors WORK_DIR
#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include "contact_checks.h"

namespace ref = minkq::reference;
using ref::Mesh;
using ref::Pairs;

namespace {

// Writes the float positions with 9 significant digits: read back, they are the same floats.
void write_mesh(const std::string& path, const Mesh& m, bool ply) {
  std::ofstream f(path);
  char line[128];
  if (ply)
    f << "ply\nformat ascii 1.0\nelement vertex " << m.vertex_count()
      << "\nproperty float x\nproperty float y\nproperty float z\nelement face " << m.triangle_count()
      << "\nproperty list uchar int vertex_indices\nend_header\n";
  for (size_t v = 0; v < m.vertex_count(); ++v) {
    std::snprintf(line, sizeof line, "%s%.9g %.9g %.9g\n", ply ? "" : "v ", double(m.xyz[3 * v]),
                  double(m.xyz[3 * v + 1]), double(m.xyz[3 * v + 2]));
    f << line;
  }
  const int base = ply ? 0 : 1;
  for (size_t t = 0; t < m.triangle_count(); ++t)
    f << (ply ? "3 " : "f ") << m.tris[3 * t] + base << " " << m.tris[3 * t + 1] + base << " " << m.tris[3 * t + 2] + base
      << "\n";
  if (!f) throw std::runtime_error("cannot write " + path);
}

// A: a wavy 24 x 24 sheet on [0,1]^2; B: a 20 x 20 sheet twisted two turns about the x axis,
// through A along x, with a little deterministic jitter so that nothing lines up exactly.
std::pair<Mesh, Mesh> generated_pair() {
  Mesh a = ref::grid_sheet(24), b = ref::twisted_sheet(20, 2.0);
  for (size_t i = 0; i < a.xyz.size(); i += 3) a.xyz[i + 2] = float(0.05 * std::sin(7.0 * a.xyz[i] + 3.0 * a.xyz[i + 1]));
  for (size_t i = 0; i < b.xyz.size(); ++i) {
    b.xyz[i] = float(double(b.xyz[i]) * 0.97 + 0.002 * std::sin(0.37 * double(i)));
    if (i % 3 == 1) b.xyz[i] += 0.5f;
  }
  return {a, b};
}

// A then B, as the CLI numbers them. The concatenated mesh's derived edges are A's then B's
// renumbered (B's lowest vertex is above all of A's), checked here since the comparison
// depends on it.
Mesh concatenate(const Mesh& a, const Mesh& b) {
  Mesh m = a;
  const int32_t n = int32_t(a.vertex_count());
  m.xyz.insert(m.xyz.end(), b.xyz.begin(), b.xyz.end());
  for (int32_t v : b.tris) m.tris.push_back(v + n);
  m.edges = ref::derive_edges(m.tris);
  std::vector<int32_t> expected = a.edges;
  for (int32_t v : b.edges) expected.push_back(v + n);
  if (m.edges != expected) throw std::runtime_error("the concatenated mesh's edges are not A's then B's");
  return m;
}

// One value per vertex from 0 to `most`, a fifth of them 0; written in a file with comments and
// blank lines (which the CLI skips).
std::vector<float> thickness_values(size_t count, double most) {
  std::vector<float> t(count);
  for (size_t i = 0; i < count; ++i) t[i] = i % 5 == 0 ? 0.0f : float(most * std::fmod(double(i) * 0.6180339887, 1.0));
  return t;
}
void write_thickness(const std::string& path, const float* t, size_t count) {
  std::ofstream f(path);
  f << "# thickness per vertex\n\n";
  char line[64];
  for (size_t i = 0; i < count; ++i) {
    std::snprintf(line, sizeof line, i % 7 == 3 ? "  %.9g\t\n" : "%.9g\n", double(t[i]));
    f << line << (i % 11 == 5 ? "\n# a comment\n" : "");
  }
  if (!f) throw std::runtime_error("cannot write " + path);
}

int run(const std::string& command) {
  std::printf("%s\n", command.c_str());
  std::fflush(stdout);
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
}

std::string quoted(const std::string& s) { return "\"" + s + "\""; }

// The scene of a check: the meshes concatenated, the thickness per vertex (empty: none), and
// where B's ids begin (0 for one mesh: every pair is allowed).
struct Concatenated {
  Mesh mesh;
  std::vector<float> t;
  int32_t b_vertex = 0, b_triangle = 0, b_edge = 0;

  bool cross_vt(int32_t v, int32_t tri) const { return (v >= b_vertex) != (tri >= b_triangle); }
  bool cross_ee(int32_t e, int32_t f) const { return (e >= b_edge) != (f >= b_edge); }
  long double vertex_t(int32_t v) const { return t.empty() ? 0.0L : (long double)t[size_t(v)]; }
  long double element_t(const int32_t* ids, int n) const {
    long double most = 0;
    for (int k = 0; k < n; ++k) most = std::max(most, vertex_t(ids[k]));
    return most;
  }
  long double vt_reach(double r, int32_t v, int32_t tri) const {
    return r + vertex_t(v) + element_t(&mesh.tris[3 * size_t(tri)], 3);
  }
  long double ee_reach(double r, int32_t e, int32_t f) const {
    return r + element_t(&mesh.edges[2 * size_t(e)], 2) + element_t(&mesh.edges[2 * size_t(f)], 2);
  }
};

// The oracle's pairs within reach: its contacts within r + 2 max t, kept when their distance is
// <= r + t(a) + t(b) and, with `cross_only`, when they join A and B.
std::pair<Pairs, Pairs> true_pairs(const Concatenated& s, double r, bool cross_only) {
  const double most = s.t.empty() ? 0.0 : double(*std::max_element(s.t.begin(), s.t.end()));
  Pairs vt, ee;
  double scale;
  for (const auto& [v, tri] : ref::vt_contacts(s.mesh, r + 2 * most, true))
    if ((!cross_only || s.cross_vt(v, tri)) && minkq::test::vt_distance(s.mesh, v, tri, &scale) <= s.vt_reach(r, v, tri))
      vt.emplace_back(v, tri);
  for (const auto& [e, f] : ref::ee_contacts(s.mesh, r + 2 * most, true))
    if ((!cross_only || s.cross_ee(e, f)) &&
        minkq::test::ee_distance(s.mesh, s.mesh.edges, e, f, &scale) <= s.ee_reach(r, e, f))
      ee.emplace_back(e, f);
  return {vt, ee};
}

const char* const kModes[] = {"box", "sphere", "capsule_ray", "capsule_exact", "box --leaf-exact"};

// Runs `command --mode M --out PREFIX` in every mode and checks the pairs against the oracle;
// returns the failures. `pairs` gets each mode's VT and EE pairs.
int check_modes(const std::string& label, const std::string& command, const Concatenated& s, double r, bool cross_only,
                const std::string& prefix, std::vector<std::pair<Pairs, Pairs>>* pairs) {
  const auto [vt_truth, ee_truth] = true_pairs(s, r, cross_only);
  int failures = 0;
  if (cross_only && (vt_truth.empty() || ee_truth.empty())) {
    std::printf("%s: the meshes should cross, with VT and EE pairs between them\n", label.c_str());
    ++failures;
  }
  for (const char* mode : kModes) {
    if (run(command + " --mode " + mode + " --out " + quoted(prefix)) != 0) throw std::runtime_error(label + ": minkq failed");
    const Pairs vt = minkq::test::read_pairs(prefix + ".vt.bin"), ee = minkq::test::read_pairs(prefix + ".ee.bin");
    const bool exact = std::string(mode).find("--leaf-exact") != std::string::npos;
    failures += minkq::test::compare_pairs(
        label + " " + mode + " VT", vt, vt_truth, exact,
        [&](int32_t v, int32_t t, double* S) { return minkq::test::vt_distance(s.mesh, v, t, S); },
        [&](int32_t v, int32_t t) { return s.vt_reach(r, v, t); });
    failures += minkq::test::compare_pairs(
        label + " " + mode + " EE", ee, ee_truth, exact,
        [&](int32_t e, int32_t f, double* S) { return minkq::test::ee_distance(s.mesh, s.mesh.edges, e, f, S); },
        [&](int32_t e, int32_t f) { return s.ee_reach(r, e, f); });
    if (cross_only) {
      const auto own_vt = std::count_if(vt.begin(), vt.end(), [&](auto p) { return !s.cross_vt(p.first, p.second); });
      const auto own_ee = std::count_if(ee.begin(), ee.end(), [&](auto p) { return !s.cross_ee(p.first, p.second); });
      if (own_vt + own_ee) std::printf("%s %s: %ld VT and %ld EE pairs within one mesh\n", label.c_str(), mode, long(own_vt), long(own_ee));
      failures += int(own_vt + own_ee);
    }
    pairs->emplace_back(vt, ee);
  }
  return failures;
}

// `add` renumbered by `offset` (a vertex and a triangle or edge offset) and merged into `into`.
void merge_shifted(Pairs& into, const Pairs& add, int32_t first_offset, int32_t second_offset) {
  for (const auto& [a, b] : add) into.emplace_back(a + first_offset, b + second_offset);
  std::sort(into.begin(), into.end());
}

int check_pair(const std::string& binary, bool ply, const std::string& work) {
  const auto [generated_a, generated_b] = generated_pair();
  const std::string ext = ply ? ".ply" : ".obj", path_a = work + "/a" + ext, path_b = work + "/b" + ext;
  write_mesh(path_a, generated_a, ply);
  write_mesh(path_b, generated_b, ply);
  const Mesh a = ref::load_mesh(path_a), b = ref::load_mesh(path_b);
  const double r = double(float(0.75 * ref::mean_edge_length(a)));
  char radius[32];
  std::snprintf(radius, sizeof radius, "%.9g", r);

  Concatenated both{concatenate(a, b), {}, int32_t(a.vertex_count()), int32_t(a.triangle_count()), int32_t(a.edge_count())};
  Concatenated only_a{a, {}}, only_b{b, {}};
  const std::vector<float> t = thickness_values(both.mesh.vertex_count(), 2 * r);
  write_thickness(work + "/t_ab.txt", t.data(), t.size());
  write_thickness(work + "/t_a.txt", t.data(), a.vertex_count());
  write_thickness(work + "/t_b.txt", t.data() + a.vertex_count(), b.vertex_count());

  const std::string base = quoted(binary) + " query ", common = std::string(" --radius ") + radius + " --backend cpu";
  const std::string against = base + quoted(path_a) + " --against " + quoted(path_b) + common;
  int failures = 0;
  for (const bool thick : {false, true}) {
    const std::string tag = thick ? " thickness" : "";
    both.t = only_a.t = only_b.t = {};
    if (thick) {
      both.t = t;
      only_a.t.assign(t.begin(), t.begin() + a.vertex_count());
      only_b.t.assign(t.begin() + a.vertex_count(), t.end());
    }
    const std::string with_t = thick ? " --thickness " : "";
    const auto t_file = [&](const char* name) { return thick ? with_t + quoted(work + "/" + name) : std::string(); };
    std::vector<std::pair<Pairs, Pairs>> cross, self, own_a, own_b;
    failures += check_modes("cross" + tag, against + t_file("t_ab.txt"), both, r, true, work + "/cross", &cross);
    failures += check_modes("self" + tag, against + " --self" + t_file("t_ab.txt"), both, r, false, work + "/self", &self);
    failures += check_modes("A" + tag, base + quoted(path_a) + common + t_file("t_a.txt"), only_a, r, false, work + "/a", &own_a);
    failures += check_modes("B" + tag, base + quoted(path_b) + common + t_file("t_b.txt"), only_b, r, false, work + "/b", &own_b);
    // --self adds exactly each mesh's own pairs, in every mode.
    for (size_t m = 0; m < cross.size(); ++m) {
      auto [vt, ee] = cross[m];
      merge_shifted(vt, own_a[m].first, 0, 0);
      merge_shifted(vt, own_b[m].first, both.b_vertex, both.b_triangle);
      merge_shifted(ee, own_a[m].second, 0, 0);
      merge_shifted(ee, own_b[m].second, both.b_edge, both.b_edge);
      const bool same = vt == self[m].first && ee == self[m].second;
      std::printf("%s%s: --self %s the cross pairs and each mesh's own\n", thick ? "thickness " : "", kModes[m],
                  same ? "reports exactly" : "DIFFERS from");
      failures += same ? 0 : 1;
    }
  }
  return failures;
}

// Each bad thickness file: its lines, and what the message must say after "FILE:".
int check_thickness_errors(const std::string& binary, const std::string& work) {
  const Mesh a = ref::grid_sheet(3);  // 9 vertices
  const std::string mesh = work + "/sheet.obj";
  write_mesh(mesh, a, false);
  std::string nine;
  for (int i = 0; i < 9; ++i) nine += "0.5\n";
  const std::pair<std::string, std::string> cases[] = {
      {"# eight\n" + nine.substr(4), "9: the file ends after 8 values; 9 expected, one per vertex"},
      {nine + "\n0.5\n", "11: one value too many: 9 expected"},
      {"0.5\n0.5\nabc\n" + nine, "3: not a number: 'abc'"},
      {"0.5\n0.25 0.5\n" + nine, "2: not a number: '0.25 0.5'"},
      {"0.5\n\n-0.125\n" + nine, "3: negative thickness: '-0.125'"},
      {"nan\n" + nine, "1: not a finite number: 'nan'"},
      {"0.5\ninf\n" + nine, "2: not a finite number: 'inf'"},
      {"1e39\n" + nine, "1: too large for a float: '1e39'"},
  };
  int failures = 0, index = 0;
  for (const auto& [text, message] : cases) {
    const std::string file = work + "/bad" + std::to_string(index++) + ".txt", err = file + ".err";
    std::ofstream(file) << text;
    const int status = run(quoted(binary) + " query " + quoted(mesh) + " --radius 0.1 --backend cpu --thickness " +
                           quoted(file) + " 2> " + quoted(err));
    std::stringstream said;
    said << std::ifstream(err).rdbuf();
    const bool named = said.str().find(file + ":" + message) != std::string::npos;
    std::printf("exit %d, %s: %s", status, named ? "message as expected" : "WRONG message", said.str().c_str());
    failures += (status == 3 && named) ? 0 : 1;
  }
  // A good file: the same mesh with 9 values is accepted.
  std::ofstream(work + "/good.txt") << "# fine\n\n" + nine;
  failures += run(quoted(binary) + " query " + quoted(mesh) + " --radius 0.1 --backend cpu --thickness " +
                  quoted(work + "/good.txt")) != 0;
  return failures;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string what = argc == 4 ? argv[2] : "";
  if (what != "obj" && what != "ply" && what != "thickness-errors") {
    std::fprintf(stderr, "usage: check_against_output MINKQ_BINARY obj|ply|thickness-errors WORK_DIR\n");
    return 2;
  }
  try {
    const int failures = what == "thickness-errors" ? check_thickness_errors(argv[1], argv[3])
                                                    : check_pair(argv[1], what == "ply", argv[3]);
    std::printf("%d failures\n", failures);
    return failures == 0 ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "check_against_output: %s\n", e.what());
    return 3;
  }
}
