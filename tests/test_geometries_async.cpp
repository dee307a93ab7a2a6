// The stream-ordered calls on scenes of many geometries, on the CPU backend
// (geometry_async_checks.h): equal to the blocking calls over whole-scene refits, rebuilds and
// swept steps, non-finite input reported naming the geometry, refusals at once.
// test_cuda_geometries.cpp runs the same checks on a GPU and captures them into a graph.
#include "geometry_async_checks.h"

namespace minkq::test {
namespace {

class GeometriesAsyncOnCpu : public ::testing::Test {
 protected:
  Device cpu{"cpu"};
  HostAsyncMemory memory;
};

TEST_F(GeometriesAsyncOnCpu, queries_match_the_blocking_calls_over_every_move) {
  check_geometry_async_matches_blocking(memory, cpu.get(), cpu.get());
}

TEST_F(GeometriesAsyncOnCpu, a_non_finite_vertex_keeps_its_geometry_and_is_reported_once) {
  check_geometry_async_non_finite(memory, cpu.get(), cpu.get());
}

TEST_F(GeometriesAsyncOnCpu, moves_without_reservation_or_of_mixed_precision_are_refused) {
  check_geometry_async_refusals(memory, cpu.get(), cpu.get());
}

}  // namespace
}  // namespace minkq::test
