// minkq_bench's C API suites (bench/suites/), each against its baseline in the same run, one
// file each: count.cpp (count.md: MINKQ_QUERY_COUNT against queries that store their pairs),
// float64.cpp (float64.md: the double input path against float32), swept.cpp (swept.md: swept
// steps by mode against box mode and the static queries). This header holds the helpers they
// share (the scenes through the C API and their pair sets) and their entry points; minkq_bench.cpp
// runs the suites asked for and writes their files.
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

namespace minkq::bench::suites {

namespace ref = minkq::reference;

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

// ---- The suites: each returns the text of its file, false in ok on a failed check -------------

// What every suite is given: the device, the data folder, the repeats, --quick, the machine
// line and the command that wrote the file.
struct SuiteRun {
  minkq_device* device;
  std::string data;
  int repeats;
  bool quick;
  std::string machine, by;
};

// float64.cpp: float64.md, the double path's cost against float32 on the same scenes.
std::string float64_report(const SuiteRun& run, bool& ok);
// swept.cpp: swept.md, swept steps by mode against box mode and the static queries.
std::string swept_report(const SuiteRun& run, bool& ok);
// geometries.cpp: geometries.md, scenes of many geometries (cloth on a body, batched worlds)
// against the concatenated mesh, Embree's rtcCollide and one scene per world.
std::string geometries_report(const SuiteRun& run, bool& ok);
// count.cpp: count.md, count-only queries against stored ones; `large` adds the 1M-triangle
// twisted sheet.
std::string count_report(const SuiteRun& run, bool large, bool& ok);

}  // namespace minkq::bench::suites
