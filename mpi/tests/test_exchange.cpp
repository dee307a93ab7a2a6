// The exchanges of collective.h under mpirun (ctest runs this with 1 and 3 ranks): blocks
// arrive where they were sent, and a block over the limit (sent or received, one or in all)
// fails on every rank together, with the same status and message, before any data moves, so
// that no rank is left waiting and the next exchange works. The limit is lowered to a few
// bytes here; the library's is 2^31 - 1 bytes (MPI's int counts).
#include <mpi.h>

#include <cstdio>
#include <string>
#include <vector>

#include "collective.h"

namespace {

using minkq::mpi::alltoallv;
using minkq::mpi::Failure;
using minkq::mpi::neighbour_exchange;

int rank = 0, size = 1, failures = 0;

void expect(bool ok, const std::string& what) {
  if (ok) return;
  ++failures;
  std::fprintf(stderr, "rank %d: FAILED: %s\n", rank, what.c_str());
}

// Runs `exchange`, which must fail on every rank with SIZE_OVERFLOW and one message that starts
// with `prefix` (the lowest failing rank's, named).
template <class Exchange>
void expect_failure_together(const char* name, const std::string& prefix, Exchange&& exchange) {
  std::string message;
  minkq_status status = MINKQ_SUCCESS;
  try {
    exchange();
  } catch (const Failure& f) {
    status = f.status, message = f.what();
  }
  expect(status == MINKQ_ERROR_SIZE_OVERFLOW, std::string(name) + ": status " + std::to_string(int(status)));
  expect(message.rfind(prefix, 0) == 0, std::string(name) + ": message '" + message + "', expected '" + prefix + "...'");
  // Rank 0's message on every rank.
  std::string first = message;
  int length = int(first.size());
  MPI_Bcast(&length, 1, MPI_INT, 0, MPI_COMM_WORLD);
  first.resize(size_t(length));
  MPI_Bcast(first.data(), length, MPI_CHAR, 0, MPI_COMM_WORLD);
  expect(first == message, std::string(name) + ": rank 0 says '" + first + "', this rank '" + message + "'");
}

// Every rank sends q + 1 records rank * 100 + q to rank q.
void alltoallv_delivers(uint64_t limit) {
  std::vector<std::vector<int32_t>> send(static_cast<size_t>(size));
  for (int q = 0; q < size; ++q) send[size_t(q)].assign(size_t(q + 1), rank * 100 + q);
  std::vector<int> counts;
  const std::vector<int32_t> in = alltoallv(MPI_COMM_WORLD, send, &counts, limit);
  std::vector<int32_t> expected;
  for (int p = 0; p < size; ++p) expected.insert(expected.end(), size_t(rank + 1), p * 100 + rank);
  expect(in == expected, "alltoallv delivers the blocks in rank order");
  expect(counts == std::vector<int>(size_t(size), rank + 1), "alltoallv counts");
}

// A ring: rank r sends `count` floats r to r + 1 and receives from r - 1.
std::vector<std::vector<float>> ring(size_t count, uint64_t limit) {
  const std::vector<int> dests{(rank + 1) % size}, sources{(rank + size - 1) % size};
  const std::vector<std::vector<float>> send{std::vector<float>(count, float(rank))};
  return neighbour_exchange(MPI_COMM_WORLD, dests, send, sources, limit);
}

void neighbour_exchange_delivers(uint64_t limit) {
  const auto in = ring(3, limit);
  expect(in.size() == 1 && in[0] == std::vector<float>(3, float((rank + size - 1) % size)),
         "neighbour_exchange delivers the ring's blocks");
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  const int last = size - 1;

  alltoallv_delivers(minkq::mpi::kMessageLimit);
  neighbour_exchange_delivers(minkq::mpi::kMessageLimit);

  // One block over the limit, sent by the last rank to rank 0.
  expect_failure_together("alltoallv, one block", "rank " + std::to_string(last) + ": a message of 40 bytes to rank 0",
                          [&] {
                            std::vector<std::vector<int32_t>> send(static_cast<size_t>(size));
                            if (rank == last) send[0].assign(10, 1);
                            alltoallv(MPI_COMM_WORLD, send, nullptr, 32);
                          });
  // Each block within the limit, a rank's blocks in all over it.
  if (size > 1) {
    expect_failure_together("alltoallv, sent in all", "rank 0: messages of over 32 bytes in all to send", [&] {
      std::vector<std::vector<int32_t>> send(size_t(size), std::vector<int32_t>(rank == 0 ? 6 : 0, 1));
      alltoallv(MPI_COMM_WORLD, send, nullptr, 32);
    });
    // Every rank within the limit in what it sends; rank 0 receives more than it in all.
    expect_failure_together("alltoallv, received in all",
                            "rank 0: messages of " + std::to_string(20 * size) + " bytes in all to receive", [&] {
                              std::vector<std::vector<int32_t>> send(static_cast<size_t>(size));
                              send[0].assign(5, rank);
                              alltoallv(MPI_COMM_WORLD, send, nullptr, 20 * uint64_t(size) - 1);
                            });
  }
  // The ring with rank 0's block over the limit: rank 0 names it as the sender.
  expect_failure_together("neighbour_exchange", "rank 0: a message of 40 bytes to rank " + std::to_string(1 % size),
                          [&] { ring(rank == 0 ? 10 : 1, 32); });
  // Nothing left in flight: the exchanges work as before.
  alltoallv_delivers(minkq::mpi::kMessageLimit);
  neighbour_exchange_delivers(minkq::mpi::kMessageLimit);

  int total = 0;
  MPI_Allreduce(&failures, &total, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
  if (rank == 0) std::printf("test_exchange: %d failures over %d ranks\n", total, size);
  MPI_Finalize();
  return total == 0 ? 0 : 1;
}
