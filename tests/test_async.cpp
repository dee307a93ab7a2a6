// The stream-ordered calls on the CPU backend (async_checks.h): equal to the blocking calls,
// never past a buffer, non-finite input reported, arguments refused at once. test_cuda.cpp
// runs the same checks on a GPU, and records them into a CUDA graph.
#include "async_checks.h"

namespace minkq::test {
namespace {

class AsyncOnCpu : public ::testing::Test {
 protected:
  Device cpu{"cpu"};
  HostAsyncMemory memory;
};

TEST_F(AsyncOnCpu, queries_match_the_blocking_calls_over_refits_and_rebuilds) {
  check_async_matches_blocking(memory, cpu.get(), cpu.get());
}

TEST_F(AsyncOnCpu, float64_queries_match_the_blocking_calls_over_refits_and_rebuilds) {
  check_async_matches_blocking(memory, cpu.get(), cpu.get(), MINKQ_SCENE_FLOAT64);
}

TEST_F(AsyncOnCpu, swept_steps_match_the_blocking_swept_calls) {
  check_async_swept_matches_blocking(memory, cpu.get(), cpu.get());
  check_async_swept_matches_blocking(memory, cpu.get(), cpu.get(), MINKQ_SCENE_FLOAT64);
}

TEST_F(AsyncOnCpu, non_finite_vertices_keep_the_positions_and_are_reported_once) {
  check_async_non_finite_is_pending(memory, cpu.get(), cpu.get());
}

TEST_F(AsyncOnCpu, bad_arguments_and_missing_reservations_are_refused_at_once) {
  check_async_argument_errors(memory, cpu.get(), cpu.get());
}

}  // namespace
}  // namespace minkq::test
