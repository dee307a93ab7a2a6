#include "collective.h"
#include "minkq_mpi.h"  // minkq_mpi_last_error_message, exported (MINKQ_MPI_API)

namespace minkq::mpi {

namespace {
thread_local std::string last_error;
}

void set_last_error(const std::string& message) { last_error = message; }

}  // namespace minkq::mpi

extern "C" const char* minkq_mpi_last_error_message(void) { return minkq::mpi::last_error.c_str(); }

namespace minkq::mpi {

void mpi_check(int code, const char* call) {
  if (code == MPI_SUCCESS) return;
  char text[MPI_MAX_ERROR_STRING];
  int length = 0;
  MPI_Error_string(code, text, &length);
  fail(MINKQ_ERROR_INTERNAL, std::string(call) + " failed: " + std::string(text, size_t(length)));
}

minkq_status agree(MPI_Comm comm, minkq_status local, const std::string& message) {
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  // The lowest failing rank speaks for all.
  const int mine = local == MINKQ_SUCCESS ? size : rank;
  int first = size;
  mpi_check(MPI_Allreduce(&mine, &first, 1, MPI_INT, MPI_MIN, comm), "MPI_Allreduce");
  if (first == size) return MINKQ_SUCCESS;
  std::string text = rank == first ? "rank " + std::to_string(rank) + ": " + message : std::string();
  int header[2] = {int(local), int(text.size())};
  mpi_check(MPI_Bcast(header, 2, MPI_INT, first, comm), "MPI_Bcast");
  text.resize(size_t(header[1]));
  if (header[1]) mpi_check(MPI_Bcast(text.data(), header[1], MPI_CHAR, first, comm), "MPI_Bcast");
  set_last_error(text);
  return minkq_status(header[0]);
}

void fail_together(MPI_Comm comm, const std::string& problem) {
  const minkq_status status = agree(comm, problem.empty() ? MINKQ_SUCCESS : MINKQ_ERROR_SIZE_OVERFLOW, problem);
  if (status != MINKQ_SUCCESS) fail(status, last_error);
}

}  // namespace minkq::mpi
