// The scenes the differential fuzzer decodes and the regression tests replay (mesh scenes and
// user-box BVH scenes), the Report that collects failures, the Stats a campaign counts, the
// scenes printed as C++ (hex floats: exact), and the set comparisons every check uses.
// Part of the scene checks (scene_checks.h includes every part).
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <iterator>
#include <string>
#include <utility>
#include <vector>

#include "minkq.h"

namespace minkq::fuzz {

using Pairs = std::vector<std::pair<int32_t, int32_t>>;
using LD = long double;

// ---- Scenes -----------------------------------------------------------------------------------

// One set of a mesh scene's vertex positions as the checks take them: float input, or float64
// input (MINKQ_SCENE_FLOAT64) with its rounding to nearest float, which the scene's trees and
// tests use (capi/minkq.h). Empty: no such positions.
struct Positions {
  std::vector<float> xyz;     // 3 per vertex: the float input, or the float64 input rounded
  std::vector<double> xyz64;  // 3 per vertex: the float64 input; empty for float input

  // Float input `f`, or (when `d` is not empty) float64 input `d`, whatever `f` then holds.
  static Positions of(const std::vector<float>& f, const std::vector<double>& d) {
    Positions p;
    if (d.empty()) {
      p.xyz = f;
    } else {
      p.xyz64 = d;
      p.xyz.assign(d.begin(), d.end());  // to nearest
    }
    return p;
  }
  bool float64() const { return !xyz64.empty(); }
  bool empty() const { return xyz.empty(); }
  size_t count() const { return xyz.size() / 3; }
  bool operator==(const Positions& o) const { return xyz == o.xyz && xyz64 == o.xyz64; }
  // The input as the C API takes it: 3 floats or (MINKQ_SCENE_FLOAT64) 3 doubles per vertex.
  minkq_buffer buffer() const {
    if (float64()) return {xyz64.data(), 0, count(), MINKQ_MEMORY_HOST};
    return {xyz.empty() ? nullptr : xyz.data(), 0, count(), MINKQ_MEMORY_HOST};
  }
};

// A mesh scene: VT and EE queries at radius r, then (if `moved` is not empty) a refit to the
// moved positions and the same checks again, then (if `swept1` is not empty) a swept step from
// `swept0` to `swept1` and its checks. With `xyz64` the scene is float64 input
// (MINKQ_SCENE_FLOAT64): every position set is then the *64 one (xyz, moved, swept0, swept1
// are ignored; the checks round the doubles themselves).
struct MeshScene {
  std::vector<float> xyz;      // 3 per vertex
  std::vector<int32_t> tris;   // 3 per triangle
  std::vector<int32_t> edges;  // 2 per edge; empty: minkq derives them from the triangles
  float r = 0.0f;
  bool drop_incident = false;
  std::vector<float> moved;  // empty, or new positions for every vertex
  uint32_t variant = 0;      // how the pair buffers are passed (see run_query)
  std::string label;         // which generator made it
  std::vector<double> xyz64, moved64;    // float64 input: the positions, the refit's
  std::vector<float> swept0, swept1;     // a swept step's positions at t = 0 and t = 1
  std::vector<double> swept0_64, swept1_64;  // float64: the same

  bool float64() const { return !xyz64.empty(); }
  bool swept() const { return float64() ? !swept1_64.empty() : !swept1.empty(); }
  Positions start() const { return Positions::of(xyz, xyz64); }
  Positions refit() const { return float64() ? Positions::of({}, moved64) : Positions::of(moved, {}); }
  Positions step_start() const { return float64() ? Positions::of({}, swept0_64) : Positions::of(swept0, {}); }
  Positions step_end() const { return float64() ? Positions::of({}, swept1_64) : Positions::of(swept1, {}); }
};

// A BVH over user boxes queried by spheres (first), capsules (first-second) or boxes.
struct BoxScene {
  std::vector<float> boxes;  // 6 per box: lo xyz, hi xyz
  minkq_shape shape = MINKQ_SHAPE_SPHERE;
  std::vector<float> first, second;  // 3 per query; second empty for spheres
  float r = 0.0f;
  std::vector<float> moved;  // empty, or new boxes (same count) for a refit check
  uint32_t variant = 0;
  std::string label;
};

// ---- Reports ------------------------------------------------------------------------------------

class Report {
 public:
  void fail(const std::string& what) {
    if (failures_.size() < 12) failures_.push_back(what);
    ++count_;
  }
  bool ok() const { return count_ == 0; }
  size_t count() const { return count_; }
  std::string text() const {
    std::string out;
    for (const std::string& f : failures_) out += "  FAIL " + f + "\n";
    if (count_ > failures_.size()) out += "  ... " + std::to_string(count_ - failures_.size()) + " more\n";
    return out;
  }

 private:
  std::vector<std::string> failures_;
  size_t count_ = 0;
};

struct Stats {
  uint64_t mesh_scenes = 0;     // mesh scenes checked (every mode, both kinds)
  uint64_t refit_scenes = 0;    // of which also checked after a refit
  uint64_t float64_scenes = 0;  // of which float64 input
  uint64_t swept_scenes = 0;    // of which also checked in a swept step
  uint64_t still_steps = 0;     // of those, steps of zero motion (compared with the static sets)
  uint64_t sampled_contacts = 0;  // swept steps: the oracle's contacts at the sampled times
  uint64_t box_scenes = 0;      // user-box BVH scenes checked
  uint64_t queries = 0;         // minkq queries run
  uint64_t independent = 0;     // candidate sets compared with the independent traversal
  uint64_t pairs = 0;           // candidate pairs compared
  uint64_t true_contacts = 0;   // oracle contacts found
};

// ---- Printing a scene as C++ (hex floats: exact) ----------------------------------------------

inline std::string fmt_g(double v) {
  char text[48];
  std::snprintf(text, sizeof text, "%.9g", v);
  return text;
}

inline std::string hex_float(float v) {
  char text[48];
  std::snprintf(text, sizeof text, "%af", double(v));
  return text;
}

template <class T, class Format>
std::string list(const std::vector<T>& values, Format format, size_t per_line) {
  std::string out = "{";
  for (size_t i = 0; i < values.size(); ++i) {
    if (i) out += (i % per_line == 0) ? ",\n    " : ", ";
    out += format(values[i]);
  }
  return out + "}";
}
inline std::string float_list(const std::vector<float>& v) { return list(v, hex_float, 3); }
inline std::string hex_double(double v) {
  char text[48];
  std::snprintf(text, sizeof text, "%a", v);
  return text;
}
inline std::string double_list(const std::vector<double>& v) { return list(v, hex_double, 3); }
inline std::string int_list(const std::vector<int32_t>& v) {
  return list(v, [](int32_t i) { return std::to_string(i); }, 24);
}

// The scene as a C++ snippet to paste into tests/test_fuzz_regressions.cpp.
inline std::string describe(const MeshScene& s) {
  std::string out = "// " + s.label + ": " + std::to_string(s.start().count()) + " vertices, " +
                    std::to_string(s.tris.size() / 3) + " triangles, " +
                    (s.edges.empty() ? std::string("derived edges") : std::to_string(s.edges.size() / 2) + " edges") +
                    "\nfuzz::MeshScene s;\n";
  // A position set, or (when it equals the start) the start's name.
  auto positions = [&](const char* name, const std::vector<float>& f, const std::vector<double>& d) {
    if (s.float64() ? d.empty() : f.empty()) return;
    auto same_bits = [](const auto& a, const auto& b) {
      return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof a[0]) == 0);
    };
    const bool start = std::string(name) != "xyz" && std::string(name) != "xyz64" &&
                       (s.float64() ? same_bits(d, s.xyz64) : same_bits(f, s.xyz));
    out += std::string("s.") + name + " = " +
           (start ? std::string(s.float64() ? "s.xyz64" : "s.xyz") : s.float64() ? double_list(d) : float_list(f)) + ";\n";
  };
  if (s.float64()) positions("xyz64", {}, s.xyz64); else positions("xyz", s.xyz, {});
  out += "s.tris = " + int_list(s.tris) + ";\n";
  if (!s.edges.empty()) out += "s.edges = " + int_list(s.edges) + ";\n";
  out += "s.r = " + hex_float(s.r) + ";  // " + fmt_g(s.r) + "\n";
  out += std::string("s.drop_incident = ") + (s.drop_incident ? "true" : "false") + ";\n";
  if (s.float64()) positions("moved64", {}, s.moved64); else positions("moved", s.moved, {});
  if (s.float64()) {
    positions("swept0_64", {}, s.swept0_64);
    positions("swept1_64", {}, s.swept1_64);
  } else {
    positions("swept0", s.swept0, {});
    positions("swept1", s.swept1, {});
  }
  out += "s.variant = " + std::to_string(s.variant) + ";\n";
  return out;
}

inline std::string describe(const BoxScene& s) {
  static const char* shapes[] = {"MINKQ_SHAPE_SPHERE", "MINKQ_SHAPE_CAPSULE", "MINKQ_SHAPE_BOX"};
  std::string out = "// " + s.label + ": " + std::to_string(s.boxes.size() / 6) + " boxes, " +
                    std::to_string(s.first.size() / 3) + " queries\nfuzz::BoxScene s;\n";
  out += "s.boxes = " + list(s.boxes, hex_float, 6) + ";\n";
  out += std::string("s.shape = ") + shapes[int(s.shape) % 3] + ";\n";
  out += "s.first = " + float_list(s.first) + ";\n";
  if (!s.second.empty()) out += "s.second = " + float_list(s.second) + ";\n";
  out += "s.r = " + hex_float(s.r) + ";  // " + fmt_g(s.r) + "\n";
  if (!s.moved.empty()) out += "s.moved = " + list(s.moved, hex_float, 6) + ";\n";
  out += "s.variant = " + std::to_string(s.variant) + ";\n";
  return out;
}

inline std::string show(const Pairs& pairs, size_t max = 6) {
  std::string out;
  for (size_t i = 0; i < pairs.size() && i < max; ++i)
    out += "(" + std::to_string(pairs[i].first) + "," + std::to_string(pairs[i].second) + ") ";
  if (pairs.size() > max) out += "... (" + std::to_string(pairs.size()) + ")";
  return out;
}

inline Pairs minus(const Pairs& a, const Pairs& b) {
  Pairs out;
  std::set_difference(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(out));
  return out;
}

inline void expect_equal(Report& report, const Pairs& got, const Pairs& want, const std::string& what) {
  if (got == want) return;
  report.fail(what + ": " + std::to_string(got.size()) + " vs " + std::to_string(want.size()) +
              " pairs; only in the first: " + show(minus(got, want)) + "; only in the second: " + show(minus(want, got)));
}

inline void expect_subset(Report& report, const Pairs& small, const Pairs& large, const std::string& what) {
  const Pairs outside = minus(small, large);
  if (!outside.empty()) report.fail(what + ": " + std::to_string(outside.size()) + " pairs outside: " + show(outside));
}

}  // namespace minkq::fuzz
