// Shared pieces of the bench programs: C API handles, pair sets, the comparison with the
// reference oracle, and the machine description written at the top of every result file.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <tbb/parallel_sort.h>

#include "harness.h"
#include "minkq.h"
#include "minkq.hpp"
#include "minkq/query_sources.h"
#include "minkq_reference.h"

namespace minkq::bench {

// Owning handles, check(), open_device(), new_result() and new_bvh() (capi/minkq.hpp).
using namespace minkq::cxx;

// A VT + EE scene with incident pairs dropped, edges derived by the library (the numbering of
// reference::derive_edges).
inline Scene create_scene(minkq_device* device, const std::vector<float>& xyz, const std::vector<int32_t>& tris,
                        uint32_t flags = MINKQ_SCENE_VT | MINKQ_SCENE_EE | MINKQ_SCENE_DROP_INCIDENT) {
  return new_mesh_scene(device, xyz.data(), xyz.size() / 3, tris.data(), tris.size() / 3, flags);
}

// Pairs packed by minkq::pack_pair (first << 32 | second), sorted: set operations by merge.
using PairSet = std::vector<uint64_t>;
inline uint64_t pack(int32_t a, int32_t b) { return pack_pair(a, b); }

inline PairSet to_set(const int32_t* pairs, uint64_t count) {
  PairSet s(count);
  for (uint64_t i = 0; i < count; ++i) s[i] = pack(pairs[2 * i], pairs[2 * i + 1]);
  tbb::parallel_sort(s.begin(), s.end());
  return s;
}
inline PairSet to_set(const reference::Pairs& p) {
  PairSet s(p.size());
  for (size_t i = 0; i < p.size(); ++i) s[i] = pack(p[i].first, p[i].second);
  std::sort(s.begin(), s.end());
  return s;
}
// Elements of `need` absent from `have` (both sorted).
inline uint64_t missing(const PairSet& need, const PairSet& have) {
  uint64_t m = 0;
  size_t j = 0;
  for (uint64_t x : need) {
    while (j < have.size() && have[j] < x) ++j;
    if (j == have.size() || have[j] != x) ++m;
  }
  return m;
}

inline std::string machine_line(const std::string& device_names) {
  char b[512];
  std::snprintf(b, sizeof b, "%s, %d online CPUs; minkq devices: %s; minkq %u (ABI %u)", cpu_model().c_str(),
                online_cpus(), device_names.c_str(), minkq_version(), minkq_abi_version());
  return b;
}

}  // namespace minkq::bench
