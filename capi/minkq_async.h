/*
 * minkq_async.h: the stream-ordered calls of minkq's C API. Part of minkq.h, which includes it
 * where they belong (after the queries); a program includes minkq.h. Kept apart because it is
 * one concept of its own: the calls that enqueue a scene's refits, rebuilds and queries on a
 * stream without waiting, so that a simulator can capture them in a CUDA graph.
 */
#ifndef MINKQ_ASYNC_H
#define MINKQ_ASYNC_H

#include "minkq.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- Stream-ordered calls: a scene inside a simulator's captured step -------------------
 *
 * The *_async calls enqueue their work on a stream and return without waiting for it: they do
 * not synchronise, allocate or read device results on the host, so a sequence of them (refit,
 * VT and EE queries) can be recorded into a CUDA graph by stream capture and replayed over new
 * data. On a CUDA device:
 *   - the stream is a cudaStream_t of the scene's device, passed as a pointer (NULL: CUDA's
 *     default stream), and the scene's asynchronous work is ordered on it only: the caller orders its own work (and
 *     other streams) around it, and keeps the buffers alive until the work has run;
 *   - every buffer is device memory: vertices.memory must be MINKQ_MEMORY_DEVICE, and all
 *     buffers are checked as device buffers of blocking calls are;
 *   - the scene's scratch (see minkq_scene_reserve) is shared by its asynchronous calls:
 *     enqueue them on one stream, or order their streams; a blocking call runs on the calling
 *     thread's per-thread default stream and does not wait for work enqueued elsewhere;
 *   - a captured graph keeps what the calls were given and the scene's device memory: the
 *     radius, the capacities and every buffer's address. Blocking calls between replays
 *     (refits, rebuilds, queries of any size) neither move nor outgrow the memory a graph uses:
 *     a scene's first stream-ordered call, like minkq_scene_reserve (any flags, none too), fixes
 *     its trees' nodes at their bound, allocating (see minkq_scene_reserve): make one of them
 *     before capturing. A larger pair buffer, another radius or other flags mean capturing again.
 * On the CPU the same calls run to completion before returning, on host memory
 * (vertices.memory MINKQ_MEMORY_HOST), and the stream is ignored. Both backends apply the same
 * rules, so a program tested on the CPU keeps them on CUDA.
 *
 * Checked at once, as by the blocking calls and with their errors, before anything is
 * enqueued: handles, descriptions, counts, strides, memory kinds, capacities, the radius and
 * reservations. The data read on the device (vertex coordinates) is checked by the device: a
 * refit or rebuild whose vertices hold a NaN or infinity leaves the scene's positions as they
 * were (a rebuild then builds the trees for those positions), and records the scene's pending
 * error, which minkq_scene_async_status returns and clears. Queries run on the positions the
 * scene holds.
 *
 * Scenes of several geometries take them too: the whole-scene moves take the moving geometries'
 * vertices one after another (of one precision, as minkq_scene_refit does), each geometry checks
 * its own part on the device and keeps its positions as a whole when that holds a NaN or infinity
 * (the others take theirs; minkq_scene_async_status names the buffer's vertex and its geometry).
 * Their queries run from tables of jobs in device memory, one per query kind and arrangement of
 * the geometries (which ones are swept): minkq_scene_reserve writes those of the arrangements its
 * stream-ordered moves reach (every moving geometry at rest; with MINKQ_RESERVE_SWEPT, every one
 * swept). After a blocking move of one geometry into another arrangement, the next stream-ordered
 * query writes its table first (allocating and copying, so not while capturing: make one such
 * query, or minkq_scene_reserve again, before capturing). Their VT and EE queries of one
 * minkq_scene_query_vt_ee_async are two launches, one after the other.
 *
 * Flags: MINKQ_QUERY_LEAF_EXACT and MINKQ_QUERY_CANONICAL (pairs sorted when they all fit,
 * with scratch reserved for the capacity); MINKQ_QUERY_DIGEST and MINKQ_QUERY_STATS need a
 * host read and return MINKQ_ERROR_UNSUPPORTED here. */
typedef void* minkq_stream;

typedef enum minkq_reserve_flags {
  MINKQ_RESERVE_REFIT = 1,   /* scratch for minkq_scene_refit_async and the pending error */
  MINKQ_RESERVE_REBUILD = 2, /* also the tree builds' scratch, for minkq_scene_rebuild_async */
  MINKQ_RESERVE_SWEPT = 4    /* with REFIT or REBUILD: the swept calls' second positions */
} minkq_reserve_flags;

/* Reserves, on the scene's device, the scratch its asynchronous calls use, so that they never
 * allocate: MINKQ_RESERVE_REFIT for refits (a copy of the vertices), MINKQ_RESERVE_REBUILD for
 * refits and rebuilds (about the trees' size again), MINKQ_RESERVE_SWEPT with either for the swept
 * calls (two more copies of the vertices), and canonical_capacity pairs for the sort
 * of canonical asynchronous queries (queries with a larger capacity return INVALID_ARGUMENT).
 * Queries without MINKQ_QUERY_CANONICAL need no reservation to run. Reservations only grow and
 * last as long as the scene; call this before capturing. On CUDA every call, whatever its flags
 * (0 too), also sizes each tree's nodes for the most any build over its n elements keeps
 * (n - 1 nodes, 68 bytes each with the refit's flags) and fixes them there, so that no later
 * rebuild, blocking or stream-ordered, moves them or runs out of room (a stream-ordered rebuild
 * cannot grow them: it neither allocates nor reads the node count back). Unreserved, a CUDA
 * tree holds room for half again the nodes a build kept, which a later blocking build grows
 * (moving them) when it keeps more; a scene's first stream-ordered call fixes them as this call
 * does. A blocking call (it may allocate and synchronise).
 * Errors: INVALID_ARGUMENT (NULL scene, unknown flag bits), SIZE_OVERFLOW
 * (canonical_capacity over SIZE_MAX / 16: the sort keeps 16 bytes a pair), OUT_OF_MEMORY (where
 * the device cannot hold the scratch; on the CPU only MINKQ_RESERVE_REBUILD keeps any: the
 * builds' scratch, about 64 bytes per element of each tree, and the triangles and edges by id
 * (12 and 8 bytes each: the trees keep them in their leaf order), so that rebuilds allocate
 * nothing), DEVICE. */
MINKQ_API minkq_status minkq_scene_reserve(minkq_scene* scene, uint32_t flags, size_t canonical_capacity);

/* minkq_scene_refit, enqueued on `stream` (see above: the vertices in device memory on CUDA;
 * non-finite coordinates reported by minkq_scene_async_status). Needs MINKQ_RESERVE_REFIT.
 * Errors (at once): those of minkq_scene_refit except NON_FINITE; INVALID_ARGUMENT without the
 * reservation or for host vertices on a CUDA device (device ones on the CPU); DEVICE. */
MINKQ_API minkq_status minkq_scene_refit_async(minkq_scene* scene, minkq_buffer vertices, minkq_stream stream);
/* minkq_scene_rebuild, enqueued on `stream`, as minkq_scene_refit_async; its trees are those
 * minkq_scene_rebuild builds, whatever number of nodes they keep (the reservation sized the
 * nodes for every build, so none is refused for room). Needs MINKQ_RESERVE_REBUILD. */
MINKQ_API minkq_status minkq_scene_rebuild_async(minkq_scene* scene, minkq_buffer vertices, minkq_stream stream);

/* minkq_scene_refit_swept and minkq_scene_rebuild_swept, enqueued on `stream`, as
 * minkq_scene_refit_async and minkq_scene_rebuild_async are: x0 and x1 in device memory on CUDA,
 * checked together on the device; with a non-finite coordinate in either the scene keeps its
 * positions at rest (x1 = x0: queries then give the static pairs at x0) and
 * minkq_scene_async_status reports it. Need MINKQ_RESERVE_SWEPT with MINKQ_RESERVE_REFIT (refit)
 * or MINKQ_RESERVE_REBUILD (rebuild). */
MINKQ_API minkq_status minkq_scene_refit_swept_async(minkq_scene* scene, minkq_buffer x0, minkq_buffer x1,
                                                   minkq_stream stream);
MINKQ_API minkq_status minkq_scene_rebuild_swept_async(minkq_scene* scene, minkq_buffer x0, minkq_buffer x1,
                                                       minkq_stream stream);

/* minkq_scene_query, enqueued on `stream`: writes the exact number of pairs to *out_count (a
 * uint64_t in device memory on CUDA, host memory on the CPU), also when it exceeds capacity,
 * and min(count, capacity) of the pairs to out_pairs (device memory on CUDA, host on the CPU),
 * never past it: which ones, and in what order, when they do not all fit, is unspecified. A
 * simulator grows its buffer between steps when the count says so. CANONICAL sorts the pairs
 * when they fit and needs capacity <= the reserved canonical capacity. Cost: on CUDA the count
 * stays on the device, so CANONICAL sorts all `capacity` slots (those past the count padded),
 * on every call and replay, however few pairs were found: pass a capacity near the counts
 * expected, or sort after reading the count. Blocking queries sort only the pairs found; on the
 * CPU both sort only those. Errors (at once): those
 * of minkq_scene_query for the description and buffers; INVALID_ARGUMENT for a NULL out_count,
 * or a canonical capacity over the reservation; UNSUPPORTED for DIGEST or STATS; never
 * CAPACITY. */
MINKQ_API minkq_status minkq_scene_query_async(minkq_scene* scene, const minkq_query_desc* query, int32_t* out_pairs,
                                               size_t capacity, uint64_t* out_count, minkq_stream stream);
/* minkq_scene_query_vt_ee, enqueued on `stream`: one kernel launch for both queries, each
 * query's pairs and count as minkq_scene_query_async gives it alone. Errors: those of
 * minkq_scene_query_async for either query; INVALID_ARGUMENT when a kind is the wrong one or
 * vt_count and ee_count are the same pointer. */
MINKQ_API minkq_status minkq_scene_query_vt_ee_async(minkq_scene* scene, const minkq_query_desc* vt_query,
                                                     const minkq_query_desc* ee_query, int32_t* vt_pairs,
                                                     size_t vt_capacity, uint64_t* vt_count, int32_t* ee_pairs,
                                                     size_t ee_capacity, uint64_t* ee_count, minkq_stream stream);

/* Waits for the work enqueued on `stream` (CUDA), then returns the scene's pending error and
 * clears it: MINKQ_SUCCESS when every asynchronous refit and rebuild since the last call (or
 * the reservation) accepted its vertices, else the status of the first one that did not, with
 * a message naming the call and the vertex ("minkq_scene_refit_async: vertex 12 has a
 * non-finite coordinate; the scene kept its positions"). A blocking call. Errors:
 * INVALID_ARGUMENT (NULL scene), NON_FINITE (the pending error), DEVICE. */
MINKQ_API minkq_status minkq_scene_async_status(minkq_scene* scene, minkq_stream stream);

#ifdef __cplusplus
}
#endif

#endif /* MINKQ_ASYNC_H */
