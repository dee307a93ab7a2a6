// The CUDA backend against the CPU backend for every kind of input and output it reads and
// writes in device memory: vertices at any stride, float64 vertices (rounded and widened on the
// device), swept positions, codimensional (VV, EV) scenes, count-only queries, non-finite and
// misplaced inputs named, output buffers in device memory, the fused VT + EE call and user-box
// queries from device memory. Needs the CUDA runtime (cudaMalloc); skips without a device.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "async_checks.h"  // far_doubles
#include "cuda_checks.h"

#if defined(MINKQ_TEST_HAVE_CUDART)

namespace minkq {
namespace {

using namespace cuda_test;

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
// Host memory marked MINKQ_MEMORY_DEVICE is read where the device can read it, with the pairs
// host memory gives: mapped pinned memory on every device, pageable memory where the device
// has pageable access (HMM / ATS). Packed records are copied, not gathered by a kernel, so the
// copy must take each side's kind from its address (a device-to-device copy is undefined for
// host memory): vertices at stride 12, and the triangles, which are read back to the host.
// Without pageable access, pageable memory is refused, naming the buffer, and the device
// keeps working.
TEST_F(Cuda, host_memory_marked_device_is_read_where_the_device_can_else_named) {
  test::Device cpu("cpu"), cuda("cuda");
  const Mesh mesh = reference::twisted_sheet(20, 1.0);
  const float r = float(0.5 * reference::mean_edge_length(mesh));
  cxx::Scene expected = make_scene(cpu.get(), mesh, kBoth);
  ASSERT_TRUE(expected);
  const size_t vertex_bytes = mesh.xyz.size() * sizeof(float), triangle_bytes = mesh.tris.size() * sizeof(int32_t);
  void* mapped = nullptr;
  ASSERT_EQ(cudaHostAlloc(&mapped, vertex_bytes + triangle_bytes, cudaHostAllocMapped), cudaSuccess);
  std::memcpy(mapped, mesh.xyz.data(), vertex_bytes);
  std::memcpy(static_cast<char*>(mapped) + vertex_bytes, mesh.tris.data(), triangle_bytes);
  minkq_scene_desc desc{};
  desc.flags = kBoth;
  desc.vertices = device_buffer(mapped, mesh.vertex_count(), 12);
  desc.triangles = device_buffer(static_cast<char*>(mapped) + vertex_bytes, mesh.triangle_count(), 12);
  {
    cxx::Scene pinned = test::new_scene(cuda.get(), desc);
    ASSERT_TRUE(pinned) << minkq_last_error_message();
    compare_all_modes(expected.get(), pinned.get(), r, "mapped pinned vertices and triangles");
    ASSERT_EQ(minkq_scene_rebuild(pinned.get(), desc.vertices), MINKQ_SUCCESS) << minkq_last_error_message();
    compare_all_modes(expected.get(), pinned.get(), r, "mapped pinned rebuild");
  }
  ASSERT_EQ(cudaFreeHost(mapped), cudaSuccess);

  std::vector<float> pageable = mesh.xyz;  // ordinary host memory
  std::vector<int32_t> pageable_tris = mesh.tris;
  desc.vertices = device_buffer(pageable.data(), mesh.vertex_count(), 12);
  desc.triangles = device_buffer(pageable_tris.data(), mesh.triangle_count(), 12);
  int pageable_access = 0;
  ASSERT_EQ(cudaDeviceGetAttribute(&pageable_access, cudaDevAttrPageableMemoryAccess, 0), cudaSuccess);
  minkq_scene* scene = nullptr;
  const minkq_status created = minkq_scene_create(cuda.get(), &desc, &scene);
  if (pageable_access) {  // HMM / ATS: the device reads pageable memory, so it is accepted
    EXPECT_EQ(created, MINKQ_SUCCESS) << minkq_last_error_message();
    if (scene) compare_all_modes(expected.get(), scene, r, "pageable vertices and triangles");
  } else {
    EXPECT_EQ(created, MINKQ_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(scene, nullptr);
    const std::string message = minkq_last_error_message();
    EXPECT_NE(message.find("vertices.data is host memory"), std::string::npos) << message;
  }
  minkq_scene_release(scene);
  // Output pairs in host memory marked device: written in place where the device can, else
  // refused the same way; the scene works on.
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
  } else {
    EXPECT_EQ(queried, MINKQ_SUCCESS) << minkq_last_error_message();
  }
  const Outcome after = scene_query(good.get(), MINKQ_QUERY_EE, MINKQ_MODE_BOX, r, MINKQ_QUERY_CANONICAL);
  EXPECT_GT(after.count, 0u);
}

// Host vertices that are strided or float64 are gathered on the host in parallel (backend.h's
// gather_host, gather_float64_host) before the upload: over many blocks of records, the same
// pairs as the CPU, with float64 rho reduced over all of them.
TEST_F(Cuda, strided_host_vertices_gathered_in_parallel_match_cpu) {
  test::Device cpu("cpu"), cuda("cuda");
  Mesh mesh = reference::twisted_sheet(160, 2.0);  // 25600 vertices: many blocks
  reference::set_float64(mesh, test::far_doubles(mesh.xyz));
  const float r = float(0.5 * reference::mean_edge_length(mesh));
  for (const uint32_t flags : {kBoth, kBoth | MINKQ_SCENE_FLOAT64}) {
    const bool float64 = flags & MINKQ_SCENE_FLOAT64;
    cxx::Scene expected = make_scene(cpu.get(), mesh, flags, test::vertices_of(mesh, flags));
    for (const size_t stride : float64 ? std::vector<size_t>{24, 28} : std::vector<size_t>{16, 14}) {
      const size_t scalar = float64 ? sizeof(double) : sizeof(float);
      std::vector<unsigned char> records(mesh.vertex_count() * stride, 0xAB);
      const void* xyz = float64 ? static_cast<const void*>(mesh.xyz64.data()) : mesh.xyz.data();
      for (size_t v = 0; v < mesh.vertex_count(); ++v)
        std::memcpy(&records[v * stride], static_cast<const char*>(xyz) + 3 * scalar * v, 3 * scalar);
      const std::string what = std::string(float64 ? "float64" : "float32") + " host stride " + std::to_string(stride);
      cxx::Scene scene = make_scene(cuda.get(), mesh, flags, host_buffer(records.data(), mesh.vertex_count(), stride));
      ASSERT_TRUE(scene) << what;
      compare_all_modes(expected.get(), scene.get(), r, what);
    }
  }
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

}  // namespace
}  // namespace minkq

#endif  // MINKQ_TEST_HAVE_CUDART
