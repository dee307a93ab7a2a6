// What minkq-mpi and the distributed tests share on top of partition.h: a rank's part as a
// scene description, and the pairs of all ranks gathered on rank 0.
#pragma once

#include <mpi.h>

#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

#include "minkq_mpi.h"
#include "partition.h"

namespace minkq::mpi_tools {

inline minkq_mpi_scene_desc desc_of(const Part& p, uint32_t flags) {
  auto host = [](const void* data, size_t count) { return minkq_buffer{data, 0, count, MINKQ_MEMORY_HOST}; };
  minkq_mpi_scene_desc d{};
  d.flags = flags;
  d.vertices = host(p.xyz.data(), p.vertex_count());
  d.triangles = host(p.tris.data(), p.triangle_count());
  d.vertex_ids = host(p.vertex_ids.data(), p.vertex_count());
  d.triangle_ids = host(p.triangle_ids.data(), p.triangle_count());
  d.vertex_owned = host(p.vertex_owned.data(), p.vertex_count());
  d.triangle_owned = host(p.triangle_owned.data(), p.triangle_count());
  return d;
}

using GlobalPairs = std::vector<std::pair<int64_t, int64_t>>;

// Every rank's `count` pairs (2 global ids each), on `root`, sorted (duplicates kept, so that a
// caller can find them); empty elsewhere.
inline GlobalPairs gather_pairs(MPI_Comm comm, const int64_t* pairs, size_t count, int root = 0) {
  int rank = 0, size = 1;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  const int values = int(2 * count);
  const size_t ranks = size_t(size);
  std::vector<int> counts(ranks), at(ranks);
  MPI_Gather(&values, 1, MPI_INT, counts.data(), 1, MPI_INT, root, comm);
  int total = 0;
  for (int p = 0; p < size; ++p) at[size_t(p)] = total, total += counts[size_t(p)];
  std::vector<int64_t> all(rank == root ? size_t(total) : 0);
  MPI_Gatherv(pairs, values, MPI_INT64_T, all.data(), counts.data(), at.data(), MPI_INT64_T, root, comm);
  GlobalPairs out(all.size() / 2);
  for (size_t i = 0; i < out.size(); ++i) out[i] = {all[2 * i], all[2 * i + 1]};
  std::sort(out.begin(), out.end());
  return out;
}
inline GlobalPairs gather_pairs(MPI_Comm comm, const minkq_mpi_result* result, int root = 0) {
  return gather_pairs(comm, minkq_mpi_result_pairs(result), minkq_mpi_result_count(result), root);
}

}  // namespace minkq::mpi_tools
