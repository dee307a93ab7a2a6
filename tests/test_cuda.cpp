// The CUDA backend against the CPU backend through the C API: the same trees and the same
// per-element code, so every query must give the identical canonical pair list (and digest)
// in every mode, after refits, with strided and device-memory inputs, and with small output
// buffers. Skips (saying why) where no CUDA device is usable.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "async_checks.h"
#include "capi_util.h"
#include "minkq/queries.h"
#include "test_util.h"
#include "tree_counts.h"

#if defined(MINKQ_TEST_HAVE_CUDART)
#include <cuda_runtime.h>
#endif

namespace minkq {
namespace {

using reference::Mesh;
using test::host_buffer;

constexpr uint32_t kBoth = MINKQ_SCENE_VT | MINKQ_SCENE_EE;

#define SKIP_WITHOUT_CUDA()                                                                          \
  if (minkq_cuda_device_count() == 0)                                                                \
  GTEST_SKIP() << "no CUDA device: minkq_cuda_device_count() == 0 (built without CUDA, no driver or " \
                  "no GPU)"

// Scenes and BVHs whose failed creation fails the test (capi_util.h).
cxx::Scene make_scene(minkq_device* device, const Mesh& mesh, uint32_t flags, minkq_buffer vertices) {
  minkq_scene_desc desc{};
  desc.flags = flags;
  desc.vertices = vertices;
  desc.triangles = host_buffer(mesh.tris.data(), mesh.triangle_count());
  return test::new_scene(device, desc);
}

cxx::Scene make_scene(minkq_device* device, const Mesh& mesh, uint32_t flags) { return test::new_scene(device, mesh, flags); }

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

Outcome scene_query(minkq_scene* scene, minkq_query_kind kind, minkq_mode mode, float r, uint32_t flags) {
  const minkq_query_desc desc{kind, mode, flags, r};
  return run_exact([&](int32_t* pairs, size_t capacity, minkq_query_info* info) {
    return minkq_scene_query(scene, &desc, pairs, capacity, MINKQ_MEMORY_HOST, info);
  });
}

// Lexicographic order, for comparing outputs that were not asked to be canonical.
std::vector<int32_t> sorted_pairs(const std::vector<int32_t>& raw) {
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
void expect_same_pairs(const std::vector<int32_t>& cpu, const std::vector<int32_t>& cuda, const std::string& what) {
  ASSERT_EQ(cpu.size(), cuda.size()) << what << ": " << cpu.size() / 2 << " pairs on cpu, " << cuda.size() / 2
                                     << " on cuda";
  const auto diff = std::mismatch(cpu.begin(), cpu.end(), cuda.begin());
  if (diff.first != cpu.end()) {
    const size_t i = size_t(diff.first - cpu.begin()) / 2;
    ADD_FAILURE() << what << ": pair " << i << " is (" << cpu[2 * i] << "," << cpu[2 * i + 1] << ") on cpu but ("
                  << cuda[2 * i] << "," << cuda[2 * i + 1] << ") on cuda";
  }
}

void expect_same(const Outcome& cpu, const Outcome& cuda, const std::string& what) {
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
const ModeCase kModes[] = {
    {MINKQ_QUERY_VT, MINKQ_MODE_BOX, "VT box"},
    {MINKQ_QUERY_VT, MINKQ_MODE_SPHERE, "VT sphere"},
    {MINKQ_QUERY_VT, MINKQ_MODE_CAPSULE_RAY, "VT capsule_ray"},
    {MINKQ_QUERY_VT, MINKQ_MODE_CAPSULE_EXACT, "VT capsule_exact"},
    {MINKQ_QUERY_EE, MINKQ_MODE_BOX, "EE box"},
    {MINKQ_QUERY_EE, MINKQ_MODE_CAPSULE_RAY, "EE capsule_ray"},
    {MINKQ_QUERY_EE, MINKQ_MODE_CAPSULE_EXACT, "EE capsule_exact"},
};

// Every mode, with and without the leaf test: identical canonical pairs, digests and work
// counts; the non-canonical CUDA output is the same set in some order.
void compare_all_modes(minkq_scene* cpu, minkq_scene* cuda, float r, const std::string& label) {
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

TEST_F(Cuda, device_is_named_and_missing_ordinals_are_unsupported) {
  test::Device cuda("cuda");
  ASSERT_NE(cuda.get(), nullptr);
  EXPECT_EQ(minkq_device_backend(cuda.get()), MINKQ_BACKEND_CUDA);
  EXPECT_EQ(std::string(minkq_device_name(cuda.get())).rfind("cuda:0 (", 0), 0u) << minkq_device_name(cuda.get());
  minkq_device* missing = nullptr;
  const std::string spec = "cuda:" + std::to_string(minkq_cuda_device_count());
  EXPECT_EQ(minkq_device_create(spec.c_str(), &missing), MINKQ_ERROR_UNSUPPORTED);
  EXPECT_EQ(missing, nullptr);
  EXPECT_FALSE(std::string(minkq_last_error_message()).empty());
}

TEST_F(Cuda, every_mode_matches_cpu_with_and_without_leaf_test) {
  test::Device cpu("cpu"), cuda("cuda");
  for (const auto& [name, mesh] : Scenes(seed).meshes)
    for (bool drop : {false, true}) {
      const uint32_t flags = kBoth | (drop ? uint32_t(MINKQ_SCENE_DROP_INCIDENT) : 0u);
      cxx::Scene a = make_scene(cpu.get(), mesh, flags), b = make_scene(cuda.get(), mesh, flags);
      ASSERT_TRUE(a && b);
      const double edge = reference::mean_edge_length(mesh);
      for (double factor : {0.1, 1.0})
        compare_all_modes(a.get(), b.get(), float(factor * edge), name + (drop ? " drop_incident" : ""));
    }
}

TEST_F(Cuda, refit_matches_cpu_after_moving_vertices) {
  test::Device cpu("cpu"), cuda("cuda");
  test::Random rng(seed);
  for (const auto& [name, mesh] : Scenes(seed).meshes) {
    cxx::Scene a = make_scene(cpu.get(), mesh, kBoth), b = make_scene(cuda.get(), mesh, kBoth);
    ASSERT_TRUE(a && b);
    const float r = float(0.5 * reference::mean_edge_length(mesh));
    for (int step = 0; step < 3; ++step) {
      // Moved vertices, passed with a 16-byte stride (padding float) to exercise the gather.
      std::vector<float> moved(4 * mesh.vertex_count());
      for (size_t v = 0; v < mesh.vertex_count(); ++v) {
        const float angle = 0.2f * float(step + 1) * mesh.xyz[3 * v];
        const float y = mesh.xyz[3 * v + 1], z = mesh.xyz[3 * v + 2];
        moved[4 * v] = mesh.xyz[3 * v] + rng.uniform(-0.01f, 0.01f);
        moved[4 * v + 1] = std::cos(angle) * y - std::sin(angle) * z;
        moved[4 * v + 2] = std::sin(angle) * y + std::cos(angle) * z;
        moved[4 * v + 3] = std::numeric_limits<float>::quiet_NaN();  // never read
      }
      const minkq_buffer buffer = host_buffer(moved.data(), mesh.vertex_count(), 4 * sizeof(float));
      ASSERT_EQ(minkq_scene_refit(a.get(), buffer), MINKQ_SUCCESS) << minkq_last_error_message();
      ASSERT_EQ(minkq_scene_refit(b.get(), buffer), MINKQ_SUCCESS) << minkq_last_error_message();
      compare_all_modes(a.get(), b.get(), r, name + " refit " + std::to_string(step));
    }
  }
}

// A rebuild on either backend builds the same tree (same pairs, same work counts through
// compare_all_modes), and tree growth agrees up to the rounding of the device's sum.
TEST_F(Cuda, rebuild_and_tree_growth_match_cpu) {
  test::Device cpu("cpu"), cuda("cuda");
  const Mesh flat = reference::twisted_sheet(40, 0.0), wrung = reference::twisted_sheet(40, 3.0);
  cxx::Scene a = make_scene(cpu.get(), flat, kBoth), b = make_scene(cuda.get(), flat, kBoth);
  ASSERT_TRUE(a && b);
  const float r = float(0.5 * reference::mean_edge_length(wrung));
  const minkq_buffer moved = host_buffer(wrung.xyz.data(), wrung.vertex_count());
  auto growth_of = [](minkq_scene* scene) {
    double g = -1.0;
    EXPECT_EQ(minkq_scene_tree_growth(scene, &g), MINKQ_SUCCESS) << minkq_last_error_message();
    return g;
  };
  ASSERT_EQ(minkq_scene_refit(a.get(), moved), MINKQ_SUCCESS) << minkq_last_error_message();
  ASSERT_EQ(minkq_scene_refit(b.get(), moved), MINKQ_SUCCESS) << minkq_last_error_message();
  EXPECT_NEAR(growth_of(b.get()), growth_of(a.get()), 1e-12 * growth_of(a.get()));
  EXPECT_GT(growth_of(b.get()), 1.5);
  ASSERT_EQ(minkq_scene_rebuild(a.get(), moved), MINKQ_SUCCESS) << minkq_last_error_message();
  ASSERT_EQ(minkq_scene_rebuild(b.get(), moved), MINKQ_SUCCESS) << minkq_last_error_message();
  EXPECT_EQ(growth_of(a.get()), 1.0);
  EXPECT_EQ(growth_of(b.get()), 1.0);
  compare_all_modes(a.get(), b.get(), r, "wrung sheet after rebuild");
}

TEST_F(Cuda, capacity_returns_the_exact_count_and_writes_nothing_past_the_buffer) {
  test::Device cpu("cpu"), cuda("cuda");
  const Mesh mesh = reference::random_soup(3000, seed, 0.08);
  cxx::Scene a = make_scene(cpu.get(), mesh, kBoth), b = make_scene(cuda.get(), mesh, kBoth);
  ASSERT_TRUE(a && b);
  const minkq_query_desc desc{MINKQ_QUERY_EE, MINKQ_MODE_BOX, MINKQ_QUERY_CANONICAL | MINKQ_QUERY_DIGEST,
                              float(reference::mean_edge_length(mesh))};
  const Outcome expected = scene_query(a.get(), desc.kind, desc.mode, desc.radius, desc.flags);
  ASSERT_GT(expected.count, 2u);
  minkq_query_info info{};
  EXPECT_EQ(minkq_scene_query(b.get(), &desc, nullptr, 0, MINKQ_MEMORY_HOST, &info), MINKQ_ERROR_CAPACITY);
  EXPECT_EQ(info.count, expected.count);

  const size_t capacity = size_t(expected.count) - 1, guard = 64;
  const int32_t sentinel = -7;
  std::vector<int32_t> buffer(2 * (capacity + guard), sentinel);
  EXPECT_EQ(minkq_scene_query(b.get(), &desc, buffer.data(), capacity, MINKQ_MEMORY_HOST, &info), MINKQ_ERROR_CAPACITY);
  EXPECT_EQ(info.count, expected.count);
  for (size_t i = 2 * capacity; i < buffer.size(); ++i) ASSERT_EQ(buffer[i], sentinel) << "written past capacity at " << i;

  // Exactly enough room, and more than enough: all pairs, nothing past the count.
  for (size_t room : {size_t(expected.count), size_t(expected.count) + guard}) {
    std::vector<int32_t> out(2 * (room + guard), sentinel);
    ASSERT_EQ(minkq_scene_query(b.get(), &desc, out.data(), room, MINKQ_MEMORY_HOST, &info), MINKQ_SUCCESS)
        << minkq_last_error_message();
    EXPECT_EQ(info.count, expected.count);
    EXPECT_EQ(info.digest, expected.digest);
    for (size_t i = 2 * expected.count; i < out.size(); ++i) ASSERT_EQ(out[i], sentinel) << "written past count at " << i;
    out.resize(2 * expected.count);
    expect_same_pairs(expected.pairs, out, "room " + std::to_string(room));
  }
}

// Pairs of a user-box BVH query, host buffers in and out.
Outcome bvh_query(minkq_bvh* bvh, minkq_shape shape, minkq_mode mode, float r, const std::vector<Vec3>& first,
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

cxx::Bvh make_bvh(minkq_device* device, const std::vector<Box>& boxes) {
  return test::new_bvh(device, host_buffer(boxes.data(), boxes.size()));
}

TEST_F(Cuda, user_box_queries_match_cpu_for_every_shape_and_after_refit) {
  test::Device cpu("cpu"), cuda("cuda");
  test::Random rng(seed);
  auto random_boxes = [&](int n, float scale) {
    std::vector<Box> boxes(static_cast<size_t>(n));
    for (Box& b : boxes) b = rng.box(rng.vec3(0.0f, 1.0f), scale);
    return boxes;
  };
  std::vector<Box> boxes = random_boxes(4000, 0.02f);
  cxx::Bvh a = make_bvh(cpu.get(), boxes), b = make_bvh(cuda.get(), boxes);
  ASSERT_TRUE(a && b);
  const int nq = 3000;
  std::vector<Vec3> p0(nq), p1(nq), lo(nq), hi(nq);
  for (int i = 0; i < nq; ++i) {
    p0[i] = rng.vec3(0.0f, 1.0f);
    p1[i] = p0[i] + rng.vec3(-0.05f, 0.05f);
    const Box q = rng.box(p0[i], 0.03f);
    lo[i] = q.lo;
    hi[i] = q.hi;
  }
  for (int round = 0; round < 2; ++round) {
    const std::string tag = round ? " after refit" : "";
    for (float r : {0.0f, 0.01f, 0.04f}) {
      const std::string at = " r=" + std::to_string(r) + tag;
      for (minkq_mode mode : {MINKQ_MODE_BOX, MINKQ_MODE_SPHERE})
        expect_same(bvh_query(a.get(), MINKQ_SHAPE_SPHERE, mode, r, p0, {}),
                    bvh_query(b.get(), MINKQ_SHAPE_SPHERE, mode, r, p0, {}), "spheres mode " + std::to_string(mode) + at);
      for (minkq_mode mode : {MINKQ_MODE_BOX, MINKQ_MODE_CAPSULE_RAY, MINKQ_MODE_CAPSULE_EXACT})
        expect_same(bvh_query(a.get(), MINKQ_SHAPE_CAPSULE, mode, r, p0, p1),
                    bvh_query(b.get(), MINKQ_SHAPE_CAPSULE, mode, r, p0, p1), "capsules mode " + std::to_string(mode) + at);
    }
    expect_same(bvh_query(a.get(), MINKQ_SHAPE_BOX, MINKQ_MODE_BOX, 0.0f, lo, hi),
                bvh_query(b.get(), MINKQ_SHAPE_BOX, MINKQ_MODE_BOX, 0.0f, lo, hi), "boxes" + tag);
    boxes = random_boxes(int(boxes.size()), 0.03f);
    ASSERT_EQ(minkq_bvh_refit(a.get(), host_buffer(boxes.data(), boxes.size())), MINKQ_SUCCESS);
    ASSERT_EQ(minkq_bvh_refit(b.get(), host_buffer(boxes.data(), boxes.size())), MINKQ_SUCCESS)
        << minkq_last_error_message();
  }
}

TEST_F(Cuda, single_box_and_tiny_scenes_match_cpu) {
  test::Device cpu("cpu"), cuda("cuda");
  for (int n : {1, 2, 3}) {
    std::vector<Box> boxes;
    for (int i = 0; i < n; ++i) boxes.push_back({{float(i), 0, 0}, {float(i) + 0.5f, 1, 1}});
    cxx::Bvh a = make_bvh(cpu.get(), boxes), b = make_bvh(cuda.get(), boxes);
    ASSERT_TRUE(a && b);
    const std::vector<Vec3> centres = {{0.25f, 0.5f, 0.5f}, {1.7f, 0.5f, 0.5f}, {9, 9, 9}};
    expect_same(bvh_query(a.get(), MINKQ_SHAPE_SPHERE, MINKQ_MODE_SPHERE, 0.3f, centres, {}),
                bvh_query(b.get(), MINKQ_SHAPE_SPHERE, MINKQ_MODE_SPHERE, 0.3f, centres, {}),
                std::to_string(n) + " boxes");
  }
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

minkq_buffer device_buffer(const void* data, size_t count, size_t stride) {
  return minkq_buffer{data, stride, count, MINKQ_MEMORY_DEVICE};
}

// MINKQ_QUERY_COUNT on CUDA: the CPU's exact count in every mode, blocking (host info) and
// stream-ordered (a device count), with the sentinel-filled pair buffer left alone.
TEST_F(Cuda, count_only_queries_match_cpu_counts_blocking_and_async) {
  test::Device cpu("cpu"), cuda("cuda");
  const Mesh mesh = reference::random_soup(3000, seed, 0.08);
  cxx::Scene a = make_scene(cpu.get(), mesh, kBoth), b = make_scene(cuda.get(), mesh, kBoth);
  ASSERT_TRUE(a && b);
  const float r = float(reference::mean_edge_length(mesh));
  const int32_t sentinel = -7;
  DeviceMemory pairs(64 * sizeof(int32_t)), count(sizeof(uint64_t));
  const std::vector<int32_t> fill(64, sentinel);
  ASSERT_EQ(cudaMemcpy(pairs.ptr, fill.data(), 64 * sizeof(int32_t), cudaMemcpyHostToDevice), cudaSuccess);
  for (const ModeCase& m : kModes)
    for (uint32_t leaf : {0u, uint32_t(MINKQ_QUERY_LEAF_EXACT)}) {
      const std::string what = std::string(m.name) + (leaf ? " leaf_exact" : "");
      const Outcome expected = scene_query(a.get(), m.kind, m.mode, r, leaf | MINKQ_QUERY_STATS);
      const minkq_query_desc desc{m.kind, m.mode, leaf | MINKQ_QUERY_COUNT | MINKQ_QUERY_STATS, r};
      minkq_query_info info{};
      ASSERT_EQ(minkq_scene_query(b.get(), &desc, nullptr, 0, MINKQ_MEMORY_HOST, &info), MINKQ_SUCCESS)
          << what << ": " << minkq_last_error_message();
      EXPECT_EQ(info.count, expected.count) << what;
      EXPECT_EQ(info.stats.nodes_visited, expected.stats.nodes_visited) << what;
      const minkq_query_desc async{m.kind, m.mode, leaf | MINKQ_QUERY_COUNT, r};
      ASSERT_EQ(minkq_scene_query_async(b.get(), &async, pairs.as<int32_t>(), 32, count.as<uint64_t>(), nullptr),
                MINKQ_SUCCESS)
          << what << ": " << minkq_last_error_message();
      uint64_t counted = 0;
      ASSERT_EQ(cudaMemcpy(&counted, count.ptr, sizeof counted, cudaMemcpyDeviceToHost), cudaSuccess);
      EXPECT_EQ(counted, expected.count) << what << " (async)";
    }
  std::vector<int32_t> after(64);
  ASSERT_EQ(cudaMemcpy(after.data(), pairs.ptr, 64 * sizeof(int32_t), cudaMemcpyDeviceToHost), cudaSuccess);
  EXPECT_EQ(after, fill) << "a count-only query wrote pairs";
}

TEST_F(Cuda, device_memory_vertices_with_any_stride_match_host_input) {
  test::Device cpu("cpu"), cuda("cuda");
  const Mesh mesh = reference::twisted_sheet(40, 3.0);
  const float r = float(0.5 * reference::mean_edge_length(mesh));
  cxx::Scene reference_scene = make_scene(cpu.get(), mesh, kBoth);
  for (size_t stride : {size_t(12), size_t(16), size_t(14)}) {
    DeviceMemory vertices = device_vertices(mesh.xyz, stride);
    cxx::Scene scene = make_scene(cuda.get(), mesh, kBoth, device_buffer(vertices.ptr, mesh.vertex_count(), stride));
    ASSERT_TRUE(scene);
    compare_all_modes(reference_scene.get(), scene.get(), r, "device vertices stride " + std::to_string(stride));
    // Refit from device memory too: move every vertex, on both sides.
    Mesh moved = mesh;
    reference::transform(moved, 1.5, 0.25);
    DeviceMemory moved_vertices = device_vertices(moved.xyz, stride);
    cxx::Scene moved_cpu = make_scene(cpu.get(), moved, kBoth);
    ASSERT_EQ(minkq_scene_refit(scene.get(), device_buffer(moved_vertices.ptr, mesh.vertex_count(), stride)),
              MINKQ_SUCCESS)
        << minkq_last_error_message();
    compare_all_modes(moved_cpu.get(), scene.get(), 1.5f * r, "device refit stride " + std::to_string(stride));
  }
}

// Float64 input (MINKQ_SCENE_FLOAT64): rounded and widened by rho on the device exactly as on
// the CPU, from host memory and from device memory at any stride, at creation and in refits.
TEST_F(Cuda, float64_vertices_from_host_and_device_memory_match_cpu) {
  test::Device cpu("cpu"), cuda("cuda");
  Mesh mesh = reference::twisted_sheet(40, 3.0);
  reference::set_float64(mesh, test::far_doubles(mesh.xyz));
  const float r = float(0.5 * reference::mean_edge_length(mesh));
  const uint32_t flags = kBoth | MINKQ_SCENE_FLOAT64;
  cxx::Scene reference_scene = make_scene(cpu.get(), mesh, flags, test::vertices_of(mesh, flags));
  cxx::Scene from_host = make_scene(cuda.get(), mesh, flags, test::vertices_of(mesh, flags));
  compare_all_modes(reference_scene.get(), from_host.get(), r, "float64 host vertices");
  Mesh moved = mesh;
  reference::transform(moved, 1.5, 0.25);
  cxx::Scene moved_cpu = make_scene(cpu.get(), moved, flags, test::vertices_of(moved, flags));
  for (size_t stride : {size_t(24), size_t(32), size_t(28), size_t(26)}) {
    DeviceMemory vertices = device_vertices(mesh.xyz64, stride);
    cxx::Scene scene = make_scene(cuda.get(), mesh, flags, device_buffer(vertices.ptr, mesh.vertex_count(), stride));
    ASSERT_TRUE(scene);
    compare_all_modes(reference_scene.get(), scene.get(), r, "float64 device vertices stride " + std::to_string(stride));
    DeviceMemory moved_vertices = device_vertices(moved.xyz64, stride);
    ASSERT_EQ(minkq_scene_refit(scene.get(), device_buffer(moved_vertices.ptr, mesh.vertex_count(), stride)),
              MINKQ_SUCCESS)
        << minkq_last_error_message();
    compare_all_modes(moved_cpu.get(), scene.get(), 1.5f * r, "float64 device refit stride " + std::to_string(stride));
  }
  // A double beyond the float range is refused on the device too, naming the vertex.
  std::vector<double> bad = mesh.xyz64;
  bad[3 * 17 + 2] = -1e300;
  DeviceMemory bad_vertices = device_vertices(bad, 24);
  EXPECT_EQ(minkq_scene_refit(from_host.get(), device_buffer(bad_vertices.ptr, mesh.vertex_count(), 24)),
            MINKQ_ERROR_NON_FINITE);
  EXPECT_NE(std::string(minkq_last_error_message()).find("vertex 17"), std::string::npos) << minkq_last_error_message();
}

// Swept positions (minkq_scene_refit_swept / rebuild_swept): the same swept boxes and path
// tests on the device, from host and from device memory, float and float64.
TEST_F(Cuda, swept_queries_match_cpu) {
  test::Device cpu("cpu"), cuda("cuda");
  for (uint32_t precision : {0u, uint32_t(MINKQ_SCENE_FLOAT64)}) {
    Mesh from = reference::twisted_sheet(40, 3.0);
    const float r = float(0.5 * reference::mean_edge_length(from));
    Mesh to = from;
    reference::transform(to, 1.02, 0.01);
    if (precision) {
      reference::set_float64(from, test::far_doubles(from.xyz));
      reference::set_float64(to, test::far_doubles(to.xyz));
    }
    const uint32_t flags = kBoth | MINKQ_SCENE_DROP_INCIDENT | precision;
    cxx::Scene on_cpu = make_scene(cpu.get(), from, flags, test::vertices_of(from, flags));
    ASSERT_EQ(minkq_scene_rebuild_swept(on_cpu.get(), test::vertices_of(from, flags), test::vertices_of(to, flags)),
              MINKQ_SUCCESS);
    const size_t stride = precision ? 24 : 12;
    DeviceMemory x0 = precision ? device_vertices(from.xyz64, stride) : device_vertices(from.xyz, stride);
    DeviceMemory x1 = precision ? device_vertices(to.xyz64, stride) : device_vertices(to.xyz, stride);
    for (bool device_memory : {false, true}) {
      const std::string what = std::string(precision ? "float64" : "float") + (device_memory ? " device" : " host");
      cxx::Scene on_gpu = make_scene(cuda.get(), from, flags, test::vertices_of(from, flags));
      const minkq_buffer a = device_memory ? device_buffer(x0.ptr, from.vertex_count(), stride) : test::vertices_of(from, flags);
      const minkq_buffer b = device_memory ? device_buffer(x1.ptr, from.vertex_count(), stride) : test::vertices_of(to, flags);
      for (bool rebuild : {false, true}) {
        ASSERT_EQ(rebuild ? minkq_scene_rebuild_swept(on_gpu.get(), a, b) : minkq_scene_refit_swept(on_gpu.get(), a, b),
                  MINKQ_SUCCESS)
            << minkq_last_error_message();
        for (minkq_mode mode : {MINKQ_MODE_BOX, MINKQ_MODE_SPHERE, MINKQ_MODE_CAPSULE_RAY, MINKQ_MODE_CAPSULE_EXACT})
          expect_same(scene_query(on_cpu.get(), MINKQ_QUERY_VT, mode, r, MINKQ_QUERY_DIGEST),
                      scene_query(on_gpu.get(), MINKQ_QUERY_VT, mode, r, MINKQ_QUERY_DIGEST), what + " VT");
        expect_same(scene_query(on_cpu.get(), MINKQ_QUERY_EE, MINKQ_MODE_BOX, r, MINKQ_QUERY_DIGEST),
                    scene_query(on_gpu.get(), MINKQ_QUERY_EE, MINKQ_MODE_BOX, r, MINKQ_QUERY_DIGEST), what + " EE");
      }
    }
  }
}

// VV and EV (codimensional scenes: the sheet's vertices and edges, no triangles), static and
// swept: the same pairs and digests on the device.
TEST_F(Cuda, vv_and_ev_queries_match_cpu) {
  test::Device cpu("cpu"), cuda("cuda");
  Mesh codim = reference::twisted_sheet(40, 3.0);
  const float r = float(0.5 * reference::mean_edge_length(codim));
  codim.tris.clear();  // explicit edges, no triangles
  const uint32_t flags = MINKQ_SCENE_VV | MINKQ_SCENE_EV | MINKQ_SCENE_DROP_INCIDENT;
  test::Scene on_cpu(cpu.get(), codim, flags), on_gpu(cuda.get(), codim, flags);
  for (bool swept : {false, true}) {
    if (swept) {
      Mesh to = codim;
      reference::transform(to, 1.02, 0.01);
      for (minkq_scene* scene : {on_cpu.get(), on_gpu.get()})
        ASSERT_EQ(minkq_scene_rebuild_swept(scene, test::vertices_of(codim, 0), test::vertices_of(to, 0)), MINKQ_SUCCESS);
    }
    for (minkq_query_kind kind : {MINKQ_QUERY_VV, MINKQ_QUERY_EV})
      for (minkq_mode mode : {MINKQ_MODE_BOX, MINKQ_MODE_SPHERE, MINKQ_MODE_CAPSULE_RAY, MINKQ_MODE_CAPSULE_EXACT})
        for (uint32_t leaf : {0u, uint32_t(MINKQ_QUERY_LEAF_EXACT)}) {
          if (swept && leaf) continue;
          const std::string what = std::string(kind == MINKQ_QUERY_VV ? "VV" : "EV") + (swept ? " swept" : "");
          expect_same(scene_query(on_cpu.get(), kind, mode, r, leaf | MINKQ_QUERY_DIGEST),
                      scene_query(on_gpu.get(), kind, mode, r, leaf | MINKQ_QUERY_DIGEST), what);
        }
  }
}

TEST_F(Cuda, non_finite_device_vertices_name_the_first_bad_vertex) {
  test::Device cuda("cuda");
  Mesh mesh = reference::twisted_sheet(40, 3.0);
  const size_t bad = mesh.vertex_count() / 3;
  mesh.xyz[3 * bad + 2] = std::numeric_limits<float>::infinity();
  mesh.xyz[3 * (bad + 5)] = std::numeric_limits<float>::quiet_NaN();
  for (size_t stride : {size_t(12), size_t(14)}) {
    DeviceMemory vertices = device_vertices(mesh.xyz, stride);
    minkq_scene_desc desc{};
    desc.flags = kBoth;
    desc.vertices = device_buffer(vertices.ptr, mesh.vertex_count(), stride);
    desc.triangles = host_buffer(mesh.tris.data(), mesh.triangle_count());
    minkq_scene* scene = nullptr;
    EXPECT_EQ(minkq_scene_create(cuda.get(), &desc, &scene), MINKQ_ERROR_NON_FINITE);
    EXPECT_EQ(scene, nullptr);
    const std::string message = minkq_last_error_message();
    EXPECT_NE(message.find("vertex " + std::to_string(bad) + " "), std::string::npos) << message;
    minkq_scene_release(scene);
  }
}

// Host memory marked MINKQ_MEMORY_DEVICE is refused, named, before any kernel reads it (a
// fault there would stick to the context and fail every later call); the device stays usable.
TEST_F(Cuda, host_memory_marked_device_is_refused_and_named) {
  test::Device cuda("cuda");
  const Mesh mesh = reference::twisted_sheet(20, 1.0);
  const float r = float(0.5 * reference::mean_edge_length(mesh));
  std::vector<float> pageable = mesh.xyz;  // ordinary host memory
  minkq_scene_desc desc{};
  desc.flags = kBoth;
  desc.vertices = device_buffer(pageable.data(), mesh.vertex_count(), 12);
  desc.triangles = host_buffer(mesh.tris.data(), mesh.triangle_count());
  int pageable_access = 0;
  ASSERT_EQ(cudaDeviceGetAttribute(&pageable_access, cudaDevAttrPageableMemoryAccess, 0), cudaSuccess);
  minkq_scene* scene = nullptr;
  const minkq_status created = minkq_scene_create(cuda.get(), &desc, &scene);
  if (pageable_access) {  // HMM / ATS: the device reads pageable memory, so it is accepted
    EXPECT_EQ(created, MINKQ_SUCCESS) << minkq_last_error_message();
  } else {
    EXPECT_EQ(created, MINKQ_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(scene, nullptr);
    const std::string message = minkq_last_error_message();
    EXPECT_NE(message.find("vertices.data is host memory"), std::string::npos) << message;
  }
  minkq_scene_release(scene);
  // Output pairs in host memory marked device: refused the same way, and the scene still works.
  cxx::Scene good = make_scene(cuda.get(), mesh, kBoth);
  ASSERT_TRUE(good);
  std::vector<int32_t> host_pairs(2 * 1024);
  const minkq_query_desc query{MINKQ_QUERY_EE, MINKQ_MODE_BOX, 0, r};
  minkq_query_info info{};
  const minkq_status queried = minkq_scene_query(good.get(), &query, host_pairs.data(), 1024, MINKQ_MEMORY_DEVICE, &info);
  if (!pageable_access) {
    EXPECT_EQ(queried, MINKQ_ERROR_INVALID_ARGUMENT);
    EXPECT_NE(std::string(minkq_last_error_message()).find("out_pairs is host memory"), std::string::npos)
        << minkq_last_error_message();
  }
  const Outcome after = scene_query(good.get(), MINKQ_QUERY_EE, MINKQ_MODE_BOX, r, MINKQ_QUERY_CANONICAL);
  EXPECT_GT(after.count, 0u);
}

TEST_F(Cuda, device_output_buffers_match_host_output_and_respect_capacity) {
  test::Device cpu("cpu"), cuda("cuda");
  const Mesh mesh = reference::random_soup(3000, seed, 0.08);
  cxx::Scene a = make_scene(cpu.get(), mesh, kBoth), b = make_scene(cuda.get(), mesh, kBoth);
  ASSERT_TRUE(a && b);
  const float r = float(reference::mean_edge_length(mesh));
  for (const ModeCase& m : kModes) {
    const minkq_query_desc desc{m.kind, m.mode, MINKQ_QUERY_CANONICAL | MINKQ_QUERY_DIGEST, r};
    const Outcome expected = scene_query(a.get(), m.kind, m.mode, r, desc.flags);
    const size_t guard = 64, room = size_t(expected.count) + guard;
    DeviceMemory pairs(2 * room * sizeof(int32_t));
    ASSERT_EQ(cudaMemset(pairs.ptr, 0xFF, 2 * room * sizeof(int32_t)), cudaSuccess);
    minkq_query_info info{};
    // Too small by one: CAPACITY, exact count, nothing past the buffer.
    if (expected.count > 0) {
      EXPECT_EQ(minkq_scene_query(b.get(), &desc, pairs.as<int32_t>(), size_t(expected.count) - 1, MINKQ_MEMORY_DEVICE,
                                  &info),
                MINKQ_ERROR_CAPACITY)
          << m.name;
      EXPECT_EQ(info.count, expected.count) << m.name;
      std::vector<int32_t> tail(2 * (guard + 1));
      ASSERT_EQ(cudaMemcpy(tail.data(), pairs.as<int32_t>() + 2 * (expected.count - 1), tail.size() * sizeof(int32_t),
                           cudaMemcpyDeviceToHost),
                cudaSuccess);
      for (int32_t value : tail) ASSERT_EQ(value, -1) << m.name << ": written past capacity";
    }
    ASSERT_EQ(minkq_scene_query(b.get(), &desc, pairs.as<int32_t>(), room, MINKQ_MEMORY_DEVICE, &info), MINKQ_SUCCESS)
        << minkq_last_error_message();
    Outcome got;
    got.count = info.count;
    got.digest = info.digest;
    got.pairs.resize(2 * size_t(info.count));
    ASSERT_EQ(cudaMemcpy(got.pairs.data(), pairs.ptr, got.pairs.size() * sizeof(int32_t), cudaMemcpyDeviceToHost),
              cudaSuccess);
    expect_same(expected, got, std::string(m.name) + " device output");
  }
}

// The fused VT + EE call on CUDA: one launch for both; each query's output equals the CPU's
// (fused or alone), into host or device buffers, and a short EE buffer gets nothing past it.
TEST_F(Cuda, vt_and_ee_in_one_call_match_cpu_into_host_and_device_buffers) {
  test::Device cpu("cpu"), cuda("cuda");
  for (const auto& [name, mesh] : Scenes(seed).meshes) {
    cxx::Scene a = make_scene(cpu.get(), mesh, kBoth | MINKQ_SCENE_DROP_INCIDENT);
    cxx::Scene b = make_scene(cuda.get(), mesh, kBoth | MINKQ_SCENE_DROP_INCIDENT);
    ASSERT_TRUE(a && b);
    const double edge = reference::mean_edge_length(mesh);
    const uint32_t all = MINKQ_QUERY_CANONICAL | MINKQ_QUERY_DIGEST | MINKQ_QUERY_STATS;
    for (minkq_mode vt_mode : {MINKQ_MODE_BOX, MINKQ_MODE_SPHERE})
      for (minkq_mode ee_mode : {MINKQ_MODE_BOX, MINKQ_MODE_CAPSULE_EXACT})
        for (uint32_t leaf : {0u, uint32_t(MINKQ_QUERY_LEAF_EXACT)}) {
          const std::string what = name + " VT mode " + std::to_string(vt_mode) + " EE mode " +
                                   std::to_string(ee_mode) + (leaf ? " leaf_exact" : "");
          const minkq_query_desc vt{MINKQ_QUERY_VT, vt_mode, leaf | all, float(0.5 * edge)};
          const minkq_query_desc ee{MINKQ_QUERY_EE, ee_mode, leaf | all, float(0.25 * edge)};
          const Outcome vt_alone = scene_query(a.get(), vt.kind, vt.mode, vt.radius, vt.flags);
          const Outcome ee_alone = scene_query(a.get(), ee.kind, ee.mode, ee.radius, ee.flags);
          for (minkq_memory memory : {MINKQ_MEMORY_HOST, MINKQ_MEMORY_DEVICE}) {
            const size_t guard = 64, vt_room = size_t(vt_alone.count), ee_room = size_t(ee_alone.count) + guard;
            DeviceMemory vt_device(2 * (vt_room + 1) * sizeof(int32_t)), ee_device(2 * ee_room * sizeof(int32_t));
            std::vector<int32_t> vt_host(2 * vt_room), ee_host(2 * ee_room, -1);
            ASSERT_EQ(cudaMemset(ee_device.ptr, 0xFF, 2 * ee_room * sizeof(int32_t)), cudaSuccess);
            const bool on_device = memory == MINKQ_MEMORY_DEVICE;
            int32_t* vt_out = on_device ? vt_device.as<int32_t>() : vt_host.data();
            int32_t* ee_out = on_device ? ee_device.as<int32_t>() : ee_host.data();
            auto fetch = [&](const int32_t* out, uint64_t count) {
              std::vector<int32_t> pairs(2 * size_t(count));
              if (on_device)
                EXPECT_EQ(cudaMemcpy(pairs.data(), out, pairs.size() * sizeof(int32_t), cudaMemcpyDeviceToHost),
                          cudaSuccess);
              else
                std::copy(out, out + pairs.size(), pairs.begin());
              return pairs;
            };
            minkq_query_info vt_info{}, ee_info{};
            if (ee_alone.count > 0) {  // EE one short: CAPACITY, VT written, nothing past the EE buffer
              EXPECT_EQ(minkq_scene_query_vt_ee(b.get(), &vt, &ee, vt_out, vt_room, ee_out, size_t(ee_alone.count) - 1,
                                                memory, &vt_info, &ee_info),
                        MINKQ_ERROR_CAPACITY)
                  << what;
              EXPECT_EQ(ee_info.count, ee_alone.count) << what;
              const std::vector<int32_t> tail = fetch(ee_out, ee_room);
              for (size_t i = 2 * (size_t(ee_alone.count) - 1); i < tail.size(); ++i)
                ASSERT_EQ(tail[i], -1) << what << ": written past capacity";
              Outcome vt_got{vt_info.count, vt_info.digest, vt_info.stats, fetch(vt_out, vt_info.count)};
              expect_same(vt_alone, vt_got, what + " VT beside a short EE buffer");
            }
            ASSERT_EQ(minkq_scene_query_vt_ee(b.get(), &vt, &ee, vt_out, vt_room, ee_out, ee_room, memory, &vt_info,
                                              &ee_info),
                      MINKQ_SUCCESS)
                << minkq_last_error_message();
            expect_same(vt_alone, Outcome{vt_info.count, vt_info.digest, vt_info.stats, fetch(vt_out, vt_info.count)},
                        what + " VT fused");
            expect_same(ee_alone, Outcome{ee_info.count, ee_info.digest, ee_info.stats, fetch(ee_out, ee_info.count)},
                        what + " EE fused");
          }
        }
  }
}

TEST_F(Cuda, user_queries_from_device_memory_match_host_queries) {
  test::Device cpu("cpu"), cuda("cuda");
  test::Random rng(seed);
  std::vector<Box> boxes(3000);
  for (Box& box : boxes) box = rng.box(rng.vec3(0.0f, 1.0f), 0.02f);
  cxx::Bvh a = make_bvh(cpu.get(), boxes), b = make_bvh(cuda.get(), boxes);
  ASSERT_TRUE(a && b);
  std::vector<Vec3> p0(2000), p1(2000);
  for (size_t i = 0; i < p0.size(); ++i) {
    p0[i] = rng.vec3(0.0f, 1.0f);
    p1[i] = p0[i] + rng.vec3(-0.05f, 0.05f);
  }
  std::vector<float> flat0, flat1;
  for (size_t i = 0; i < p0.size(); ++i) {
    flat0.insert(flat0.end(), {p0[i].x, p0[i].y, p0[i].z});
    flat1.insert(flat1.end(), {p1[i].x, p1[i].y, p1[i].z});
  }
  DeviceMemory d0 = device_vertices(flat0, 16), d1 = device_vertices(flat1, 14);
  minkq_bvh_query_desc desc{};
  desc.shape = MINKQ_SHAPE_CAPSULE;
  desc.mode = MINKQ_MODE_CAPSULE_EXACT;
  desc.flags = MINKQ_QUERY_CANONICAL | MINKQ_QUERY_DIGEST;
  desc.radius = 0.01f;
  desc.first = device_buffer(d0.ptr, p0.size(), 16);
  desc.second = device_buffer(d1.ptr, p1.size(), 14);
  const Outcome got = run_exact([&](int32_t* pairs, size_t capacity, minkq_query_info* info) {
    return minkq_bvh_query(b.get(), &desc, pairs, capacity, MINKQ_MEMORY_HOST, info);
  });
  expect_same(bvh_query(a.get(), MINKQ_SHAPE_CAPSULE, MINKQ_MODE_CAPSULE_EXACT, 0.01f, p0, p1), got,
              "device capsule queries");
}

// ---- Stream-ordered calls -------------------------------------------------------------------

// Device memory and a stream of the test's own (not the per-thread default stream the
// blocking calls use), for async_checks.h.
class DeviceAsyncMemory final : public test::AsyncMemory {
 public:
  DeviceAsyncMemory() { EXPECT_EQ(cudaStreamCreateWithFlags(&stream_, cudaStreamNonBlocking), cudaSuccess); }
  ~DeviceAsyncMemory() override {
    cudaStreamSynchronize(stream_);
    for (void* p : blocks_) cudaFree(p);
    cudaStreamDestroy(stream_);
  }
  void* allocate(size_t bytes) override {
    void* p = nullptr;
    EXPECT_EQ(cudaMalloc(&p, bytes ? bytes : 1), cudaSuccess);
    blocks_.push_back(p);
    return p;
  }
  void write(void* dst, const void* host, size_t bytes) override {
    EXPECT_EQ(cudaMemcpyAsync(dst, host, bytes, cudaMemcpyHostToDevice, stream_), cudaSuccess);
    EXPECT_EQ(cudaStreamSynchronize(stream_), cudaSuccess);
  }
  void read(void* host, const void* src, size_t bytes) override {
    EXPECT_EQ(cudaMemcpyAsync(host, src, bytes, cudaMemcpyDeviceToHost, stream_), cudaSuccess);
    EXPECT_EQ(cudaStreamSynchronize(stream_), cudaSuccess);
  }
  minkq_stream stream() override { return stream_; }
  void wait() override { EXPECT_EQ(cudaStreamSynchronize(stream_), cudaSuccess); }
  minkq_memory kind() override { return MINKQ_MEMORY_DEVICE; }

 private:
  cudaStream_t stream_ = nullptr;
  std::vector<void*> blocks_;
};

// A CUDA graph recorded from what `record(check)` enqueues on `stream` (global capture mode)
// and instantiated: `record` passes each minkq call's status to check(), which expects success
// and keeps the message. ok() once recorded and instantiated without an error.
class CapturedGraph {
 public:
  template <class Record>
  CapturedGraph(cudaStream_t stream, Record record) : stream_(stream) {
    EXPECT_EQ(cudaStreamBeginCapture(stream, cudaStreamCaptureModeGlobal), cudaSuccess);
    bool called = true;
    record([&](minkq_status status) {
      EXPECT_EQ(status, MINKQ_SUCCESS) << minkq_last_error_message();
      called = called && status == MINKQ_SUCCESS;
    });
    EXPECT_EQ(cudaStreamEndCapture(stream, &graph_), cudaSuccess);
    if (called && graph_) EXPECT_EQ(cudaGraphInstantiate(&exec_, graph_, 0), cudaSuccess);
  }
  CapturedGraph(const CapturedGraph&) = delete;
  CapturedGraph& operator=(const CapturedGraph&) = delete;
  ~CapturedGraph() {
    if (exec_) cudaGraphExecDestroy(exec_);
    if (graph_) cudaGraphDestroy(graph_);
  }
  bool ok() const { return exec_ != nullptr; }
  cudaError_t launch() const { return cudaGraphLaunch(exec_, stream_); }

 private:
  cudaStream_t stream_;
  cudaGraph_t graph_ = nullptr;
  cudaGraphExec_t exec_ = nullptr;
};

class CudaAsync : public Cuda {
 protected:
  void SetUp() override {
    Cuda::SetUp();
    if (IsSkipped()) return;
    cpu = std::make_unique<test::Device>("cpu");
    cuda = std::make_unique<test::Device>("cuda");
    device_memory = std::make_unique<DeviceAsyncMemory>();
  }
  std::unique_ptr<test::Device> cpu, cuda;
  std::unique_ptr<DeviceAsyncMemory> device_memory;  // made only where a GPU is present
  DeviceAsyncMemory& memory() { return *device_memory; }
};

TEST_F(CudaAsync, queries_match_the_blocking_calls_over_refits_and_rebuilds) {
  test::check_async_matches_blocking(memory(), cuda->get(), cpu->get());
}

TEST_F(CudaAsync, float64_queries_match_the_blocking_calls_over_refits_and_rebuilds) {
  test::check_async_matches_blocking(memory(), cuda->get(), cpu->get(), MINKQ_SCENE_FLOAT64);
}

TEST_F(CudaAsync, swept_steps_match_the_blocking_swept_calls) {
  test::check_async_swept_matches_blocking(memory(), cuda->get(), cpu->get());
  test::check_async_swept_matches_blocking(memory(), cuda->get(), cpu->get(), MINKQ_SCENE_FLOAT64);
}

TEST_F(CudaAsync, non_finite_vertices_keep_the_positions_and_are_reported_once) {
  test::check_async_non_finite_is_pending(memory(), cuda->get(), cpu->get());
}

TEST_F(CudaAsync, bad_arguments_and_missing_reservations_are_refused_at_once) {
  test::check_async_argument_errors(memory(), cuda->get(), cpu->get());
}

// A simulator's captured step: refit (or rebuild) + VT + EE recorded once into a CUDA graph by
// stream capture, then replayed over new positions written into the same device buffer; every
// replay gives the pairs of the blocking calls on the CPU at those positions.
TEST_F(CudaAsync, captured_refit_and_queries_replay_over_moving_vertices) {
  // Launches that block (the sanitizer stages set it) do not mix with stream capture; the gpu
  // stage runs this test without it.
  if (const char* blocking = std::getenv("CUDA_LAUNCH_BLOCKING"); blocking && std::string(blocking) == "1")
    GTEST_SKIP() << "CUDA_LAUNCH_BLOCKING=1: stream capture is not tested with blocking launches";
  const Mesh mesh = reference::twisted_sheet(40, 3.0);
  const float r = float(0.5 * reference::mean_edge_length(mesh));
  DeviceAsyncMemory& memory = this->memory();
  test::AsyncScene s(memory, cuda->get(), cpu->get(), mesh);
  for (bool rebuild : {false, true}) {
    SCOPED_TRACE(rebuild ? "rebuild" : "refit");
    const size_t capacity = 1 << 15;
    ASSERT_EQ(minkq_scene_reserve(s.scene.get(), MINKQ_RESERVE_REBUILD, capacity), MINKQ_SUCCESS)
        << minkq_last_error_message();
    float* positions = memory.copy_of(mesh.xyz);
    int32_t* vt_pairs = static_cast<int32_t*>(memory.allocate(2 * capacity * sizeof(int32_t)));
    int32_t* ee_pairs = static_cast<int32_t*>(memory.allocate(2 * capacity * sizeof(int32_t)));
    uint64_t* counts = static_cast<uint64_t*>(memory.allocate(2 * sizeof(uint64_t)));
    const minkq_buffer vertices{positions, 0, mesh.vertex_count(), MINKQ_MEMORY_DEVICE};
    const minkq_query_desc vt{MINKQ_QUERY_VT, MINKQ_MODE_BOX, MINKQ_QUERY_LEAF_EXACT | MINKQ_QUERY_CANONICAL, r};
    const minkq_query_desc ee{MINKQ_QUERY_EE, MINKQ_MODE_BOX, MINKQ_QUERY_LEAF_EXACT | MINKQ_QUERY_CANONICAL, r};
    cudaStream_t stream = static_cast<cudaStream_t>(memory.stream());
    const CapturedGraph graph(stream, [&](auto check) {
      check(rebuild ? minkq_scene_rebuild_async(s.scene.get(), vertices, stream)
                    : minkq_scene_refit_async(s.scene.get(), vertices, stream));
      check(minkq_scene_query_vt_ee_async(s.scene.get(), &vt, &ee, vt_pairs, capacity, counts, ee_pairs, capacity,
                                          counts + 1, stream));
    });
    ASSERT_TRUE(graph.ok());
    for (int step = 1; step <= 4; ++step) {
      Mesh next = mesh;
      reference::transform(next, 1.0 + 0.05 * step, 0.002 * step);
      for (size_t v = 0; v < next.vertex_count(); ++v) next.xyz[3 * v + 1] += 0.01f * float(std::cos(0.05 * double(v) * step));
      memory.write(positions, next.xyz.data(), next.xyz.size() * sizeof(float));
      ASSERT_EQ(graph.launch(), cudaSuccess);
      const std::vector<uint64_t> count = memory.read_back(counts, 2);
      const minkq_buffer host = host_buffer(next.xyz.data(), next.vertex_count());
      ASSERT_EQ(rebuild ? minkq_scene_rebuild(s.blocking.get(), host) : minkq_scene_refit(s.blocking.get(), host),
                MINKQ_SUCCESS);
      const test::Pairs vt_expected = s.blocking.query(MINKQ_QUERY_VT, MINKQ_MODE_BOX, r, MINKQ_QUERY_LEAF_EXACT);
      const test::Pairs ee_expected = s.blocking.query(MINKQ_QUERY_EE, MINKQ_MODE_BOX, r, MINKQ_QUERY_LEAF_EXACT);
      ASSERT_EQ(count[0], vt_expected.size()) << "replay " << step;
      ASSERT_EQ(count[1], ee_expected.size()) << "replay " << step;
      EXPECT_EQ(test::pairs_of(memory.read_back(vt_pairs, 2 * count[0]), count[0]), vt_expected) << "replay " << step;
      EXPECT_EQ(test::pairs_of(memory.read_back(ee_pairs, 2 * count[1]), count[1]), ee_expected) << "replay " << step;
    }
    EXPECT_EQ(minkq_scene_async_status(s.scene.get(), stream), MINKQ_SUCCESS) << minkq_last_error_message();
  }
}

// Issue 30: a captured graph keeps the addresses and launch sizes of the scene's device memory,
// so the blocking calls between its replays must neither move nor outgrow them. A refit + VT +
// EE graph is captured at positions whose trees keep fewer nodes; between replays a blocking
// rebuild goes to positions whose trees keep more, and blocking canonical queries find more
// pairs than the reserved canonical capacity (they grow the blocking queries' scratch). Every
// replay must still give the CPU's pairs at its positions: with MINKQ_RESERVE_REBUILD, with
// MINKQ_RESERVE_REFIT only, and with no reservation (a captured query alone, not canonical).
TEST_F(CudaAsync, blocking_rebuilds_and_queries_between_replays_keep_a_captured_graph_valid) {
  if (const char* blocking = std::getenv("CUDA_LAUNCH_BLOCKING"); blocking && std::string(blocking) == "1")
    GTEST_SKIP() << "CUDA_LAUNCH_BLOCKING=1: stream capture is not tested with blocking launches";
  Mesh few = reference::twisted_sheet(40, 0.0), more = reference::twisted_sheet(40, 3.0);
  test::TreeCounts few_nodes = test::tree_counts(few), more_nodes = test::tree_counts(more);
  if (few_nodes.triangles > more_nodes.triangles) {
    std::swap(few, more);
    std::swap(few_nodes, more_nodes);
  }
  ASSERT_LT(few_nodes.triangles, more_nodes.triangles) << "the rebuild must keep more triangle-tree nodes";
  const float r = float(0.5 * reference::mean_edge_length(few));
  const size_t capacity = 1 << 15;  // also the canonical reservation, which the blocking queries pass
  DeviceAsyncMemory& memory = this->memory();
  for (uint32_t flags : {uint32_t(MINKQ_RESERVE_REBUILD), uint32_t(MINKQ_RESERVE_REFIT), 0u}) {
    SCOPED_TRACE("reserve flags " + std::to_string(flags));
    test::AsyncScene s(memory, cuda->get(), cpu->get(), few);
    const bool refits = flags != 0, canonical = flags != 0;
    if (flags != 0)
      ASSERT_EQ(minkq_scene_reserve(s.scene.get(), flags, capacity), MINKQ_SUCCESS) << minkq_last_error_message();
    float* positions = memory.copy_of(few.xyz);
    int32_t* vt_pairs = static_cast<int32_t*>(memory.allocate(2 * capacity * sizeof(int32_t)));
    int32_t* ee_pairs = static_cast<int32_t*>(memory.allocate(2 * capacity * sizeof(int32_t)));
    uint64_t* counts = static_cast<uint64_t*>(memory.allocate(2 * sizeof(uint64_t)));
    const minkq_buffer vertices{positions, 0, few.vertex_count(), MINKQ_MEMORY_DEVICE};
    const uint32_t query_flags = MINKQ_QUERY_LEAF_EXACT | (canonical ? uint32_t(MINKQ_QUERY_CANONICAL) : 0u);
    const minkq_query_desc vt{MINKQ_QUERY_VT, MINKQ_MODE_BOX, query_flags, r};
    const minkq_query_desc ee{MINKQ_QUERY_EE, MINKQ_MODE_BOX, query_flags, r};
    cudaStream_t stream = static_cast<cudaStream_t>(memory.stream());
    const CapturedGraph graph(stream, [&](auto check) {
      if (refits) check(minkq_scene_refit_async(s.scene.get(), vertices, stream));
      check(minkq_scene_query_vt_ee_async(s.scene.get(), &vt, &ee, vt_pairs, capacity, counts, ee_pairs, capacity,
                                          counts + 1, stream));
    });
    ASSERT_TRUE(graph.ok());
    for (int step = 0; step < 3; ++step) {
      SCOPED_TRACE("replay " + std::to_string(step));
      // Blocking calls between replays: a rebuild at the positions with more nodes (then the
      // replay's refit or query runs on that tree), and canonical queries past the reservation.
      Mesh next = more;
      reference::transform(next, 1.0 + 0.03 * step, 0.001 * step);
      ASSERT_EQ(minkq_scene_rebuild(s.scene.get(), host_buffer(next.xyz.data(), next.vertex_count())), MINKQ_SUCCESS)
          << minkq_last_error_message();
      const test::Pairs wide = s.scene.query(MINKQ_QUERY_EE, MINKQ_MODE_BOX, 4 * r, MINKQ_QUERY_LEAF_EXACT);
      ASSERT_GT(wide.size(), 2 * capacity);
      s.scene.query(MINKQ_QUERY_VT, MINKQ_MODE_BOX, 4 * r, MINKQ_QUERY_LEAF_EXACT);
      memory.write(positions, next.xyz.data(), next.xyz.size() * sizeof(float));
      ASSERT_EQ(graph.launch(), cudaSuccess);
      const std::vector<uint64_t> count = memory.read_back(counts, 2);
      ASSERT_EQ(minkq_scene_rebuild(s.blocking.get(), host_buffer(next.xyz.data(), next.vertex_count())), MINKQ_SUCCESS);
      const test::Pairs vt_expected = s.blocking.query(MINKQ_QUERY_VT, MINKQ_MODE_BOX, r, MINKQ_QUERY_LEAF_EXACT);
      const test::Pairs ee_expected = s.blocking.query(MINKQ_QUERY_EE, MINKQ_MODE_BOX, r, MINKQ_QUERY_LEAF_EXACT);
      ASSERT_EQ(count[0], vt_expected.size());
      ASSERT_EQ(count[1], ee_expected.size());
      const test::Pairs vt_got = test::pairs_of(memory.read_back(vt_pairs, 2 * count[0]), count[0]);
      const test::Pairs ee_got = test::pairs_of(memory.read_back(ee_pairs, 2 * count[1]), count[1]);
      EXPECT_EQ(canonical ? vt_got : test::sorted(vt_got), vt_expected);  // canonical: sorted on the device
      EXPECT_EQ(canonical ? ee_got : test::sorted(ee_got), ee_expected);
    }
    EXPECT_EQ(minkq_scene_async_status(s.scene.get(), stream), MINKQ_SUCCESS) << minkq_last_error_message();
  }
}

#endif  // MINKQ_TEST_HAVE_CUDART

}  // namespace
}  // namespace minkq
