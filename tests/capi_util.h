// RAII helpers over the C API for the test suites, and pair-set utilities.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "minkq.h"
#include "minkq_reference.h"

namespace minkq::test {

using Pairs = std::vector<std::pair<int32_t, int32_t>>;

inline minkq_buffer host_buffer(const void* data, size_t count, size_t stride = 0) {
  return minkq_buffer{data, stride, count, MINKQ_MEMORY_HOST};
}

struct Device {
  minkq_device* handle = nullptr;
  explicit Device(const char* spec = "cpu") {
    const minkq_status status = minkq_device_create(spec, &handle);
    EXPECT_EQ(status, MINKQ_SUCCESS) << minkq_last_error_message();
  }
  ~Device() { minkq_device_release(handle); }
  Device(const Device&) = delete;
  Device& operator=(const Device&) = delete;
};

struct Scene {
  minkq_scene* handle = nullptr;
  Scene(minkq_device* device, const reference::Mesh& mesh, uint32_t flags) {
    minkq_scene_desc desc{};
    desc.flags = flags;
    desc.vertices = host_buffer(mesh.xyz.data(), mesh.xyz.size() / 3);
    desc.triangles = host_buffer(mesh.tris.data(), mesh.tris.size() / 3);
    const minkq_status status = minkq_scene_create(device, &desc, &handle);
    EXPECT_EQ(status, MINKQ_SUCCESS) << minkq_last_error_message();
  }
  ~Scene() { minkq_scene_release(handle); }
  Scene(const Scene&) = delete;
  Scene& operator=(const Scene&) = delete;

  std::vector<int32_t> edges() const {
    std::vector<int32_t> out(2 * minkq_scene_edge_count(handle));
    EXPECT_EQ(minkq_scene_edges(handle, out.data(), out.size() / 2), MINKQ_SUCCESS);
    return out;
  }

  // Runs a query (canonical order) and returns its pairs; fails the test on any error.
  Pairs query(minkq_query_kind kind, minkq_mode mode, float r, uint32_t flags = 0, uint64_t* digest = nullptr) {
    minkq_query_desc desc{kind, mode, flags | MINKQ_QUERY_CANONICAL | (digest ? MINKQ_QUERY_DIGEST : 0u), r};
    minkq_query_info info{};
    minkq_status status = minkq_scene_query(handle, &desc, nullptr, 0, MINKQ_MEMORY_HOST, &info);
    std::vector<int32_t> raw;
    if (status == MINKQ_ERROR_CAPACITY) {
      raw.resize(2 * info.count);
      status = minkq_scene_query(handle, &desc, raw.data(), info.count, MINKQ_MEMORY_HOST, &info);
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
  minkq_result* result = nullptr;
  EXPECT_EQ(minkq_result_create(&result), MINKQ_SUCCESS);
  const minkq_query_desc desc{kind, mode, flags | MINKQ_QUERY_STATS, r};
  EXPECT_EQ(minkq_scene_query_result(scene, &desc, result), MINKQ_SUCCESS) << minkq_last_error_message();
  const minkq_query_stats stats = minkq_result_stats(result);
  EXPECT_EQ(stats.candidates, minkq_result_count(result));
  minkq_result_release(result);
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
