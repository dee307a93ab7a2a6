// minkq_float64_swept's shared parts (bench/float64_swept/): the small helpers both studies use
// (medians, geomeans, the date, the scenes through the C API and their pair sets) and the two
// studies' entry points, one file each: float64.cpp writes float64.md, swept.cpp swept.md;
// main.cpp reads the options and runs the studies asked for.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <ctime>
#include <string>
#include <type_traits>
#include <vector>

#include "common.h"
#include "scenes.h"

namespace minkq::bench::float64_swept {

namespace ref = minkq::reference;

inline double geomean(const std::vector<double>& v) {
  if (v.empty()) return NAN;
  double s = 0;
  for (double x : v) s += std::log(x);
  return std::exp(s / double(v.size()));
}

inline std::string utc_now() {
  char when[64];
  const std::time_t now = std::time(nullptr);
  std::strftime(when, sizeof when, "%Y-%m-%d %H:%M UTC", std::gmtime(&now));
  return when;
}

inline float scene_radius(const SceneFrames& sc) { return float(sc.radius_factor * sc.mean_edge); }

// ---- Scenes through the C API ----------------------------------------------------------------

constexpr uint32_t kFlags = MINKQ_SCENE_VT | MINKQ_SCENE_EE | MINKQ_SCENE_DROP_INCIDENT;

inline minkq_buffer buffer_of(const std::vector<float>& x) { return host_buffer(x.data(), x.size() / 3, 12); }
inline minkq_buffer buffer_of(const std::vector<double>& x) { return host_buffer(x.data(), x.size() / 3, 24); }

template <class T>
Scene create(minkq_device* device, const std::vector<T>& xyz, const std::vector<int32_t>& tris) {
  minkq_scene_desc desc{};
  desc.flags = kFlags | (std::is_same<T, double>::value ? uint32_t(MINKQ_SCENE_FLOAT64) : 0u);
  desc.vertices = buffer_of(xyz);
  desc.triangles = host_buffer(tris.data(), tris.size() / 3, 12);
  desc.edges = host_buffer(nullptr, 0);
  return new_scene(device, desc);
}

inline PairSet pairs_of(const minkq_result* r) { return to_set(minkq_result_pairs(r), minkq_result_count(r)); }

inline void query(minkq_scene* scene, minkq_query_kind kind, minkq_mode mode, uint32_t flags, float r, minkq_result* out) {
  const minkq_query_desc q{kind, mode, flags, r};
  check(minkq_scene_query_result(scene, &q, out), "minkq_scene_query_result");
}

inline bool includes(const PairSet& big, const PairSet& small) {
  return std::includes(big.begin(), big.end(), small.begin(), small.end());
}

// ---- The studies: each returns the text of its file, false in ok on a failed check ------------

// float64.cpp: float64.md, the double path's cost against float32 on the same scenes.
std::string float64_report(minkq_device* device, const std::string& data, int repeats, bool quick,
                           const std::string& machine, const std::string& by, bool& ok);
// swept.cpp: swept.md, swept steps by mode against box mode and the static queries.
std::string swept_report(minkq_device* device, const std::string& data, int repeats, bool quick,
                         const std::string& machine, const std::string& by, bool& ok);

}  // namespace minkq::bench::float64_swept
