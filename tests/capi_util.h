// Test-side helpers over the C API: handles (capi/minkq.hpp's) whose creation fails the test
// instead of throwing, a scene that runs canonical queries, and pair-set utilities.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "minkq.h"
#include "minkq.hpp"
#include "minkq_reference.h"

namespace minkq::test {

using Pairs = std::vector<std::pair<int32_t, int32_t>>;
using cxx::host_buffer;

// Adopts what create(&raw) made; a failed creation fails the test and leaves the handle empty.
template <class Handle, class Create>
Handle created(Create&& create) {
  typename Handle::pointer raw = nullptr;
  const minkq_status status = create(&raw);
  EXPECT_EQ(status, MINKQ_SUCCESS) << minkq_last_error_message();
  return Handle(raw);
}

struct Device : cxx::Device {
  explicit Device(const char* spec = "cpu")
      : cxx::Device(created<cxx::Device>([&](minkq_device** out) { return minkq_device_create(spec, out); })) {}
};

inline cxx::Scene new_scene(minkq_device* device, const minkq_scene_desc& desc) {
  return created<cxx::Scene>([&](minkq_scene** out) { return minkq_scene_create(device, &desc, out); });
}

// The mesh's vertices as a scene with `flags` reads them: its double input (xyz64) for a
// MINKQ_SCENE_FLOAT64 scene, else its floats.
inline minkq_buffer vertices_of(const reference::Mesh& mesh, uint32_t flags) {
  if (flags & MINKQ_SCENE_FLOAT64) return host_buffer(mesh.xyz64.data(), mesh.xyz64.size() / 3);
  return host_buffer(mesh.xyz.data(), mesh.xyz.size() / 3);
}

// Explicit edges are passed when the mesh has them and no triangles (an EE-only scene).
inline cxx::Scene new_scene(minkq_device* device, const reference::Mesh& mesh, uint32_t flags) {
  minkq_scene_desc desc{};
  desc.flags = flags;
  desc.vertices = vertices_of(mesh, flags);
  desc.triangles = host_buffer(mesh.tris.data(), mesh.tris.size() / 3);
  if (mesh.tris.empty()) desc.edges = host_buffer(mesh.edges.data(), mesh.edges.size() / 2);
  return new_scene(device, desc);
}

inline cxx::Bvh new_bvh(minkq_device* device, minkq_buffer boxes) {
  return created<cxx::Bvh>([&](minkq_bvh** out) { return minkq_bvh_create(device, boxes, out); });
}

inline cxx::Result new_result() {
  return created<cxx::Result>([](minkq_result** out) { return minkq_result_create(out); });
}

struct Scene : cxx::Scene {
  Scene(minkq_device* device, const reference::Mesh& mesh, uint32_t flags) : cxx::Scene(new_scene(device, mesh, flags)) {}

  std::vector<int32_t> edges() const { return edges_of(get()); }

  // The same for any scene: its edges in the numbering EE pairs use.
  static std::vector<int32_t> edges_of(const minkq_scene* scene) {
    std::vector<int32_t> out(2 * minkq_scene_edge_count(scene));
    EXPECT_EQ(minkq_scene_edges(scene, out.data(), out.size() / 2), MINKQ_SUCCESS) << minkq_last_error_message();
    return out;
  }

  // Runs a query (canonical order) and returns its pairs; fails the test on any error.
  Pairs query(minkq_query_kind kind, minkq_mode mode, float r, uint32_t flags = 0, uint64_t* digest = nullptr) {
    return query_pairs(get(), kind, mode, r, flags, digest);
  }

  // The same for any scene.
  static Pairs query_pairs(minkq_scene* scene, minkq_query_kind kind, minkq_mode mode, float r, uint32_t flags = 0,
                           uint64_t* digest = nullptr) {
    minkq_query_desc desc{kind, mode, flags | MINKQ_QUERY_CANONICAL | (digest ? uint32_t(MINKQ_QUERY_DIGEST) : 0u), r};
    minkq_query_info info{};
    minkq_status status = minkq_scene_query(scene, &desc, nullptr, 0, MINKQ_MEMORY_HOST, &info);
    std::vector<int32_t> raw;
    if (status == MINKQ_ERROR_CAPACITY) {
      raw.resize(2 * info.count);
      status = minkq_scene_query(scene, &desc, raw.data(), info.count, MINKQ_MEMORY_HOST, &info);
    }
    EXPECT_EQ(status, MINKQ_SUCCESS) << minkq_last_error_message();
    if (digest) *digest = info.digest;
    Pairs pairs(info.count);
    for (size_t i = 0; i < pairs.size(); ++i) pairs[i] = {raw[2 * i], raw[2 * i + 1]};
    return pairs;
  }
};

// Runs a query with MINKQ_QUERY_STATS into a result; returns its work counts.
inline minkq_query_stats work_of(minkq_scene* scene, minkq_query_kind kind, minkq_mode mode, float r,
                                 uint32_t flags = 0) {
  const cxx::Result result = new_result();
  const minkq_query_desc desc{kind, mode, flags | MINKQ_QUERY_STATS, r};
  EXPECT_EQ(minkq_scene_query_result(scene, &desc, result.get()), MINKQ_SUCCESS) << minkq_last_error_message();
  const minkq_query_stats stats = minkq_result_stats(result.get());
  EXPECT_EQ(stats.candidates, minkq_result_count(result.get()));
  return stats;
}

inline bool is_subset(const Pairs& small, const Pairs& large) {
  return std::includes(large.begin(), large.end(), small.begin(), small.end());
}

inline Pairs difference(const Pairs& a, const Pairs& b) {
  Pairs out;
  std::set_difference(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(out));
  return out;
}

inline std::string describe(const Pairs& pairs, size_t max = 5) {
  std::string text;
  for (size_t i = 0; i < pairs.size() && i < max; ++i)
    text += "(" + std::to_string(pairs[i].first) + "," + std::to_string(pairs[i].second) + ") ";
  return text + (pairs.size() > max ? "..." : "");
}

}  // namespace minkq::test
