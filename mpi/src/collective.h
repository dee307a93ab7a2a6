// The communication layer of minkq_mpi: collective errors and the exchanges the scene uses.
//
// Every collective call is a sequence of phases: local work that may fail (checks,
// allocation), then agree(), which gives every rank the first failing rank's status and
// message, then communication that cannot fail on bad input. So no rank is ever left waiting
// in a communication that another rank skipped because its input was bad.
#pragma once

#include <mpi.h>

#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "minkq.h"

namespace minkq::mpi {

// A local failure of one phase, with the status every rank will return.
struct Failure : std::runtime_error {
  minkq_status status;
  Failure(minkq_status s, const std::string& message) : std::runtime_error(message), status(s) {}
};
[[noreturn]] inline void fail(minkq_status status, const std::string& message) { throw Failure(status, message); }
inline void require(bool ok, minkq_status status, const std::string& message) {
  if (!ok) fail(status, message);
}

// The calling thread's last message (minkq_mpi_last_error_message).
void set_last_error(const std::string& message);

// Runs one phase's local work, catching its failure, then agrees: every rank returns the
// status of the lowest failing rank, with that rank's message prefixed "rank R: ". Returns
// MINKQ_SUCCESS on every rank when none failed.
template <class Work>
minkq_status phase(MPI_Comm comm, Work&& work);

// Gives every rank the lowest failing rank's status and message (the agreement of phase()).
minkq_status agree(MPI_Comm comm, minkq_status local, const std::string& message);

// Checks an MPI return code; MPI failures are reported as internal errors.
void mpi_check(int code, const char* call);

// Fails on every rank together (a Failure with SIZE_OVERFLOW and the lowest such rank's problem,
// named as agree() names it) when any rank's `problem` is not empty; returns on every rank
// otherwise. For checks inside a communication, which every rank must leave together.
void fail_together(MPI_Comm comm, const std::string& problem);

// The most bytes one message, or one rank's messages of one exchange in all, may hold: MPI's
// counts and displacements are int. The exchanges take a lower limit for the tests.
constexpr uint64_t kMessageLimit = uint64_t(INT32_MAX);

// All-to-all of variable-sized blocks of trivially copyable records: send[q] goes to rank q;
// returns what each rank sent here, in rank order, with counts[p] records from rank p. Sent or
// received bytes over `limit` (one block, or a rank's blocks in all) fail on every rank,
// together, before any data moves (fail_together).
template <class T>
std::vector<T> alltoallv(MPI_Comm comm, const std::vector<std::vector<T>>& send, std::vector<int>* counts = nullptr,
                         uint64_t limit = kMessageLimit);

// Point-to-point exchange between known partners: sends send[i] to ranks dests[i] and
// receives one block from each of sources[j] (returned in that order). Both sides must agree
// on who sends to whom; the sizes travel first, so a block may be empty. A block over `limit`
// bytes, sent or received, fails on every rank of comm together, before any data moves: every
// rank of comm calls it.
template <class T>
std::vector<std::vector<T>> neighbour_exchange(MPI_Comm comm, const std::vector<int>& dests,
                                               const std::vector<std::vector<T>>& send, const std::vector<int>& sources,
                                               uint64_t limit = kMessageLimit);

// ---- Definitions ---------------------------------------------------------------------------

// The problem of a message over the limit, `where` naming its partner ("to rank 2").
inline std::string over_limit(uint64_t bytes, const std::string& where, uint64_t limit) {
  return "a message of " + std::to_string(bytes) + " bytes " + where + " is over the limit of " + std::to_string(limit) +
         " (MPI counts are int)";
}

template <class Work>
minkq_status phase(MPI_Comm comm, Work&& work) {
  minkq_status status = MINKQ_SUCCESS;
  std::string message;
  try {
    work();
  } catch (const Failure& f) {
    status = f.status, message = f.what();
  } catch (const std::bad_alloc&) {
    status = MINKQ_ERROR_OUT_OF_MEMORY, message = "out of host memory";
  } catch (const std::exception& e) {
    status = MINKQ_ERROR_INTERNAL, message = e.what();
  }
  return agree(comm, status, message);
}

template <class T>
std::vector<T> alltoallv(MPI_Comm comm, const std::vector<std::vector<T>>& send, std::vector<int>* counts,
                         uint64_t limit) {
  static_assert(std::is_trivially_copyable_v<T>);
  const int size = int(send.size());
  std::vector<int> send_bytes(size), recv_bytes(size), send_at(size), recv_at(size);
  std::string problem;
  uint64_t total = 0;
  for (int q = 0; q < size && problem.empty(); ++q) {
    const uint64_t bytes = uint64_t(send[q].size()) * sizeof(T);
    total += bytes;
    if (bytes > limit)
      problem = over_limit(bytes, "to rank " + std::to_string(q), limit);
    else if (total > limit)
      problem = "messages of over " + std::to_string(limit) + " bytes in all to send (MPI displacements are int)";
  }
  fail_together(comm, problem);
  std::vector<char> out(total);
  for (int q = 0, at = 0; q < size; ++q) {
    send_bytes[q] = int(send[q].size() * sizeof(T)), send_at[q] = at, at += send_bytes[q];
    if (send_bytes[q]) std::memcpy(out.data() + send_at[q], send[q].data(), size_t(send_bytes[q]));
  }
  mpi_check(MPI_Alltoall(send_bytes.data(), 1, MPI_INT, recv_bytes.data(), 1, MPI_INT, comm), "MPI_Alltoall");
  uint64_t in_total = 0;
  for (int p = 0; p < size; ++p) in_total += uint64_t(recv_bytes[p]);
  fail_together(comm, in_total > limit ? "messages of " + std::to_string(in_total) + " bytes in all to receive, over the limit of " +
                                             std::to_string(limit) + " (MPI displacements are int)"
                                       : std::string());
  for (int p = 0, at = 0; p < size; ++p) recv_at[p] = at, at += recv_bytes[p];
  std::vector<T> in(size_t(in_total) / sizeof(T));
  mpi_check(MPI_Alltoallv(out.data(), send_bytes.data(), send_at.data(), MPI_BYTE, in.data(), recv_bytes.data(),
                          recv_at.data(), MPI_BYTE, comm),
            "MPI_Alltoallv");
  if (counts) {
    counts->resize(size);
    for (int p = 0; p < size; ++p) (*counts)[p] = int(recv_bytes[p] / int(sizeof(T)));
  }
  return in;
}

template <class T>
std::vector<std::vector<T>> neighbour_exchange(MPI_Comm comm, const std::vector<int>& dests,
                                               const std::vector<std::vector<T>>& send, const std::vector<int>& sources,
                                               uint64_t limit) {
  static_assert(std::is_trivially_copyable_v<T>);
  constexpr int kSizeTag = 7301, kDataTag = 7302;
  std::vector<uint64_t> out_sizes(dests.size()), in_sizes(sources.size());
  std::vector<MPI_Request> requests;
  requests.reserve(2 * (dests.size() + sources.size()));
  auto wait_all = [&] {
    mpi_check(MPI_Waitall(int(requests.size()), requests.data(), MPI_STATUSES_IGNORE), "MPI_Waitall");
    requests.clear();
  };
  // The sizes first (they cannot fail), then the limits checked on every rank together.
  for (size_t j = 0; j < sources.size(); ++j)
    mpi_check(MPI_Irecv(&in_sizes[j], 1, MPI_UINT64_T, sources[j], kSizeTag, comm, &requests.emplace_back()), "MPI_Irecv");
  for (size_t i = 0; i < dests.size(); ++i) {
    out_sizes[i] = send[i].size();
    mpi_check(MPI_Isend(&out_sizes[i], 1, MPI_UINT64_T, dests[i], kSizeTag, comm, &requests.emplace_back()), "MPI_Isend");
  }
  wait_all();
  std::string problem;
  for (size_t i = 0; i < dests.size() && problem.empty(); ++i)
    if (out_sizes[i] > limit / sizeof(T))
      problem = over_limit(out_sizes[i] * sizeof(T), "to rank " + std::to_string(dests[i]), limit);
  for (size_t j = 0; j < sources.size() && problem.empty(); ++j)
    if (in_sizes[j] > limit / sizeof(T))
      problem = over_limit(in_sizes[j] * sizeof(T), "from rank " + std::to_string(sources[j]), limit);
  fail_together(comm, problem);
  std::vector<std::vector<T>> in(sources.size());
  for (size_t j = 0; j < sources.size(); ++j) {
    in[j].resize(size_t(in_sizes[j]));
    if (in_sizes[j])
      mpi_check(MPI_Irecv(in[j].data(), int(in_sizes[j] * sizeof(T)), MPI_BYTE, sources[j], kDataTag, comm,
                          &requests.emplace_back()),
                "MPI_Irecv");
  }
  for (size_t i = 0; i < dests.size(); ++i)
    if (!send[i].empty())
      mpi_check(MPI_Isend(send[i].data(), int(send[i].size() * sizeof(T)), MPI_BYTE, dests[i], kDataTag, comm,
                          &requests.emplace_back()),
                "MPI_Isend");
  wait_all();
  return in;
}

}  // namespace minkq::mpi
