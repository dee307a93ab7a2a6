// What the CUDA test files share (test_cuda.cpp, test_cuda_inputs.cpp, test_cuda_async.cpp):
// the fixture that skips without a usable device, scenes and queries on both backends, and the
// comparisons of a CUDA query's outcome with the CPU's (pairs, digests and work counts).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "capi_util.h"
#include "minkq/query_sources.h"
#include "test_util.h"

#if defined(MINKQ_TEST_HAVE_CUDART)
#include <cuda_runtime.h>
#endif

#define SKIP_WITHOUT_CUDA()                                                                          \
  if (minkq_cuda_device_count() == 0)                                                                \
  GTEST_SKIP() << "no CUDA device: minkq_cuda_device_count() == 0 (built without CUDA, no driver or " \
                  "no GPU)"

namespace minkq::cuda_test {

using reference::Mesh;
using test::host_buffer;

inline constexpr uint32_t kBoth = MINKQ_SCENE_VT | MINKQ_SCENE_EE;

// Scenes and BVHs whose failed creation fails the test (capi_util.h).
inline cxx::Scene make_scene(minkq_device* device, const Mesh& mesh, uint32_t flags, minkq_buffer vertices) {
  minkq_scene_desc desc{};
  desc.flags = flags;
  desc.vertices = vertices;
  desc.triangles = host_buffer(mesh.tris.data(), mesh.triangle_count());
  return test::new_scene(device, desc);
}

inline cxx::Scene make_scene(minkq_device* device, const Mesh& mesh, uint32_t flags) { return test::new_scene(device, mesh, flags); }

// One query's outcome: exact count, digest and the pairs (2 int32 each, host memory).
struct Outcome {
  uint64_t count = 0;
  uint64_t digest = 0;
  minkq_query_stats stats{};
  std::vector<int32_t> pairs;
};

// Runs a query twice: once to learn the count, once into a buffer of exactly that size.
template <class Query>
Outcome run_exact(Query query) {
  Outcome out;
  minkq_query_info info{};
  minkq_status status = query(nullptr, 0, &info);
  if (status == MINKQ_ERROR_CAPACITY) {
    out.pairs.resize(2 * info.count);
    status = query(out.pairs.data(), info.count, &info);
  }
  EXPECT_EQ(status, MINKQ_SUCCESS) << minkq_last_error_message();
  out.count = info.count;
  out.digest = info.digest;
  out.stats = info.stats;
  out.pairs.resize(2 * info.count);
  return out;
}

inline Outcome scene_query(minkq_scene* scene, minkq_query_kind kind, minkq_mode mode, float r, uint32_t flags) {
  const minkq_query_desc desc{kind, mode, flags, r};
  return run_exact([&](int32_t* pairs, size_t capacity, minkq_query_info* info) {
    return minkq_scene_query(scene, &desc, pairs, capacity, MINKQ_MEMORY_HOST, info);
  });
}

// Lexicographic order, for comparing outputs that were not asked to be canonical.
inline std::vector<int32_t> sorted_pairs(const std::vector<int32_t>& raw) {
  std::vector<uint64_t> keys(raw.size() / 2);
  for (size_t i = 0; i < keys.size(); ++i) keys[i] = pack_pair(raw[2 * i], raw[2 * i + 1]);
  std::sort(keys.begin(), keys.end());
  std::vector<int32_t> out(raw.size());
  for (size_t i = 0; i < keys.size(); ++i) {
    const Pair pair = unpack_pair(keys[i]);
    out[2 * i] = pair.first;
    out[2 * i + 1] = pair.second;
  }
  return out;
}

// Equal pair lists, reported by count and first difference rather than by dumping them.
inline void expect_same_pairs(const std::vector<int32_t>& cpu, const std::vector<int32_t>& cuda, const std::string& what) {
  ASSERT_EQ(cpu.size(), cuda.size()) << what << ": " << cpu.size() / 2 << " pairs on cpu, " << cuda.size() / 2
                                     << " on cuda";
  const auto diff = std::mismatch(cpu.begin(), cpu.end(), cuda.begin());
  if (diff.first != cpu.end()) {
    const size_t i = size_t(diff.first - cpu.begin()) / 2;
    ADD_FAILURE() << what << ": pair " << i << " is (" << cpu[2 * i] << "," << cpu[2 * i + 1] << ") on cpu but ("
                  << cuda[2 * i] << "," << cuda[2 * i + 1] << ") on cuda";
  }
}

inline void expect_same(const Outcome& cpu, const Outcome& cuda, const std::string& what) {
  EXPECT_EQ(cpu.count, cuda.count) << what;
  EXPECT_EQ(cpu.digest, cuda.digest) << what;
  // Work counts depend only on the tree and the queries (zero where not asked for).
  EXPECT_EQ(cpu.stats.nodes_visited, cuda.stats.nodes_visited) << what;
  EXPECT_EQ(cpu.stats.node_tests, cuda.stats.node_tests) << what;
  EXPECT_EQ(cpu.stats.primitive_tests, cuda.stats.primitive_tests) << what;
  EXPECT_EQ(cpu.stats.candidates, cuda.stats.candidates) << what;
  expect_same_pairs(cpu.pairs, cuda.pairs, what);
}

struct ModeCase {
  minkq_query_kind kind;
  minkq_mode mode;
  const char* name;
};
// Every mode each kind accepts (sphere is for point queries only).
inline const ModeCase kModes[] = {
    {MINKQ_QUERY_VT, MINKQ_MODE_BOX, "VT box"},
    {MINKQ_QUERY_VT, MINKQ_MODE_SPHERE, "VT sphere"},
    {MINKQ_QUERY_VT, MINKQ_MODE_CAPSULE_RAY, "VT capsule_ray"},
    {MINKQ_QUERY_VT, MINKQ_MODE_CAPSULE_EXACT, "VT capsule_exact"},
    {MINKQ_QUERY_EE, MINKQ_MODE_BOX, "EE box"},
    {MINKQ_QUERY_EE, MINKQ_MODE_CAPSULE_RAY, "EE capsule_ray"},
    {MINKQ_QUERY_EE, MINKQ_MODE_CAPSULE_EXACT, "EE capsule_exact"},
};
// Every mode of the codimensional kinds (MINKQ_SCENE_VV, MINKQ_SCENE_EV).
inline const ModeCase kCodimModes[] = {
    {MINKQ_QUERY_VV, MINKQ_MODE_BOX, "VV box"},
    {MINKQ_QUERY_VV, MINKQ_MODE_SPHERE, "VV sphere"},
    {MINKQ_QUERY_VV, MINKQ_MODE_CAPSULE_RAY, "VV capsule_ray"},
    {MINKQ_QUERY_VV, MINKQ_MODE_CAPSULE_EXACT, "VV capsule_exact"},
    {MINKQ_QUERY_EV, MINKQ_MODE_BOX, "EV box"},
    {MINKQ_QUERY_EV, MINKQ_MODE_SPHERE, "EV sphere"},
    {MINKQ_QUERY_EV, MINKQ_MODE_CAPSULE_RAY, "EV capsule_ray"},
    {MINKQ_QUERY_EV, MINKQ_MODE_CAPSULE_EXACT, "EV capsule_exact"},
};

// Every mode, with and without the leaf test: identical canonical pairs, digests and work
// counts; the non-canonical CUDA output is the same set in some order.
inline void compare_all_modes(minkq_scene* cpu, minkq_scene* cuda, float r, const std::string& label) {
  for (const ModeCase& m : kModes)
    for (uint32_t leaf : {0u, uint32_t(MINKQ_QUERY_LEAF_EXACT)}) {
      const std::string what = label + " " + m.name + (leaf ? " leaf_exact" : "") + " r=" + std::to_string(r);
      const uint32_t flags = leaf | MINKQ_QUERY_CANONICAL | MINKQ_QUERY_DIGEST | MINKQ_QUERY_STATS;
      const Outcome expected = scene_query(cpu, m.kind, m.mode, r, flags);
      expect_same(expected, scene_query(cuda, m.kind, m.mode, r, flags), what);
      const Outcome unordered = scene_query(cuda, m.kind, m.mode, r, leaf);
      EXPECT_EQ(unordered.count, expected.count) << what << " (not canonical)";
      expect_same_pairs(expected.pairs, sorted_pairs(unordered.pairs), what + " (not canonical)");
    }
}

struct Scenes {
  std::vector<std::pair<std::string, Mesh>> meshes;
  explicit Scenes(uint64_t seed) {
    meshes.emplace_back("soup", reference::random_soup(3000, seed, 0.08));
    meshes.emplace_back("twisted sheet", reference::twisted_sheet(40, 3.0));
  }
};

class Cuda : public ::testing::Test {
 protected:
  void SetUp() override {
    SKIP_WITHOUT_CUDA();
    seed = test::fresh_seed();
  }
  uint64_t seed = 0;
};

// Pairs of a user-box BVH query, host buffers in and out.
inline Outcome bvh_query(minkq_bvh* bvh, minkq_shape shape, minkq_mode mode, float r, const std::vector<Vec3>& first,
                  const std::vector<Vec3>& second) {
  minkq_bvh_query_desc desc{};
  desc.shape = shape;
  desc.mode = mode;
  desc.flags = MINKQ_QUERY_CANONICAL | MINKQ_QUERY_DIGEST;
  desc.radius = r;
  desc.first = host_buffer(first.data(), first.size());
  desc.second = host_buffer(second.empty() ? nullptr : second.data(), second.size());
  return run_exact([&](int32_t* pairs, size_t capacity, minkq_query_info* info) {
    return minkq_bvh_query(bvh, &desc, pairs, capacity, MINKQ_MEMORY_HOST, info);
  });
}

inline cxx::Bvh make_bvh(minkq_device* device, const std::vector<Box>& boxes) {
  return test::new_bvh(device, host_buffer(boxes.data(), boxes.size()));
}

#if defined(MINKQ_TEST_HAVE_CUDART)

// One cudaMalloc block, freed on scope exit.
struct DeviceMemory {
  void* ptr = nullptr;
  explicit DeviceMemory(size_t bytes) { EXPECT_EQ(cudaMalloc(&ptr, bytes ? bytes : 1), cudaSuccess); }
  ~DeviceMemory() { cudaFree(ptr); }
  DeviceMemory(DeviceMemory&& other) noexcept : ptr(other.ptr) { other.ptr = nullptr; }
  DeviceMemory& operator=(const DeviceMemory&) = delete;
  template <class T>
  T* as() const { return static_cast<T*>(ptr); }
};

// Vertices copied to device memory as records of `stride` bytes (any stride >= 3 coordinates;
// strides that are not a multiple of the coordinate's size make the backend read bytes).
template <class T>
DeviceMemory device_vertices(const std::vector<T>& xyz, size_t stride) {
  const size_t n = xyz.size() / 3;
  std::vector<unsigned char> records(n * stride, 0xAB);
  for (size_t v = 0; v < n; ++v) std::memcpy(&records[v * stride], &xyz[3 * v], 3 * sizeof(T));
  DeviceMemory memory(records.size());
  EXPECT_EQ(cudaMemcpy(memory.ptr, records.data(), records.size(), cudaMemcpyHostToDevice), cudaSuccess);
  return memory;
}

inline minkq_buffer device_buffer(const void* data, size_t count, size_t stride) {
  return minkq_buffer{data, stride, count, MINKQ_MEMORY_DEVICE};
}
#endif  // MINKQ_TEST_HAVE_CUDART

}  // namespace minkq::cuda_test
