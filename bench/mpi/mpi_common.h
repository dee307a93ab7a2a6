// What the distributed benchmarks share (minkq_mpi_bench, and arborx_mpi_bench beside ArborX's
// DistributedTree): their common options, clocks and the slowest rank's time, a status check
// that aborts every rank, the moving scene of each step, the partitions asked for, a
// single-process result as global pairs, and the global edge numbering with each edge's owner.
#pragma once
#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "distributed.h"
#include "minkq.h"
#include "minkq_mpi.h"
#include "minkq_reference.h"

namespace minkq::mpi_bench {

namespace ref = minkq::reference;

inline double now_ms() {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
inline double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}
// The slowest rank's value, on every rank.
inline double slowest(double ms, MPI_Comm comm = MPI_COMM_WORLD) {
  double all = 0;
  MPI_Allreduce(&ms, &all, 1, MPI_DOUBLE, MPI_MAX, comm);
  return all;
}
// The other ranks wait for rank 0's one-process timing asleep (polling every millisecond), not
// in a barrier that spins on the cores rank 0 is timing with.
inline void wait_for_rank_0(MPI_Comm comm = MPI_COMM_WORLD) {
  int rank = 0, size = 1, token = 0;
  MPI_Comm_rank(comm, &rank);
  MPI_Comm_size(comm, &size);
  if (rank == 0) {
    for (int p = 1; p < size; ++p) MPI_Send(&token, 1, MPI_INT, p, 99, comm);
    return;
  }
  MPI_Request request;
  MPI_Irecv(&token, 1, MPI_INT, 0, 99, comm, &request);
  for (int done = 0; !done;) {
    MPI_Test(&request, &done, MPI_STATUS_IGNORE);
    if (!done) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}
// A failed minkq_mpi call ends the run on every rank (the bench's inputs are valid).
inline void mpi_check(minkq_status s, const char* call) {
  if (s != MINKQ_SUCCESS) {
    int rank = 0;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    std::fprintf(stderr, "rank %d: %s failed: %s\n", rank, call, minkq_mpi_last_error_message());
    MPI_Abort(MPI_COMM_WORLD, 3);
  }
}

// The scene at step k: the sheet twisted further, or the mesh moved by a wave. scale() sets the
// step so that a vertex moves at most `motion` x r a step.
struct Motion {
  int n = 0;       // sheet size, or 0 for the mesh
  ref::Mesh mesh;  // the mesh at step 0
  double per_step = 0;
  ref::Mesh at(int step) const {
    if (n) return ref::twisted_sheet(n, 3.0 + per_step * step);
    ref::Mesh m = mesh;
    for (size_t v = 0; v < m.vertex_count(); ++v)
      m.xyz[3 * v + 2] += float(per_step * step * std::sin(0.37 * double(v)));
    return m;
  }
  void scale(const ref::Mesh& first, float r, double motion) {  // first: at(0)
    per_step = n ? 1e-3 : double(r);
    const ref::Mesh probe = at(1);
    double d = 0;
    for (size_t i = 0; i < first.xyz.size(); ++i) d = std::max(d, std::fabs(double(first.xyz[i]) - double(probe.xyz[i])));
    per_step *= motion * r / d;
  }
};

// The global edge numbering minkq_mpi defines (every distinct edge as (min id, max id), sorted:
// derive_edges' order) and each edge's owner, the owner of its lowest-id triangle.
struct GlobalEdges {
  std::vector<int32_t> edges;  // 2 per edge
  std::vector<int> owner;
};
inline GlobalEdges global_edges(const std::vector<int32_t>& tris, const mpi_tools::Owners& owners) {
  GlobalEdges g;
  g.edges = ref::derive_edges(tris);
  const size_t ne = g.edges.size() / 2;
  std::vector<std::pair<int32_t, int32_t>> keys(ne);
  for (size_t e = 0; e < ne; ++e) keys[e] = {g.edges[2 * e], g.edges[2 * e + 1]};
  g.owner.assign(ne, -1);
  for (size_t t = 0; t < tris.size() / 3; ++t)
    for (int k = 0; k < 3; ++k) {
      const int32_t a = tris[3 * t + size_t(k)], b = tris[3 * t + size_t((k + 1) % 3)];
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      int& o = g.owner[size_t(std::lower_bound(keys.begin(), keys.end(), key) - keys.begin())];
      if (o < 0) o = owners.triangle[t];
    }
  return g;
}

// The options both take: [--size N | --mesh PATH] [--steps S] [--radius-factor F] [--motion M]
// [--partitions LIST] [--out FILE], and --threads T where `threads` is asked for (0 = not given).
struct Options {
  int n = 301, steps = 10, threads = 0;
  double factor = 0.25, motion = 0.2;
  std::string out, mesh_path, partitions = "slab,morton,random";
};
inline Options parse_options(int argc, char** argv, Options o, bool threads) {
  for (int i = 1; i < argc; i += 2) {
    const std::string a = argv[i];
    if (i + 1 >= argc) {
      std::fprintf(stderr, "%s: %s needs a value\n", argv[0], a.c_str());
      MPI_Abort(MPI_COMM_WORLD, 2);
    }
    const char* v = argv[i + 1];
    if (a == "--size") o.n = std::atoi(v);
    else if (a == "--mesh") o.mesh_path = v;
    else if (a == "--steps") o.steps = std::atoi(v);
    else if (a == "--radius-factor") o.factor = std::atof(v);
    else if (a == "--motion") o.motion = std::atof(v);
    else if (a == "--partitions") o.partitions = v;
    else if (a == "--out") o.out = v;
    else if (threads && a == "--threads") o.threads = std::atoi(v);
    else {
      std::fprintf(stderr, "%s: unknown option %s\n", argv[0], a.c_str());
      MPI_Abort(MPI_COMM_WORLD, 2);
    }
  }
  return o;
}

// The scene of the options: its motion, its first positions, r and a name for the table.
struct Scene {
  Motion motion;
  ref::Mesh first;
  float r = 0;
  std::string name;
};
inline Scene make_scene(const Options& o) {
  Scene s;
  if (o.mesh_path.empty()) s.motion.n = o.n;
  else s.motion.mesh = ref::load_mesh(o.mesh_path);
  s.first = s.motion.at(0);
  s.r = float(o.factor * ref::mean_edge_length(s.first));
  s.motion.scale(s.first, s.r, o.motion);
  s.name = s.motion.n ? "twisted sheet " + std::to_string(o.n) + "x" + std::to_string(o.n)
                      : o.mesh_path.substr(o.mesh_path.find_last_of('/') + 1);
  return s;
}

inline std::vector<mpi_tools::Partition> partition_list(const std::string& list) {
  std::vector<mpi_tools::Partition> kinds;
  for (size_t at = 0; at < list.size();) {
    const size_t comma = std::min(list.find(',', at), list.size());
    kinds.push_back(mpi_tools::parse_partition(list.substr(at, comma - at)));
    at = comma + 1;
  }
  return kinds;
}

// A single-process result's pairs, sorted, as global ids (the whole mesh's indices).
inline mpi_tools::GlobalPairs result_pairs(const minkq_result* result) {
  mpi_tools::GlobalPairs pairs;
  const int32_t* p = minkq_result_pairs(result);
  for (size_t i = 0; i < minkq_result_count(result); ++i) pairs.push_back({p[2 * i], p[2 * i + 1]});
  std::sort(pairs.begin(), pairs.end());
  return pairs;
}

}  // namespace minkq::mpi_bench
