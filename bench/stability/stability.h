// minkq_stability's shared parts (bench/stability/): what the program's files hand each other.
// The cases (cases.cpp) run through every mode and backend (runner.cpp), each candidate measured
// against its mode's stated bound and each case's node predicates checked for non-finite
// intermediates (bounds.cpp); the capsule ray parametrisations are a study of their own
// (capsule_ray.cpp); main.cpp reads the options and writes stability.md.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "common.h"

namespace minkq::bench::stability {

namespace ref = minkq::reference;
using LD = long double;

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
  std::string compare_to;  // name of the case whose candidate sets must equal this one's ("" none)
};

std::vector<Case> cases(bool quick);

// ---- Every case through every mode and backend (runner.cpp) ---------------------------------
struct Row {
  std::string group, name, backend, kind, mode;
  uint64_t candidates = 0, truth = 0, fn = 0;
  Excess ex;
  std::string non_finite = "0";
  std::string same_as;  // "yes", "no (N differ)", ""
  float r = 0;
};

struct Runner {
  std::vector<std::string> backends;
  std::vector<Row> rows;
  std::map<std::string, std::map<std::string, PairSet>> sets;  // case -> backend/kind/mode -> set
  std::map<std::string, std::pair<PairSet, PairSet>> truths;   // case -> (vt, ee)
  uint64_t false_negatives = 0, over_bound = 0, over_bound_unexplained = 0;
  std::vector<std::string> over_cases;

  void run(const Case& c);
};

// ---- Capsule ray: both parametrisations (capsule_ray.cpp) ---------------------------------
struct RayRow {
  std::string name;
  uint64_t truth = 0;
  uint64_t cand[4] = {0, 0, 0, 0}, fn[4] = {0, 0, 0, 0};
};

std::vector<RayRow> ray_study(bool quick, uint64_t& false_negatives_core);

}  // namespace minkq::bench::stability
