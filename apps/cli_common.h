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
// arguments. An argument that starts with '-' (other than "-" alone) and is neither a known
// option nor a known switch is a usage error that names it.
struct Args {
  std::vector<std::string> positional;
  std::vector<std::pair<std::string, std::string>> options;
  std::vector<std::string> switches_set;

  Args(int argc, char** argv, int first, const std::vector<std::string>& known,
       const std::vector<std::string>& switches = {}) {
    const auto listed = [](const std::vector<std::string>& list, const std::string& a) {
      return std::find(list.begin(), list.end(), a) != list.end();
    };
    for (int i = first; i < argc; ++i) {
      std::string a = argv[i];
      if (a.size() < 2 || a[0] != '-') {
        positional.push_back(a);
        continue;
      }
      if (listed(switches, a)) {
        switches_set.push_back(a);
        continue;
      }
      std::string value;
      const size_t eq = a.find('=');
      const bool inline_value = eq != std::string::npos && a.rfind("--", 0) == 0;
      if (inline_value) value = a.substr(eq + 1), a = a.substr(0, eq);
      if (!listed(known, a)) throw UsageError("unknown option " + a);
      if (!inline_value) {
        if (i + 1 >= argc) throw UsageError("option " + a + " needs a value");
        value = argv[++i];
      }
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

// True when an argument from `first` on asks for help (-h or --help, before any "--" value).
inline bool wants_help(int argc, char** argv, int first) {
  for (int i = first; i < argc; ++i)
    if (std::string(argv[i]) == "--help" || std::string(argv[i]) == "-h") return true;
  return false;
}

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

// The node test and flags of `query --mode M [--leaf-exact]`, in the library's words: M is box
// (the default), sphere, capsule_ray or capsule_exact, applied to every kind as minkq_scene_query
// applies it (for point queries capsule_ray is the box test and capsule_exact the sphere test).
// Old words, kept for one release with a warning: `--mode leaf_exact` (now --mode box
// --leaf-exact) and `--mode sphere` for EE (which ran EE as capsule_exact, and still does).
// Swept queries (--to) have no --leaf-exact and run EE as box in every mode (the library's only
// swept EE test).
struct QueryModes {
  minkq_mode mode;
  uint32_t flags;
  bool swept;
  // The mode of one kind's query.
  minkq_mode of(minkq_query_kind kind) const {
    if (kind == MINKQ_QUERY_EE && swept) return MINKQ_MODE_BOX;
    if (kind == MINKQ_QUERY_EE && mode == MINKQ_MODE_SPHERE) return MINKQ_MODE_CAPSULE_EXACT;
    return mode;
  }
};
template <class Warn>
QueryModes query_modes(const std::string& word, bool leaf_exact, bool swept, bool has_ee, Warn&& warn) {
  QueryModes m{MINKQ_MODE_BOX, leaf_exact ? uint32_t(MINKQ_QUERY_LEAF_EXACT) : 0u, swept};
  if (word == "leaf_exact") {
    warn("--mode leaf_exact is deprecated: use --mode box --leaf-exact");
    m.flags = MINKQ_QUERY_LEAF_EXACT;
  } else if (word == "sphere") {
    m.mode = MINKQ_MODE_SPHERE;
    if (has_ee && !swept)
      warn("--mode sphere for EE is deprecated (sphere is a point query's test; EE ran and runs capsule_exact): use "
           "--mode capsule_exact, the same tests for VT and EE");
  } else if (word == "capsule_ray") {
    m.mode = MINKQ_MODE_CAPSULE_RAY;
  } else if (word == "capsule_exact") {
    m.mode = MINKQ_MODE_CAPSULE_EXACT;
  } else if (word != "box") {
    throw UsageError("--mode: unknown mode '" + word + "' (box, sphere, capsule_ray, capsule_exact)");
  }
  if (swept && m.flags)
    throw UsageError("--leaf-exact: swept queries (--to) report candidates for a narrow phase; use --mode box, "
                     "sphere, capsule_ray or capsule_exact without it");
  return m;
}

}  // namespace minkq::cli
