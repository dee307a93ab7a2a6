// The CUDA backend's stream-ordered calls (minkq_async.h) on a stream of the
// test's own with device memory: async_checks.h's contract checks (the same ones test_async.cpp
// runs on the CPU), and the calls captured into CUDA graphs and replayed over moving vertices,
// rebuilds included, against the blocking calls. Needs the CUDA runtime; skips without a device.
#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "async_checks.h"
#include "cuda_async_memory.h"
#include "cuda_checks.h"
#include "tree_counts.h"

#if defined(MINKQ_TEST_HAVE_CUDART)

namespace minkq {
namespace {

using namespace cuda_test;

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
// MINKQ_RESERVE_REFIT only, and with a reservation of no flags (a captured query alone, not
// canonical): any reservation fixes the trees' node storage (issue 56).
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
    ASSERT_EQ(minkq_scene_reserve(s.scene.get(), flags, canonical ? capacity : 0), MINKQ_SUCCESS)
        << minkq_last_error_message();
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

// Issue 56: an unreserved tree holds only node_room of the nodes its build keeps, so a
// reservation (any flags) sizes the trees' nodes for the most any build keeps: a rebuild
// enqueued on a stream never allocates, and a captured graph keeps its node addresses. A graph
// captured at tree_counts.h's line of triangles (a few nodes) is replayed over the caterpillar
// (nearly n - leaf size nodes) and back, rebuilding inside the graph (MINKQ_RESERVE_REBUILD) or
// by blocking rebuilds between replays (MINKQ_RESERVE_REFIT, no flags): every replay gives the
// CPU's pairs.
TEST_F(CudaAsync, reserved_trees_hold_every_build_so_rebuilds_to_more_nodes_keep_a_graph_valid) {
  if (const char* blocking = std::getenv("CUDA_LAUNCH_BLOCKING"); blocking && std::string(blocking) == "1")
    GTEST_SKIP() << "CUDA_LAUNCH_BLOCKING=1: stream capture is not tested with blocking launches";
  const Mesh line = test::caterpillar_mesh(false), caterpillar = test::caterpillar_mesh(true);
  ASSERT_GT(test::tree_counts(caterpillar).triangles,
            node_room(test::tree_counts(line).triangles, int32_t(line.triangle_count())));
  const float r = 0.5f;
  const size_t capacity = 1 << 15;
  DeviceAsyncMemory& memory = this->memory();
  // flags -1: no reservation; a stream-ordered query before capturing fixes the nodes instead.
  for (int64_t flags : {int64_t(MINKQ_RESERVE_REBUILD), int64_t(MINKQ_RESERVE_REFIT), int64_t(0), int64_t(-1)}) {
    SCOPED_TRACE("reserve flags " + std::to_string(flags));
    test::AsyncScene s(memory, cuda->get(), cpu->get(), line);
    if (flags >= 0)
      ASSERT_EQ(minkq_scene_reserve(s.scene.get(), uint32_t(flags), 0), MINKQ_SUCCESS) << minkq_last_error_message();
    const bool rebuilds = flags == MINKQ_RESERVE_REBUILD;
    float* positions = memory.copy_of(line.xyz);
    int32_t* vt_pairs = static_cast<int32_t*>(memory.allocate(2 * capacity * sizeof(int32_t)));
    int32_t* ee_pairs = static_cast<int32_t*>(memory.allocate(2 * capacity * sizeof(int32_t)));
    uint64_t* counts = static_cast<uint64_t*>(memory.allocate(2 * sizeof(uint64_t)));
    const minkq_buffer vertices{positions, 0, line.vertex_count(), MINKQ_MEMORY_DEVICE};
    const minkq_query_desc vt{MINKQ_QUERY_VT, MINKQ_MODE_BOX, MINKQ_QUERY_LEAF_EXACT, r};
    const minkq_query_desc ee{MINKQ_QUERY_EE, MINKQ_MODE_BOX, MINKQ_QUERY_LEAF_EXACT, r};
    cudaStream_t stream = static_cast<cudaStream_t>(memory.stream());
    if (flags < 0) {
      ASSERT_EQ(minkq_scene_query_vt_ee_async(s.scene.get(), &vt, &ee, vt_pairs, capacity, counts, ee_pairs, capacity,
                                              counts + 1, stream),
                MINKQ_SUCCESS)
          << minkq_last_error_message();
      ASSERT_EQ(cudaStreamSynchronize(stream), cudaSuccess);
    }
    const CapturedGraph graph(stream, [&](auto check) {
      if (rebuilds) check(minkq_scene_rebuild_async(s.scene.get(), vertices, stream));
      else if (flags > 0) check(minkq_scene_refit_async(s.scene.get(), vertices, stream));
      check(minkq_scene_query_vt_ee_async(s.scene.get(), &vt, &ee, vt_pairs, capacity, counts, ee_pairs, capacity,
                                          counts + 1, stream));
    });
    ASSERT_TRUE(graph.ok());
    int step = 0;
    for (const Mesh* next : {&caterpillar, &line, &caterpillar}) {
      SCOPED_TRACE("replay " + std::to_string(step++));
      const minkq_buffer host = host_buffer(next->xyz.data(), next->vertex_count());
      if (!rebuilds) ASSERT_EQ(minkq_scene_rebuild(s.scene.get(), host), MINKQ_SUCCESS) << minkq_last_error_message();
      memory.write(positions, next->xyz.data(), next->xyz.size() * sizeof(float));
      ASSERT_EQ(graph.launch(), cudaSuccess);
      const std::vector<uint64_t> count = memory.read_back(counts, 2);
      ASSERT_EQ(minkq_scene_rebuild(s.blocking.get(), host), MINKQ_SUCCESS) << minkq_last_error_message();
      const test::Pairs vt_expected = s.blocking.query(MINKQ_QUERY_VT, MINKQ_MODE_BOX, r, MINKQ_QUERY_LEAF_EXACT);
      const test::Pairs ee_expected = s.blocking.query(MINKQ_QUERY_EE, MINKQ_MODE_BOX, r, MINKQ_QUERY_LEAF_EXACT);
      ASSERT_EQ(count[0], vt_expected.size());
      ASSERT_EQ(count[1], ee_expected.size());
      ASSERT_LE(count[0], capacity);
      ASSERT_LE(count[1], capacity);
      EXPECT_EQ(test::sorted(test::pairs_of(memory.read_back(vt_pairs, 2 * count[0]), count[0])), vt_expected);
      EXPECT_EQ(test::sorted(test::pairs_of(memory.read_back(ee_pairs, 2 * count[1]), count[1])), ee_expected);
    }
    EXPECT_EQ(minkq_scene_async_status(s.scene.get(), stream), MINKQ_SUCCESS) << minkq_last_error_message();
  }
}

}  // namespace
}  // namespace minkq

#endif  // MINKQ_TEST_HAVE_CUDART
