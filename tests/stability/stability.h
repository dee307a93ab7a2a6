// The numerical stability checks' shared parts (tests/stability/, run by test_stability.cpp):
// the cases (cases.cpp), each candidate measured against its mode's stated bound and each case's
// node predicates checked for non-finite intermediates (bounds.cpp), and the two
// parametrisations of the capsule ray node test (capsule_ray.cpp). Formerly bench/stability/'s
// report; docs/design-notes.md keeps its findings.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <iterator>
#include <string>
#include <utility>
#include <vector>

#include "minkq/query_sources.h"
#include "minkq_reference.h"

namespace minkq::test::stability {

namespace ref = minkq::reference;
using LD = long double;

// Pairs packed by minkq::pack_pair (first << 32 | second), sorted: set operations by merge.
using PairSet = std::vector<uint64_t>;
inline PairSet to_set(const int32_t* pairs, uint64_t count) {
  PairSet s(count);
  for (uint64_t i = 0; i < count; ++i) s[i] = minkq::pack_pair(pairs[2 * i], pairs[2 * i + 1]);
  std::sort(s.begin(), s.end());
  return s;
}
inline PairSet to_set(const reference::Pairs& p) {
  PairSet s(p.size());
  for (size_t i = 0; i < p.size(); ++i) s[i] = minkq::pack_pair(p[i].first, p[i].second);
  std::sort(s.begin(), s.end());
  return s;
}
// Elements of `need` absent from `have` (both sorted).
inline uint64_t missing(const PairSet& need, const PairSet& have) {
  PairSet out;
  std::set_difference(need.begin(), need.end(), have.begin(), have.end(), std::back_inserter(out));
  return out.size();
}
inline std::string fmt(double v, int digits) {
  char b[48];
  std::snprintf(b, sizeof b, "%.*g", digits, v);
  return b;
}

// ---- Measures of how far a candidate lies (bounds.cpp) --------------------------------------
// Worst observed (excess over r) / (slack the stated bound allows) of a mode's candidates.
struct Excess {
  LD worst_ratio = 0, worst_abs = 0;  // max (d - r) / slack and max (d - r)
  uint64_t over = 0;                  // candidates beyond the stated bound
};

enum class Metric { kBox, kSphere, kRay, kCapsuleExact, kLeaf };

// Adds candidate (q, p) of a VT (vt) or EE query at radius r to ex, in the metric's own distance
// against the slack its stated bound allows (bounds.cpp lists the metrics and slacks).
void measure_excess(const ref::Mesh& m, bool vt, int32_t q, int32_t p, LD r, Metric metric, Excess& ex);

// Non-finite intermediates of the node predicates, evaluated for every query and for every
// (query, primitive box) pair of the box candidates (a superset of every mode's).
struct NonFinite {
  uint64_t r2 = 0, box_gap = 0, point_box = 0, threshold = 0, segment_box = 0, ray_t = 0;
  std::string text() const {
    std::string s;
    auto add = [&](const char* what, uint64_t n) {
      if (n) s += (s.empty() ? "" : ", ") + std::string(what) + " " + std::to_string(n);
    };
    add("r2 bound", r2), add("box gap", box_gap), add("point-box d2", point_box), add("capsule threshold", threshold),
        add("segment-box g", segment_box), add("ray t", ray_t);
    return s.empty() ? "0" : s;
  }
};

NonFinite non_finite(const ref::Mesh& m, float r, const PairSet& vt_box, const PairSet& ee_box);

// ---- Cases (cases.cpp) ----------------------------------------------------------------------
struct Case {
  std::string group, name;
  ref::Mesh mesh;
  float r;
  // The case whose candidate sets this one's must equal ("" none): a scaling by 2^k with
  // |k| <= 40 or by 1e+-3. Scalings by 2^+-70 and 2^+-100 name it too but are not held to it
  // (compare_only): there squared distances over- or underflow float and the sphere and
  // capsule_exact sets change with the scale, without false negatives.
  std::string compare_to;
  bool compare_only = false;
};

std::vector<Case> cases();

// ---- Capsule ray: both parametrisations (capsule_ray.cpp) ---------------------------------
struct RayRow {
  std::string name;
  uint64_t truth = 0;
  uint64_t cand[4] = {0, 0, 0, 0}, fn[4] = {0, 0, 0, 0};
};

// cand / fn: [0] the C API's capsule_ray, [1] the core's shape (direction e1 - e0, t <= 1)
// through a test traversal, [2] a unit direction with t <= |e|, [3] the same with |e| taken
// after rescaling.
std::vector<RayRow> ray_study();

}  // namespace minkq::test::stability
