// What the programs `minkq` and `minkq-mpi` (both in apps/) share: option parsing and
// the names of the query modes, so that both read the same arguments the same way.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "minkq.h"

namespace minkq::cli {

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// "--name value" or "--name=value" options, and "--name" switches, after the positional
// arguments.
struct Args {
  std::vector<std::string> positional;
  std::vector<std::pair<std::string, std::string>> options;
  std::vector<std::string> switches_set;

  Args(int argc, char** argv, int first, const std::vector<std::string>& known,
       const std::vector<std::string>& switches = {}) {
    for (int i = first; i < argc; ++i) {
      std::string a = argv[i];
      if (a.rfind("--", 0) != 0) {
        positional.push_back(a);
        continue;
      }
      if (std::find(switches.begin(), switches.end(), a) != switches.end()) {
        switches_set.push_back(a);
        continue;
      }
      std::string value;
      const size_t eq = a.find('=');
      if (eq != std::string::npos) {
        value = a.substr(eq + 1), a = a.substr(0, eq);
      } else {
        if (i + 1 >= argc) throw UsageError("option " + a + " needs a value");
        value = argv[++i];
      }
      if (std::find(known.begin(), known.end(), a) == known.end()) throw UsageError("unknown option " + a);
      options.emplace_back(a, value);
    }
  }
  bool has(const std::string& name) const {
    return std::find(switches_set.begin(), switches_set.end(), name) != switches_set.end();
  }
  const std::string* get(const std::string& name) const {
    const std::string* v = nullptr;
    for (const auto& [k, val] : options)
      if (k == name) v = &val;  // the last one wins
    return v;
  }
};

inline double parse_number(const std::string& option, const std::string& text) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !std::isfinite(v)) throw UsageError(option + ": not a finite number: '" + text + "'");
  return v;
}

// The radius of `query`: --radius R, or --radius-factor F for F x the mesh's mean edge length
// (mean_edge() computes it); finite, >= 0, a float.
template <class MeanEdge>
float query_radius(const Args& args, MeanEdge&& mean_edge) {
  const std::string* given = args.get("--radius");
  const std::string* factor = args.get("--radius-factor");
  if (!given && !factor) throw UsageError("query needs --radius R (or --radius-factor F)");
  if (given && factor) throw UsageError("--radius and --radius-factor: give one of them");
  double radius = parse_number(given ? "--radius" : "--radius-factor", given ? *given : *factor);
  if (radius < 0) throw UsageError(given ? "--radius: must be >= 0" : "--radius-factor: must be >= 0");
  if (factor) radius *= mean_edge();
  if (!std::isfinite(float(radius))) throw UsageError("--radius: too large for a float");
  return float(radius);
}

// The VT and EE modes and the flags of a `query --mode` name (see `minkq --help`); swept
// queries (--to) have no leaf_exact and run EE as box.
struct QueryModes {
  minkq_mode vt, ee;
  uint32_t flags;
};
inline QueryModes query_modes(const std::string& mode, bool swept) {
  if (mode == "box") return {MINKQ_MODE_BOX, MINKQ_MODE_BOX, 0};
  if (mode == "sphere" || mode == "capsule_exact")
    return {swept ? MINKQ_MODE_CAPSULE_EXACT : MINKQ_MODE_SPHERE, swept ? MINKQ_MODE_BOX : MINKQ_MODE_CAPSULE_EXACT, 0};
  if (mode == "capsule_ray") return {MINKQ_MODE_CAPSULE_RAY, swept ? MINKQ_MODE_BOX : MINKQ_MODE_CAPSULE_RAY, 0};
  if (mode == "leaf_exact" && !swept) return {MINKQ_MODE_BOX, MINKQ_MODE_BOX, MINKQ_QUERY_LEAF_EXACT};
  if (mode == "leaf_exact")
    throw UsageError("--mode leaf_exact: swept queries (--to) report candidates for a narrow phase; use box, sphere, "
                     "capsule_ray or capsule_exact");
  throw UsageError("--mode: unknown mode '" + mode + "' (box, sphere, capsule_ray, capsule_exact, leaf_exact)");
}

}  // namespace minkq::cli
