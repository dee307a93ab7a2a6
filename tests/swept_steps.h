// A swept step for the tests (positions at t = 0 and t = 1 of the same mesh, float or float64
// input) and the static oracle's contacts at sampled times of it: a lower bound of the swept
// contacts (every pair found at a sampled t comes within r during the step).
#pragma once

#include <algorithm>
#include <iterator>
#include <utility>
#include <vector>

#include "minkq.h"
#include "minkq_reference.h"

namespace minkq::test {

using reference::Mesh;

inline constexpr uint32_t kSweptScene = MINKQ_SCENE_VT | MINKQ_SCENE_EE | MINKQ_SCENE_DROP_INCIDENT;

// The positions of a step: `from` at t = 0, `to` at t = 1 (same topology); float64 input when
// both carry xyz64.
struct Step {
  Mesh from, to;
  bool float64() const { return !from.xyz64.empty(); }
  uint32_t flags() const { return kSweptScene | (float64() ? uint32_t(MINKQ_SCENE_FLOAT64) : 0u); }
  // The mesh at time t, in double (or float) as the input is.
  Mesh at(double t) const {
    Mesh m = from;
    if (float64()) {
      std::vector<double> xyz(from.xyz64.size());
      for (size_t i = 0; i < xyz.size(); ++i) xyz[i] = from.xyz64[i] + t * (to.xyz64[i] - from.xyz64[i]);
      reference::set_float64(m, std::move(xyz));
    } else {
      std::vector<double> xyz(from.xyz.size());
      for (size_t i = 0; i < xyz.size(); ++i) xyz[i] = double(from.xyz[i]) + t * (double(to.xyz[i]) - from.xyz[i]);
      reference::set_float64(m, std::move(xyz));  // the oracle reads the exact positions between
    }
    return m;
  }
};

// Contacts of the static oracle at `samples` + 1 evenly spaced times, united.
inline std::pair<reference::Pairs, reference::Pairs> sampled_contacts(const Step& step, double r, int samples) {
  reference::Pairs vt, ee;
  for (int k = 0; k <= samples; ++k) {
    const Mesh m = step.at(double(k) / samples);
    for (auto [all, found] : {std::pair{&vt, reference::vt_contacts(m, r, true)},
                              std::pair{&ee, reference::ee_contacts(m, r, true)}}) {
      reference::Pairs merged;
      std::set_union(all->begin(), all->end(), found.begin(), found.end(), std::back_inserter(merged));
      *all = std::move(merged);
    }
  }
  return {vt, ee};
}

}  // namespace minkq::test
