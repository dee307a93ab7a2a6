/*
 * minkq_mpi: VT and EE queries of one mesh split over the ranks of an MPI communicator.
 *
 * A simulator that decomposes its mesh over MPI ranks passes each rank's part: its local
 * vertices and triangles, a global id for each, and which of them the rank owns. Each global
 * vertex and each global triangle is owned by exactly one rank; a vertex on a partition
 * boundary (a corner of triangles owned by several ranks) appears on each of them, owned by one.
 * A query returns, on each rank, pairs in global ids such that:
 *   - the union over the ranks is exactly the pair set of the same query (kind, mode, flags,
 *     radius) on the whole mesh in one process, with the whole mesh's vertex i the vertex of
 *     global id i and its triangle j the triangle of global id j (when the ids are 0..n-1; any
 *     distinct non-negative ids otherwise, in their order);
 *   - each pair is returned by exactly one rank: VT (v, t) by the owner of triangle t, EE (e, f)
 *     by the owner of edge e (e < f);
 *   - whatever the partition: slabs, space-filling-curve chunks, graph partitions or a random
 *     assignment (which makes every rank a neighbour of every other: correct, only slower).
 * VT pairs are (global vertex id, global triangle id). EE pairs are (e, f), e < f, in the
 * global edge numbering: every distinct undirected edge of the global triangles, numbered
 * from 0 in lexicographic order of (smaller global vertex id, larger global vertex id). With
 * the ids 0..n-1 of a single-process mesh this is exactly minkq_scene_edges' numbering, so the
 * pairs are those minkq_scene_query gives on that mesh. An edge is owned by the owner of the
 * lowest-id global triangle it bounds.
 *
 * Positions: a vertex is where its owner says. The positions of a rank's copies of vertices
 * it does not own are checked to be finite and otherwise not read: each call that moves the
 * vertices fetches them from their owners.
 *
 * How: each rank builds minkq scenes over its owned triangles and owned edges plus a ghost
 * layer: the vertices and edges other ranks own that come within reach (r, with a relative
 * margin) of the box of its triangles. Ghosts go only to the ranks whose box they can reach:
 * point-to-point messages between neighbours, after one all-gather of the ranks' boxes per
 * query. The local trees are refit when the ghost layer keeps its members, and built afresh
 * when it changes or after minkq_mpi_scene_rebuild. With a skin (minkq_mpi_scene_set_skin) the
 * layer is a skin wider and is kept while no vertex has moved more than half a skin since it
 * was chosen: queries then send only the ghosts' new positions, to the same ranks.
 *
 * Collective calls: every function taking a scene (and minkq_mpi_scene_create) is collective
 * over the scene's communicator: every rank calls it, in the same order, with the same query
 * description and flags. Errors are collective too: a bad input on one rank (a non-finite
 * vertex, an index out of range, a vertex or triangle owned by two ranks or by none, a copy
 * of a triangle whose vertices differ from its owner's) makes the call fail on every rank with
 * the same status and the same message, naming the rank and the element ("rank 2: vertex 7
 * (global id 1041) has a non-finite coordinate (nan, 0, 1)"); the scenes then keep their
 * state. Failures of MPI itself are reported as MINKQ_ERROR_INTERNAL where MPI returns them.
 * Calling collectives in different orders on different ranks deadlocks, as with MPI.
 *
 * Not yet distributed: MINKQ_SCENE_FLOAT64, VV and EV scenes, swept queries, the asynchronous
 * calls and MINKQ_QUERY_DIGEST (UNSUPPORTED). A rank's device (such as "cuda:N" for its local
 * rank) runs its local trees and queries. Buffers are host memory, or device memory on a CUDA
 * rank: the library reads every input on the host (it checks it and sends parts of it to other
 * ranks), so device buffers are copied down first (also with a CUDA-aware MPI); results are
 * host memory.
 */
#ifndef MINKQ_MPI_H
#define MINKQ_MPI_H

#include <mpi.h>

#include "minkq.h"

/* MINKQ_MPI_API marks each function libminkq_mpi exports (as MINKQ_API does for libminkq): the
 * library hides every other symbol, and its version script lets out only minkq_mpi_* at version
 * MINKQ_MPI_<ABI>. */
#define MINKQ_MPI_API MINKQ_API

#ifdef __cplusplus
extern "C" {
#endif

/* Bumped whenever a struct layout or function signature of this header changes. */
#define MINKQ_MPI_ABI_VERSION 1

/* The message of the calling thread's last failed minkq_mpi call ("" after a success): the
 * same text on every rank. Valid until the next minkq_mpi call on this thread. */
MINKQ_MPI_API const char* minkq_mpi_last_error_message(void);

typedef struct minkq_mpi_scene minkq_mpi_scene;

typedef struct minkq_mpi_scene_desc {
  uint32_t flags;              /* MINKQ_SCENE_VT, MINKQ_SCENE_EE (at least one), DROP_INCIDENT */
  minkq_buffer vertices;       /* 3 floats per local vertex; stride >= 12 (every buffer: host memory,
                                  or device memory on a CUDA device) */
  minkq_buffer triangles;      /* 3 int32 local vertex indices per local triangle; stride >= 12 */
  minkq_buffer vertex_ids;     /* one int64 >= 0 per local vertex, distinct on the rank */
  minkq_buffer triangle_ids;   /* one int64 >= 0 per local triangle, distinct on the rank */
  minkq_buffer vertex_owned;   /* one uint8 per local vertex: 1 when this rank owns it, else 0 */
  minkq_buffer triangle_owned; /* one uint8 per local triangle: 1 when this rank owns it, else 0 */
} minkq_mpi_scene_desc;

/* Creates a distributed scene over `comm` (duplicated: the scene communicates on its own
 * communicator) with its local trees on `device`, and stores it in *out_scene (NULL on
 * failure, on every rank). Checks every rank's part and their agreement, then numbers the
 * global edges. Errors: INVALID_ARGUMENT (NULL pointer; unknown flag bits or none of VT and
 * EE; a count that differs from the vertices' or triangles'; device memory on a CPU device; an owned flag
 * other than 0 and 1; a negative id; a global id twice on one rank; a vertex or triangle owned
 * by two ranks; a copy nobody owns; a triangle copy whose global vertex ids differ from the
 * owner's), UNSUPPORTED (FLOAT64, VV, EV), NON_FINITE, INDEX_OUT_OF_RANGE, SIZE_OVERFLOW, and
 * those of minkq_scene_create on any rank. Release with minkq_mpi_scene_release. */
MINKQ_MPI_API minkq_status minkq_mpi_scene_create(MPI_Comm comm, minkq_device* device, const minkq_mpi_scene_desc* desc,
                                                  minkq_mpi_scene** out_scene);
/* Releases a distributed scene (collective: frees its communicator). NULL is ignored. */
MINKQ_MPI_API void minkq_mpi_scene_release(minkq_mpi_scene* scene);

/* Moves the rank's local vertices (its vertex count, a buffer as at creation, finite) and fetches its
 * copies' positions from their owners. The next query refits the local trees (rebuild: builds
 * them afresh), or builds them when its ghost layer changed. Errors: INVALID_ARGUMENT (NULL
 * scene, another vertex count, a bad buffer), NON_FINITE; the scene then keeps its positions
 * on every rank. */
MINKQ_MPI_API minkq_status minkq_mpi_scene_refit(minkq_mpi_scene* scene, minkq_buffer vertices);
MINKQ_MPI_API minkq_status minkq_mpi_scene_rebuild(minkq_mpi_scene* scene, minkq_buffer vertices);

/* Sets the skin: a width s >= 0 (finite, the same on every rank) by which the ghost layer is
 * chosen wider, so that later queries with the same radius keep it, sending only the ghosts'
 * positions, until some vertex has moved more than s / 2 (on an axis) since it was chosen;
 * then the next query chooses it afresh. 0 (the default) chooses it at every query. A wider
 * skin sends more ghosts less often; the pairs are the same for every skin. Collective.
 * Errors: INVALID_ARGUMENT (NULL scene, a negative skin, skins that differ between the ranks),
 * NON_FINITE. */
MINKQ_MPI_API minkq_status minkq_mpi_scene_set_skin(minkq_mpi_scene* scene, double skin);

/* Writes to *out_growth, on every rank, how far the refits since the last builds have stretched
 * the local trees: the largest minkq_scene_tree_growth over the ranks' VT and EE trees (1 when
 * none has been refit, or before the first query builds them). Rebuild (minkq_mpi_scene_rebuild)
 * when it passes about 1.5, as for one scene. Collective. Errors: INVALID_ARGUMENT (NULL scene
 * or out_growth, on any rank). */
MINKQ_MPI_API minkq_status minkq_mpi_scene_tree_growth(minkq_mpi_scene* scene, double* out_growth);

/* A rank's share of the pairs of the last query, in global ids: a growing host buffer that the
 * library owns. Not collective. */
typedef struct minkq_mpi_result minkq_mpi_result;
MINKQ_MPI_API minkq_status minkq_mpi_result_create(minkq_mpi_result** out_result);
MINKQ_MPI_API void minkq_mpi_result_release(minkq_mpi_result* result);
/* This rank's number of pairs (0 after a failed query or for NULL). */
MINKQ_MPI_API uint64_t minkq_mpi_result_count(const minkq_mpi_result* result);
/* This rank's pairs, 2 * count int64 (see the header comment for what they are), valid until
 * the result is reused or released; NULL after a MINKQ_QUERY_COUNT query. */
MINKQ_MPI_API const int64_t* minkq_mpi_result_pairs(const minkq_mpi_result* result);
/* This rank's local work counts, with MINKQ_QUERY_STATS (ghosts included), else all 0. */
MINKQ_MPI_API minkq_query_stats minkq_mpi_result_stats(const minkq_mpi_result* result);

/* Runs a VT or EE query of the whole mesh: this rank's share of the pairs into `result`
 * (see the header comment). query as for minkq_scene_query: modes, LEAF_EXACT, CANONICAL (this
 * rank's pairs sorted lexicographically), STATS and COUNT; the same description on every rank.
 * Errors: INVALID_ARGUMENT (NULL scene, query or result; a kind the scene was created without,
 * VV or EV; a bad mode, flag or radius as minkq_scene_query), UNSUPPORTED (DIGEST), NON_FINITE
 * (radius), OUT_OF_MEMORY, and those of the local minkq calls on any rank. On failure every
 * rank's result holds no pairs. */
MINKQ_MPI_API minkq_status minkq_mpi_scene_query(minkq_mpi_scene* scene, const minkq_query_desc* query,
                                                 minkq_mpi_result* result);

/* A rank's figures: what it owns, its copies, the ghost layer of its last query, and where that
 * query's time went. */
typedef struct minkq_mpi_rank_info {
  uint64_t owned_vertices, owned_triangles, owned_edges;
  uint64_t copied_vertices;     /* local vertices owned by other ranks */
  uint64_t ghost_vertices;      /* received for the last VT query */
  uint64_t ghost_edges;         /* received for the last EE query */
  uint64_t neighbours;          /* ranks it exchanged ghosts with in the last query */
  uint64_t global_edges;        /* the whole mesh's edge count */
  uint64_t local_builds;        /* local trees built (created or rebuilt) so far, VT and EE */
  uint64_t local_refits;        /* local trees refit so far */
  uint64_t ghost_exchanges;     /* ghost layers chosen and sent so far, VT and EE */
  uint64_t ghost_updates;       /* queries that kept their ghost layer (a skin), moving it only */
  uint64_t bytes_sent;          /* payload this rank sent (ghosts, positions for copies) so far */
  /* The last query on this rank: bytes of ghosts (or their positions) sent, and where its time
   * went, in ms: the ranks' reach boxes (one all-gather), the ghost layer (choosing, sending,
   * receiving, assembling), the local trees (build, rebuild or refit), the local query. */
  uint64_t last_bytes_sent;
  double last_reach_ms, last_ghost_ms, last_trees_ms, last_query_ms;
} minkq_mpi_rank_info;
/* Not collective. Errors: INVALID_ARGUMENT (NULL scene or out_info). */
MINKQ_MPI_API minkq_status minkq_mpi_scene_rank_info(const minkq_mpi_scene* scene, minkq_mpi_rank_info* out_info);

#ifdef __cplusplus
}
#endif

#endif /* MINKQ_MPI_H */
