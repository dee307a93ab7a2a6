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

// All-to-all of variable-sized blocks of trivially copyable records: send[q] goes to rank q;
// returns what each rank sent here, in rank order, with counts[p] records from rank p.
template <class T>
std::vector<T> alltoallv(MPI_Comm comm, const std::vector<std::vector<T>>& send, std::vector<int>* counts = nullptr);

// Point-to-point exchange between known partners: sends send[i] to ranks dests[i] and
// receives one block from each of sources[j] (returned in that order). Both sides must agree
// on who sends to whom; the sizes travel first, so a block may be empty.
template <class T>
std::vector<std::vector<T>> neighbour_exchange(MPI_Comm comm, const std::vector<int>& dests,
                                               const std::vector<std::vector<T>>& send, const std::vector<int>& sources);

// ---- Definitions ---------------------------------------------------------------------------

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
std::vector<T> alltoallv(MPI_Comm comm, const std::vector<std::vector<T>>& send, std::vector<int>* counts) {
  static_assert(std::is_trivially_copyable_v<T>);
  const int size = int(send.size());
  std::vector<int> send_bytes(size), recv_bytes(size), send_at(size), recv_at(size);
  size_t total = 0;
  for (int q = 0; q < size; ++q) {
    if (send[q].size() * sizeof(T) > size_t(INT32_MAX)) fail(MINKQ_ERROR_SIZE_OVERFLOW, "a message over 2 GiB");
    send_bytes[q] = int(send[q].size() * sizeof(T));
    send_at[q] = int(total);
    total += size_t(send_bytes[q]);
    if (total > size_t(INT32_MAX)) fail(MINKQ_ERROR_SIZE_OVERFLOW, "messages over 2 GiB in all");
  }
  std::vector<char> out(total);
  for (int q = 0; q < size; ++q)
    if (send_bytes[q]) std::memcpy(out.data() + send_at[q], send[q].data(), size_t(send_bytes[q]));
  mpi_check(MPI_Alltoall(send_bytes.data(), 1, MPI_INT, recv_bytes.data(), 1, MPI_INT, comm), "MPI_Alltoall");
  size_t in_total = 0;
  for (int p = 0; p < size; ++p) recv_at[p] = int(in_total), in_total += size_t(recv_bytes[p]);
  std::vector<T> in(in_total / sizeof(T));
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
                                               const std::vector<std::vector<T>>& send, const std::vector<int>& sources) {
  static_assert(std::is_trivially_copyable_v<T>);
  constexpr int kSizeTag = 7301, kDataTag = 7302;
  std::vector<uint64_t> out_sizes(dests.size()), in_sizes(sources.size());
  std::vector<MPI_Request> requests;
  requests.reserve(2 * (dests.size() + sources.size()));
  auto wait_all = [&] {
    mpi_check(MPI_Waitall(int(requests.size()), requests.data(), MPI_STATUSES_IGNORE), "MPI_Waitall");
    requests.clear();
  };
  for (size_t j = 0; j < sources.size(); ++j)
    mpi_check(MPI_Irecv(&in_sizes[j], 1, MPI_UINT64_T, sources[j], kSizeTag, comm, &requests.emplace_back()), "MPI_Irecv");
  for (size_t i = 0; i < dests.size(); ++i) {
    out_sizes[i] = send[i].size();
    if (out_sizes[i] * sizeof(T) > size_t(INT32_MAX)) fail(MINKQ_ERROR_SIZE_OVERFLOW, "a message over 2 GiB");
    mpi_check(MPI_Isend(&out_sizes[i], 1, MPI_UINT64_T, dests[i], kSizeTag, comm, &requests.emplace_back()), "MPI_Isend");
  }
  wait_all();
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
