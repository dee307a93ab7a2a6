// The stream-ordered calls' contract (minkq_async.h), checked on any device:
// test_async.cpp runs it on the CPU (host memory), test_cuda.cpp on a GPU (device memory, a
// stream of its own). Each check compares the asynchronous calls with the blocking ones.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "capi_util.h"
#include "minkq_reference.h"

namespace minkq::test {

// Memory the asynchronous calls of one device read and write, and the stream they run on.
class AsyncMemory {
 public:
  virtual ~AsyncMemory() = default;
  virtual void* allocate(size_t bytes) = 0;  // owned by this object until it is destroyed
  virtual void write(void* dst, const void* host, size_t bytes) = 0;
  virtual void read(void* host, const void* src, size_t bytes) = 0;  // waits for the stream first
  virtual minkq_stream stream() = 0;
  virtual void wait() = 0;  // for the stream's work (before a blocking call on the same scene)
  virtual minkq_memory kind() = 0;

  template <class T>
  T* copy_of(const std::vector<T>& host) {
    T* data = static_cast<T*>(allocate(host.size() * sizeof(T)));
    write(data, host.data(), host.size() * sizeof(T));
    return data;
  }
  template <class T>
  std::vector<T> read_back(const T* data, size_t count) {
    std::vector<T> host(count);
    read(host.data(), data, count * sizeof(T));
    return host;
  }
};

// Host memory, for the CPU (the stream is ignored there: a value that is not a stream).
class HostAsyncMemory final : public AsyncMemory {
 public:
  void* allocate(size_t bytes) override {
    blocks_.emplace_back(bytes + 1);
    return blocks_.back().data();
  }
  void write(void* dst, const void* host, size_t bytes) override { std::memcpy(dst, host, bytes); }
  void read(void* host, const void* src, size_t bytes) override { std::memcpy(host, src, bytes); }
  minkq_stream stream() override { return reinterpret_cast<minkq_stream>(uintptr_t(0x5eed)); }
  void wait() override {}
  minkq_memory kind() override { return MINKQ_MEMORY_HOST; }

 private:
  std::vector<std::vector<unsigned char>> blocks_;
};

inline constexpr uint32_t kAsyncBoth = MINKQ_SCENE_VT | MINKQ_SCENE_EE;

// Sorted pairs of a raw buffer's first `count` pairs.
inline Pairs pairs_of(const std::vector<int32_t>& raw, uint64_t count) {
  Pairs pairs(count);
  for (size_t i = 0; i < count; ++i) pairs[i] = {raw[2 * i], raw[2 * i + 1]};
  return pairs;
}
inline Pairs sorted(Pairs pairs) {
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

// Float coordinates moved 1e3 away in double, each nudged by a third of its float spacing so
// that rounding to nearest moves every vertex (a float64 scene's input).
inline std::vector<double> far_doubles(const std::vector<float>& xyz) {
  std::vector<double> out(xyz.size());
  for (size_t i = 0; i < xyz.size(); ++i) {
    const float x = xyz[i] + 1e3f;
    out[i] = double(x) + (double(std::nextafter(x, INFINITY)) - double(x)) * (i % 3 == 0 ? 0.3 : -0.3);
  }
  return out;
}

// A scene on `device` driven by the asynchronous calls, beside a CPU scene driven by the
// blocking ones over the same positions: its reference.
struct AsyncScene {
  AsyncMemory& memory;
  reference::Mesh mesh;
  Scene scene;
  Scene blocking;
  // extra_flags: MINKQ_SCENE_FLOAT64 for scenes of the mesh's double input (mesh.xyz64).
  AsyncScene(AsyncMemory& memory, minkq_device* device, minkq_device* cpu, const reference::Mesh& mesh,
             uint32_t extra_flags = 0)
      : memory(memory), mesh(mesh), scene(device, mesh, kAsyncBoth | MINKQ_SCENE_DROP_INCIDENT | extra_flags),
        blocking(cpu, mesh, kAsyncBoth | MINKQ_SCENE_DROP_INCIDENT | extra_flags) {}

  template <class T>
  minkq_buffer vertices_in_memory(const std::vector<T>& xyz) {
    const T* data = memory.copy_of(xyz);
    return minkq_buffer{data, 0, xyz.size() / 3, memory.kind()};
  }
  template <class T>
  minkq_status refit_async(const std::vector<T>& xyz, bool rebuild = false) {
    const minkq_buffer vertices = vertices_in_memory(xyz);
    return rebuild ? minkq_scene_rebuild_async(scene.get(), vertices, memory.stream())
                   : minkq_scene_refit_async(scene.get(), vertices, memory.stream());
  }
  // Floats, or doubles for a float64 scene.
  template <class T>
  void move_to(const std::vector<T>& xyz, bool rebuild = false) {
    ASSERT_EQ(refit_async(xyz, rebuild), MINKQ_SUCCESS) << minkq_last_error_message();
    const minkq_buffer host = host_buffer(xyz.data(), xyz.size() / 3);
    ASSERT_EQ(rebuild ? minkq_scene_rebuild(blocking.get(), host) : minkq_scene_refit(blocking.get(), host),
              MINKQ_SUCCESS)
        << minkq_last_error_message();
  }

  // An asynchronous query into a buffer of `capacity` pairs (followed by guard words): its count
  // and the pairs it wrote (all of them when they fit).
  struct Outcome {
    minkq_status status;
    uint64_t count = 0;
    std::vector<int32_t> raw;  // 2 * capacity + guard words
  };
  static constexpr int32_t kGuard = -12345;
  static constexpr size_t kGuardWords = 16;
  Outcome query_async(const minkq_query_desc& desc, size_t capacity) {
    int32_t* pairs = memory.copy_of(std::vector<int32_t>(2 * capacity + kGuardWords, kGuard));
    uint64_t* count = memory.copy_of(std::vector<uint64_t>{0xDEADBEEFull});
    Outcome out;
    out.status = minkq_scene_query_async(scene.get(), &desc, pairs, capacity, count, memory.stream());
    out.count = memory.read_back(count, 1)[0];
    out.raw = memory.read_back(pairs, 2 * capacity + kGuardWords);
    return out;
  }
};

// Every asynchronous query equals its blocking counterpart, over refits and rebuilds to moved
// vertices: same count, same pairs (in canonical order where asked), never past the buffer.
// With MINKQ_SCENE_FLOAT64 in extra_flags, the same for the sheet's double input far from the
// origin, where rounding to float moves every vertex.
inline void check_async_matches_blocking(AsyncMemory& memory, minkq_device* device, minkq_device* cpu,
                                         uint32_t extra_flags = 0) {
  const bool float64 = extra_flags & MINKQ_SCENE_FLOAT64;
  reference::Mesh mesh = reference::twisted_sheet(32, 2.0);
  if (float64) reference::set_float64(mesh, far_doubles(mesh.xyz));
  const float r = float(0.5 * reference::mean_edge_length(mesh));
  AsyncScene s(memory, device, cpu, mesh, extra_flags);
  ASSERT_EQ(minkq_scene_reserve(s.scene.get(), MINKQ_RESERVE_REBUILD, 1 << 16), MINKQ_SUCCESS)
      << minkq_last_error_message();
  struct Case {
    minkq_query_kind kind;
    minkq_mode mode;
    uint32_t flags;
  };
  const Case cases[] = {
      {MINKQ_QUERY_VT, MINKQ_MODE_BOX, MINKQ_QUERY_LEAF_EXACT | MINKQ_QUERY_CANONICAL},
      {MINKQ_QUERY_VT, MINKQ_MODE_SPHERE, 0},
      {MINKQ_QUERY_EE, MINKQ_MODE_BOX, MINKQ_QUERY_LEAF_EXACT | MINKQ_QUERY_CANONICAL},
      {MINKQ_QUERY_EE, MINKQ_MODE_CAPSULE_EXACT, MINKQ_QUERY_CANONICAL},
      {MINKQ_QUERY_EE, MINKQ_MODE_CAPSULE_RAY, MINKQ_QUERY_LEAF_EXACT},
  };
  for (int step = 0; step < 4; ++step) {
    if (step > 0) {
      reference::Mesh moved = mesh;
      reference::transform(moved, 1.0 + 0.1 * step, 0.01 * step);
      for (size_t v = 0; v < moved.vertex_count(); ++v) moved.xyz[3 * v + 2] += 0.02f * float(std::sin(0.1 * double(v) * step));
      if (float64) s.move_to(far_doubles(moved.xyz), /*rebuild=*/step == 3);
      else s.move_to(moved.xyz, /*rebuild=*/step == 3);
      if (::testing::Test::HasFatalFailure()) return;
    }
    for (const Case& c : cases) {
      const std::string what = std::string(c.kind == MINKQ_QUERY_VT ? "VT" : "EE") + " mode " +
                               std::to_string(int(c.mode)) + " flags " + std::to_string(c.flags) + " step " +
                               std::to_string(step);
      const Pairs expected = s.blocking.query(c.kind, c.mode, r, c.flags & MINKQ_QUERY_LEAF_EXACT);
      ASSERT_GT(expected.size(), 0u) << what;
      const minkq_query_desc desc{c.kind, c.mode, c.flags, r};
      for (size_t capacity : {expected.size(), expected.size() + 100, expected.size() - 1, size_t(0)}) {
        const AsyncScene::Outcome out = s.query_async(desc, capacity);
        ASSERT_EQ(out.status, MINKQ_SUCCESS) << what << ": " << minkq_last_error_message();
        EXPECT_EQ(out.count, expected.size()) << what << " capacity " << capacity;
        for (size_t k = 2 * capacity; k < out.raw.size(); ++k)
          ASSERT_EQ(out.raw[k], AsyncScene::kGuard) << what << ": word " << k << " past a buffer of " << capacity;
        if (capacity < expected.size()) {  // `capacity` of the pairs, in no particular order
          const Pairs some = sorted(pairs_of(out.raw, capacity));
          EXPECT_TRUE(is_subset(some, expected)) << what << " capacity " << capacity;
          EXPECT_EQ(std::adjacent_find(some.begin(), some.end()), some.end()) << what << ": a pair written twice";
          continue;
        }
        const Pairs got = pairs_of(out.raw, out.count);
        if (c.flags & MINKQ_QUERY_CANONICAL) EXPECT_EQ(got, expected) << what;
        else EXPECT_EQ(sorted(got), expected) << what;
      }
    }
    // Both queries in one call: each as alone.
    const minkq_query_desc vt{MINKQ_QUERY_VT, MINKQ_MODE_BOX, MINKQ_QUERY_LEAF_EXACT | MINKQ_QUERY_CANONICAL, r};
    const minkq_query_desc ee{MINKQ_QUERY_EE, MINKQ_MODE_BOX, MINKQ_QUERY_LEAF_EXACT, r};
    const Pairs vt_expected = s.blocking.query(MINKQ_QUERY_VT, MINKQ_MODE_BOX, r, MINKQ_QUERY_LEAF_EXACT);
    const Pairs ee_expected = s.blocking.query(MINKQ_QUERY_EE, MINKQ_MODE_BOX, r, MINKQ_QUERY_LEAF_EXACT);
    const size_t vt_capacity = vt_expected.size(), ee_capacity = ee_expected.size() - 1;  // EE short
    int32_t* vt_pairs = memory.copy_of(std::vector<int32_t>(2 * vt_capacity + 2, AsyncScene::kGuard));
    int32_t* ee_pairs = memory.copy_of(std::vector<int32_t>(2 * ee_capacity + 2, AsyncScene::kGuard));
    uint64_t* counts = memory.copy_of(std::vector<uint64_t>{7, 7});
    ASSERT_EQ(minkq_scene_query_vt_ee_async(s.scene.get(), &vt, &ee, vt_pairs, vt_capacity, counts, ee_pairs,
                                            ee_capacity, counts + 1, memory.stream()),
              MINKQ_SUCCESS)
        << minkq_last_error_message();
    const std::vector<uint64_t> count = memory.read_back(counts, 2);
    EXPECT_EQ(count[0], vt_expected.size());
    EXPECT_EQ(count[1], ee_expected.size());
    const std::vector<int32_t> vt_raw = memory.read_back(vt_pairs, 2 * vt_capacity + 2);
    EXPECT_EQ(pairs_of(vt_raw, count[0]), vt_expected) << "fused VT step " << step;
    EXPECT_EQ(vt_raw[2 * vt_capacity], AsyncScene::kGuard);
    EXPECT_EQ(memory.read_back(ee_pairs, 2 * ee_capacity + 2)[2 * ee_capacity], AsyncScene::kGuard);
  }
  // A rebuild gives the trees of a blocking rebuild: growth 1 again, as the blocking scene's.
  double growth = 0, blocking_growth = 0;
  memory.wait();
  ASSERT_EQ(minkq_scene_tree_growth(s.scene.get(), &growth), MINKQ_SUCCESS);
  ASSERT_EQ(minkq_scene_tree_growth(s.blocking.get(), &blocking_growth), MINKQ_SUCCESS);
  EXPECT_NEAR(growth, blocking_growth, 1e-9 * blocking_growth);
  EXPECT_EQ(minkq_scene_async_status(s.scene.get(), memory.stream()), MINKQ_SUCCESS) << minkq_last_error_message();
}

// Non-finite vertices on the asynchronous path: the call succeeds, the scene keeps its
// positions (and a rebuild builds for them), and minkq_scene_async_status reports the first
// failing call's first bad vertex once.
inline void check_async_non_finite_is_pending(AsyncMemory& memory, minkq_device* device, minkq_device* cpu) {
  const reference::Mesh mesh = reference::twisted_sheet(24, 2.0);
  const float r = float(0.5 * reference::mean_edge_length(mesh));
  AsyncScene s(memory, device, cpu, mesh);
  ASSERT_EQ(minkq_scene_reserve(s.scene.get(), MINKQ_RESERVE_REBUILD, 0), MINKQ_SUCCESS) << minkq_last_error_message();
  EXPECT_EQ(minkq_scene_async_status(s.scene.get(), memory.stream()), MINKQ_SUCCESS);
  const Pairs before = s.blocking.query(MINKQ_QUERY_EE, MINKQ_MODE_BOX, r, MINKQ_QUERY_LEAF_EXACT);
  auto expect_positions_kept = [&](const std::string& what) {
    // The async scene still answers as the blocking one at the original positions.
    memory.wait();
    EXPECT_EQ(s.scene.query(MINKQ_QUERY_EE, MINKQ_MODE_BOX, r, MINKQ_QUERY_LEAF_EXACT), before) << what;
  };
  reference::Mesh moved = mesh;
  reference::transform(moved, 3.0, 0.5);
  std::vector<float> bad = moved.xyz;
  bad[3 * 7 + 1] = std::numeric_limits<float>::quiet_NaN();
  bad[3 * 30] = std::numeric_limits<float>::infinity();
  ASSERT_EQ(s.refit_async(bad), MINKQ_SUCCESS) << minkq_last_error_message();
  expect_positions_kept("after a rejected refit");
  std::vector<float> worse = moved.xyz;
  worse[3 * 3 + 2] = -std::numeric_limits<float>::infinity();
  ASSERT_EQ(s.refit_async(worse, /*rebuild=*/true), MINKQ_SUCCESS) << minkq_last_error_message();
  expect_positions_kept("after a rejected rebuild");
  EXPECT_EQ(minkq_scene_async_status(s.scene.get(), memory.stream()), MINKQ_ERROR_NON_FINITE);
  const std::string message = minkq_last_error_message();
  EXPECT_NE(message.find("minkq_scene_refit_async: vertex 7 has a non-finite coordinate"), std::string::npos)
      << message;
  EXPECT_EQ(minkq_scene_async_status(s.scene.get(), memory.stream()), MINKQ_SUCCESS) << "cleared once reported";
  // A good refit after a rejected one is taken.
  s.move_to(moved.xyz);
  memory.wait();
  EXPECT_EQ(s.scene.query(MINKQ_QUERY_EE, MINKQ_MODE_BOX, 3 * r, MINKQ_QUERY_LEAF_EXACT),
            s.blocking.query(MINKQ_QUERY_EE, MINKQ_MODE_BOX, 3 * r, MINKQ_QUERY_LEAF_EXACT));
  ASSERT_EQ(s.refit_async(worse, /*rebuild=*/true), MINKQ_SUCCESS);
  EXPECT_EQ(minkq_scene_async_status(s.scene.get(), memory.stream()), MINKQ_ERROR_NON_FINITE);
  EXPECT_NE(std::string(minkq_last_error_message())
                .find("minkq_scene_rebuild_async: vertex 3 has a non-finite coordinate; the scene kept its positions "
                      "and built its trees for them"),
            std::string::npos)
      << minkq_last_error_message();
}

// The swept stream-ordered calls (minkq_scene_refit_swept_async / rebuild_swept_async) equal
// the blocking swept calls over several steps; a bad coordinate in x1 leaves the scene at rest
// at its kept x0 (static pairs there) and is reported naming the swept call; without
// MINKQ_RESERVE_SWEPT they are refused. extra_flags as check_async_matches_blocking's.
inline void check_async_swept_matches_blocking(AsyncMemory& memory, minkq_device* device, minkq_device* cpu,
                                               uint32_t extra_flags = 0) {
  const bool float64 = extra_flags & MINKQ_SCENE_FLOAT64;
  const reference::Mesh base = reference::twisted_sheet(24, 2.0);
  reference::Mesh mesh = base;
  if (float64) reference::set_float64(mesh, far_doubles(base.xyz));
  const float r = float(0.5 * reference::mean_edge_length(base));
  AsyncScene s(memory, device, cpu, mesh, extra_flags);
  auto positions = [&](int step) {  // the step's start (step) or end (step + 1) positions, in float
    reference::Mesh m = base;
    reference::transform(m, 1.0 + 0.05 * step, 0.01 * step);
    for (size_t v = 0; v < m.vertex_count(); ++v) m.xyz[3 * v + 1] += 0.03f * float(std::sin(0.2 * double(v) + step));
    return m.xyz;
  };
  auto buffer = [&](const std::vector<float>& xyz) {
    return float64 ? s.vertices_in_memory(far_doubles(xyz)) : s.vertices_in_memory(xyz);
  };
  auto host = [&](const std::vector<float>& xyz, std::vector<double>& keep) {
    if (!float64) return host_buffer(xyz.data(), xyz.size() / 3);
    keep = far_doubles(xyz);
    return host_buffer(keep.data(), keep.size() / 3);
  };
  const minkq_buffer x0 = buffer(positions(0)), x1 = buffer(positions(1));
  EXPECT_EQ(minkq_scene_refit_swept_async(s.scene.get(), x0, x1, memory.stream()), MINKQ_ERROR_INVALID_ARGUMENT);
  EXPECT_NE(std::string(minkq_last_error_message()).find("MINKQ_RESERVE_REFIT | MINKQ_RESERVE_SWEPT"), std::string::npos)
      << minkq_last_error_message();
  ASSERT_EQ(minkq_scene_reserve(s.scene.get(), MINKQ_RESERVE_REBUILD | MINKQ_RESERVE_SWEPT, 1 << 16), MINKQ_SUCCESS)
      << minkq_last_error_message();
  const minkq_query_desc queries[] = {
      {MINKQ_QUERY_VT, MINKQ_MODE_BOX, MINKQ_QUERY_CANONICAL, r},
      {MINKQ_QUERY_VT, MINKQ_MODE_CAPSULE_EXACT, 0, r},
      {MINKQ_QUERY_EE, MINKQ_MODE_BOX, MINKQ_QUERY_CANONICAL, r},
  };
  for (int step = 0; step < 3; ++step) {
    const bool rebuild = step == 2;
    const std::vector<float> a = positions(step), b = positions(step + 1);
    ASSERT_EQ(rebuild ? minkq_scene_rebuild_swept_async(s.scene.get(), buffer(a), buffer(b), memory.stream())
                      : minkq_scene_refit_swept_async(s.scene.get(), buffer(a), buffer(b), memory.stream()),
              MINKQ_SUCCESS)
        << minkq_last_error_message();
    std::vector<double> ka, kb;
    const minkq_buffer ha = host(a, ka), hb = host(b, kb);
    ASSERT_EQ(rebuild ? minkq_scene_rebuild_swept(s.blocking.get(), ha, hb) : minkq_scene_refit_swept(s.blocking.get(), ha, hb),
              MINKQ_SUCCESS);
    for (const minkq_query_desc& q : queries) {
      const Pairs expected = s.blocking.query(q.kind, q.mode, r);
      const AsyncScene::Outcome out = s.query_async(q, expected.size() + 8);
      ASSERT_EQ(out.status, MINKQ_SUCCESS) << minkq_last_error_message();
      ASSERT_EQ(out.count, expected.size()) << "step " << step << " mode " << q.mode;
      const Pairs got = pairs_of(out.raw, out.count);
      EXPECT_EQ((q.flags & MINKQ_QUERY_CANONICAL) ? got : sorted(got), expected) << "step " << step << " mode " << q.mode;
    }
  }
  // A NaN in x1: at rest at the last accepted start, positions(2); static pairs there.
  std::vector<float> bad = positions(9);
  bad[3 * 11 + 2] = std::numeric_limits<float>::quiet_NaN();
  ASSERT_EQ(minkq_scene_refit_swept_async(s.scene.get(), buffer(positions(8)), buffer(bad), memory.stream()),
            MINKQ_SUCCESS);
  EXPECT_EQ(minkq_scene_async_status(s.scene.get(), memory.stream()), MINKQ_ERROR_NON_FINITE);
  EXPECT_NE(std::string(minkq_last_error_message())
                .find("minkq_scene_refit_swept_async: vertex 11 has a non-finite coordinate (in x0 or x1)"),
            std::string::npos)
      << minkq_last_error_message();
  std::vector<double> kept;
  ASSERT_EQ(minkq_scene_refit(s.blocking.get(), host(positions(2), kept)), MINKQ_SUCCESS);
  for (minkq_query_kind kind : {MINKQ_QUERY_VT, MINKQ_QUERY_EE}) {
    const minkq_query_desc q{kind, MINKQ_MODE_BOX, MINKQ_QUERY_CANONICAL, r};
    const Pairs expected = s.blocking.query(kind, MINKQ_MODE_BOX, r);
    const AsyncScene::Outcome out = s.query_async(q, expected.size() + 8);
    EXPECT_EQ(pairs_of(out.raw, out.count), expected) << "at rest, kind " << kind;
  }
}

// What the asynchronous calls refuse at once, naming the argument, with nothing enqueued.
inline void check_async_argument_errors(AsyncMemory& memory, minkq_device* device, minkq_device* cpu) {
  const reference::Mesh mesh = reference::twisted_sheet(12, 1.0);
  AsyncScene s(memory, device, cpu, mesh);
  minkq_scene* scene = s.scene.get();
  auto expect = [](minkq_status got, minkq_status want, const std::string& needle) {
    EXPECT_EQ(got, want) << minkq_status_name(got) << ": " << minkq_last_error_message();
    EXPECT_NE(std::string(minkq_last_error_message()).find(needle), std::string::npos)
        << "'" << minkq_last_error_message() << "' lacks '" << needle << "'";
  };
  // Reservations first.
  expect(s.refit_async(mesh.xyz), MINKQ_ERROR_INVALID_ARGUMENT, "minkq_scene_refit_async needs scratch reserved");
  expect(minkq_scene_reserve(scene, 8, 0), MINKQ_ERROR_INVALID_ARGUMENT, "unknown bits");
  expect(minkq_scene_reserve(nullptr, MINKQ_RESERVE_REFIT, 0), MINKQ_ERROR_INVALID_ARGUMENT, "scene is NULL");
  ASSERT_EQ(minkq_scene_reserve(scene, MINKQ_RESERVE_REFIT, 0), MINKQ_SUCCESS) << minkq_last_error_message();
  EXPECT_EQ(s.refit_async(mesh.xyz), MINKQ_SUCCESS) << minkq_last_error_message();
  expect(s.refit_async(mesh.xyz, true), MINKQ_ERROR_INVALID_ARGUMENT, "MINKQ_RESERVE_REBUILD");
  // Buffers.
  const std::vector<float> short_xyz(mesh.xyz.begin(), mesh.xyz.end() - 3);
  expect(s.refit_async(short_xyz), MINKQ_ERROR_INVALID_ARGUMENT, "vertices but the scene has");
  if (memory.kind() == MINKQ_MEMORY_DEVICE)
    expect(minkq_scene_refit_async(scene, host_buffer(mesh.xyz.data(), mesh.vertex_count()), memory.stream()),
           MINKQ_ERROR_INVALID_ARGUMENT, "reads device memory");
  // Queries.
  int32_t* pairs = memory.copy_of(std::vector<int32_t>(64, 0));
  uint64_t* count = memory.copy_of(std::vector<uint64_t>{0, 0});
  const minkq_query_desc vt{MINKQ_QUERY_VT, MINKQ_MODE_BOX, 0, 0.01f};
  minkq_query_desc digest = vt, stats = vt, canonical = vt, bad_radius = vt;
  digest.flags = MINKQ_QUERY_DIGEST;
  stats.flags = MINKQ_QUERY_STATS;
  canonical.flags = MINKQ_QUERY_CANONICAL;
  bad_radius.radius = std::numeric_limits<float>::quiet_NaN();
  const minkq_stream stream = memory.stream();
  expect(minkq_scene_query_async(scene, &digest, pairs, 32, count, stream), MINKQ_ERROR_UNSUPPORTED, "host read");
  expect(minkq_scene_query_async(scene, &stats, pairs, 32, count, stream), MINKQ_ERROR_UNSUPPORTED, "host read");
  expect(minkq_scene_query_async(scene, &vt, pairs, 32, nullptr, stream), MINKQ_ERROR_INVALID_ARGUMENT,
         "out_count is NULL");
  expect(minkq_scene_query_async(scene, &vt, nullptr, 32, count, stream), MINKQ_ERROR_INVALID_ARGUMENT,
         "out_pairs is NULL but capacity is 32");
  expect(minkq_scene_query_async(scene, &bad_radius, pairs, 32, count, stream), MINKQ_ERROR_NON_FINITE, "radius");
  expect(minkq_scene_query_async(scene, &canonical, pairs, 32, count, stream), MINKQ_ERROR_INVALID_ARGUMENT,
         "needs that many pairs reserved");
  ASSERT_EQ(minkq_scene_reserve(scene, 0, 32), MINKQ_SUCCESS) << minkq_last_error_message();
  EXPECT_EQ(minkq_scene_query_async(scene, &canonical, pairs, 32, count, stream), MINKQ_SUCCESS)
      << minkq_last_error_message();
  expect(minkq_scene_query_async(scene, &canonical, pairs, 33, count, stream), MINKQ_ERROR_INVALID_ARGUMENT,
         "(reserved: 32)");
  const minkq_query_desc ee{MINKQ_QUERY_EE, MINKQ_MODE_BOX, 0, 0.01f};
  expect(minkq_scene_query_vt_ee_async(scene, &vt, &ee, pairs, 16, count, pairs + 32, 16, count, stream),
         MINKQ_ERROR_INVALID_ARGUMENT, "same pointer");
  expect(minkq_scene_query_vt_ee_async(scene, &ee, &vt, pairs, 16, count, pairs + 32, 16, count + 1, stream),
         MINKQ_ERROR_INVALID_ARGUMENT, "vt_query->kind is not MINKQ_QUERY_VT");
  expect(minkq_scene_async_status(nullptr, stream), MINKQ_ERROR_INVALID_ARGUMENT, "scene is NULL");
  EXPECT_EQ(minkq_scene_async_status(scene, stream), MINKQ_SUCCESS) << minkq_last_error_message();
}

}  // namespace minkq::test
