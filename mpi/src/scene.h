// What a distributed scene keeps on each rank, and the steps its calls are made of:
//   setup.cpp   ownership (who owns each global vertex and triangle, checked across ranks),
//               the halo (where each copy's position comes from) and the global edge numbering;
//   ghosts.cpp  the ghost layer of one query and the local minkq scene over it;
//   api.cpp     the C functions of minkq_mpi.h: checks, phases, results.
#pragma once

#include <mpi.h>

#include <chrono>
#include <cstdint>
#include <string>
#include <unordered_map>
#include <vector>

#include "minkq.h"
#include "minkq_mpi.h"

namespace minkq::mpi {

// Where this rank's copies get their positions, and whose copies it feeds.
struct Halo {
  std::vector<int> sources;                  // owner ranks of this rank's copies
  std::vector<std::vector<int32_t>> fill;    // per source: the local copies it sends, in order
  std::vector<int> dests;                    // ranks holding copies of this rank's vertices
  std::vector<std::vector<int32_t>> send;    // per dest: the local owned vertices it gets
};

// An edge this rank owns: its local vertices and its global id.
struct OwnedEdge {
  int32_t a, b;
  int64_t id;
};

// One minkq scene over this rank's owned triangles (VT) or owned edges (EE) and a ghost layer.
struct LocalScene {
  minkq_scene* scene = nullptr;
  std::vector<int64_t> vertex_ids;   // scene vertex -> global vertex id
  std::vector<int64_t> element_ids;  // scene triangle or edge -> global id
  std::vector<uint8_t> owned;        // EE: scene edge owned by this rank
  std::vector<int64_t> signature;    // the ghost layer's members, in arrival order
  bool refit = false, rebuild = false;  // what the positions' last move asks of the trees
  uint64_t ghosts = 0;
  std::vector<uint32_t> reach_order;  // the owned elements' Morton order, for the reach boxes
  // The last exchange's pattern, which a skin lets later queries reuse: then only the ghosts'
  // positions travel, along the same messages, and the trees are refit.
  struct Pattern {
    bool valid = false;
    float radius = 0;
    std::vector<int> dests, sources;
    std::vector<std::vector<int32_t>> sent;     // per dest: local vertices (VT) or owned edges (EE)
    std::vector<std::vector<int32_t>> targets;  // per source: the scene vertex of each position
    std::vector<float> reference;               // the local positions at the exchange
    std::vector<float> xyz;                     // the local scene's positions
  } pattern;
};

struct SceneState {
  MPI_Comm comm = MPI_COMM_NULL;
  int rank = 0, size = 1;
  minkq_device* device = nullptr;
  uint32_t flags = 0;
  // The rank's part.
  std::vector<int64_t> vertex_ids;
  std::unordered_map<int64_t, int32_t> local_index;  // global vertex id -> local vertex
  std::vector<uint8_t> vertex_owned;
  std::vector<float> xyz;  // 3 per local vertex; a copy holds its owner's position
  std::vector<int32_t> triangles;    // owned triangles, 3 local vertex indices each
  std::vector<int64_t> triangle_ids; // their global ids
  std::vector<OwnedEdge> edges;      // owned edges
  uint64_t owned_vertices = 0, copied_vertices = 0, global_edges = 0;
  Halo halo;
  LocalScene vt, ee;
  double skin = 0;  // minkq_mpi_scene_set_skin
  // Where the last query's time went (minkq_mpi_rank_info), and the bytes sent.
  struct Phases {
    double reach_ms = 0, ghost_ms = 0, trees_ms = 0, query_ms = 0;
    uint64_t bytes = 0;
  } last;
  uint64_t bytes_sent = 0;
  uint64_t neighbours = 0, builds = 0, refits = 0, exchanges = 0, updates = 0;
  minkq_result* local_result = nullptr;
};

inline double elapsed_ms(std::chrono::steady_clock::time_point since) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - since).count();
}
// The bytes of a set of messages.
template <class T>
uint64_t payload(const std::vector<std::vector<T>>& messages) {
  uint64_t bytes = 0;
  for (const auto& m : messages) bytes += m.size() * sizeof(T);
  return bytes;
}

// setup.cpp: the collective phases of minkq_mpi_scene_create after the local checks. Each
// returns the agreed status; triangles/triangle_ids hold every local triangle on entry (with
// `triangle_owned`), only the owned ones on success.
minkq_status setup_ownership(SceneState& s, const std::vector<int32_t>& local_triangles,
                             const std::vector<int64_t>& local_triangle_ids, const std::vector<uint8_t>& triangle_owned);
minkq_status setup_edges(SceneState& s);
// Fills every copy's position from its owner (communication only; cannot fail on input).
void exchange_halo(SceneState& s);

// ghosts.cpp: exchanges the ghost layer for a query of `kind` and radius r and brings the
// local scene of that kind up to date (built, refit or rebuilt). Collective; returns the
// agreed status.
minkq_status prepare_local_scene(SceneState& s, minkq_query_kind kind, float radius);

}  // namespace minkq::mpi

struct minkq_mpi_scene : minkq::mpi::SceneState {};

struct minkq_mpi_result {
  std::vector<int64_t> pairs;
  uint64_t count = 0;
  bool has_pairs = false;
  minkq_query_stats stats{};
};
