/*
 * minkq: which pairs of mesh elements may lie within distance r of each other?
 *
 * A stable C99 ABI over the C++/CUDA core. Objects are opaque handles created and released by
 * the library; every object belongs to a device. Functions return a minkq_status; on failure
 * minkq_last_error_message() holds a message naming the offending element. Arrays are passed
 * as minkq_buffer: pointer, byte stride, element count and memory kind (host or device).
 *
 * Guarantee: every pair of elements within r is reported (zero false negatives), in every
 * mode, for every finite input; finer modes report subsets of coarser ones:
 *   true contacts <= capsule_exact <= capsule_ray <= box   (EE)
 *   true contacts <= sphere <= box                         (VT)
 * and MINKQ_QUERY_LEAF_EXACT keeps, of any mode's pairs, the true contacts (plus at most pairs
 * within the leaf test's slack, stated at minkq_scene_query).
 *
 * Thread safety: different objects may be used from different threads at once. One object
 * (device, scene, bvh, result) must not be used by two threads at the same time; a device
 * may be shared by scenes used from different threads. On CUDA, creating and rebuilding
 * scenes and bvhs frees temporary device memory, which waits for all work on the GPU: such
 * calls are safe from several threads but do not overlap other threads' GPU work. Each call
 * selects its device for its duration and gives the calling thread's current device back.
 */
#ifndef MINKQ_H
#define MINKQ_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* ---- Versions ------------------------------------------------------------------------------ */
#define MINKQ_VERSION_MAJOR 0
#define MINKQ_VERSION_MINOR 3
#define MINKQ_VERSION_PATCH 0
/* Bumped whenever a struct layout, enum value or function signature changes. */
#define MINKQ_ABI_VERSION 2

/* The library's run-time version as MAJOR * 10000 + MINOR * 100 + PATCH. */
uint32_t minkq_version(void);
/* The run-time ABI version; compare with MINKQ_ABI_VERSION to detect a mismatched library. */
uint32_t minkq_abi_version(void);

/* ---- Errors -------------------------------------------------------------------------------- */
typedef enum minkq_status {
  MINKQ_SUCCESS = 0,
  MINKQ_ERROR_INVALID_ARGUMENT = 1,   /* null pointer, bad enum, stride or flag combination */
  MINKQ_ERROR_NON_FINITE = 2,         /* NaN or infinity in a coordinate or radius */
  MINKQ_ERROR_INDEX_OUT_OF_RANGE = 3, /* negative or too large vertex index */
  MINKQ_ERROR_SIZE_OVERFLOW = 4,      /* count whose byte size overflows, or over 2^31 - 2 */
  MINKQ_ERROR_CAPACITY = 5,           /* output buffer too small; the exact count is returned */
  MINKQ_ERROR_UNSUPPORTED = 6,        /* e.g. CUDA asked for where there is none */
  MINKQ_ERROR_OUT_OF_MEMORY = 7,
  MINKQ_ERROR_DEVICE = 8,             /* a CUDA runtime call failed */
  MINKQ_ERROR_INTERNAL = 9
} minkq_status;

/* The message of the last failed call on this thread ("" if none). Valid until the next minkq
 * call on this thread. Thread safety: per-thread. */
const char* minkq_last_error_message(void);
/* A static name for a status ("MINKQ_ERROR_CAPACITY"). */
const char* minkq_status_name(minkq_status status);

/* ---- Buffers ------------------------------------------------------------------------------- */
typedef enum minkq_memory {
  MINKQ_MEMORY_HOST = 0,  /* ordinary host memory */
  MINKQ_MEMORY_DEVICE = 1 /* CUDA device memory of the object's device (CUDA devices only) */
} minkq_memory;

/* `count` elements, element i at (const char*)data + i * byte_stride. byte_stride 0 means
 * packed (the element's own size). data may be NULL only when count is 0. */
typedef struct minkq_buffer {
  const void* data;
  size_t byte_stride;
  size_t count;
  minkq_memory memory;
} minkq_buffer;

/* ---- Devices ------------------------------------------------------------------------------- */
typedef struct minkq_device minkq_device;

typedef enum minkq_backend {
  MINKQ_BACKEND_CPU = 0,  /* all cores, through a thread pool */
  MINKQ_BACKEND_CUDA = 1
} minkq_backend;

/* Creates a device from "cpu", "cuda" (device 0), "cuda:N" or "auto" (CUDA if a GPU is usable,
 * else CPU). Errors: INVALID_ARGUMENT for an unknown spec, UNSUPPORTED when CUDA is asked for
 * where minkq was built without it or no such GPU exists. Release with minkq_device_release. */
minkq_status minkq_device_create(const char* spec, minkq_device** out_device);
/* Releases a device; every scene, bvh and result made on it must be released first. NULL ok. */
void minkq_device_release(minkq_device* device);
minkq_backend minkq_device_backend(const minkq_device* device);
/* A static description, e.g. "cpu (8 threads)" or "cuda:0 (NVIDIA H100 80GB HBM3)". */
const char* minkq_device_name(const minkq_device* device);
/* Number of usable CUDA devices (0 where built without CUDA or no GPU is present). */
int minkq_cuda_device_count(void);

/* ---- Mesh scenes: VT and EE queries ------------------------------------------------------- */
typedef struct minkq_scene minkq_scene;

typedef enum minkq_scene_flags {
  MINKQ_SCENE_VT = 1,           /* build the triangle tree for vertex-triangle queries */
  MINKQ_SCENE_EE = 2,           /* build the edge tree for edge-edge queries */
  MINKQ_SCENE_DROP_INCIDENT = 4 /* drop (v, t) with v a vertex of t, and edges sharing a vertex */
} minkq_scene_flags;

typedef struct minkq_scene_desc {
  uint32_t flags;         /* minkq_scene_flags; at least one of VT and EE */
  minkq_buffer vertices;  /* 3 floats (x, y, z) each; stride >= 12 */
  minkq_buffer triangles; /* 3 int32 vertex indices each; stride >= 12 */
  /* 2 int32 vertex indices each, or count 0 to derive them from the triangles: every distinct
   * undirected triangle edge, numbered in lexicographic order of (min vertex, max vertex). */
  minkq_buffer edges;
} minkq_scene_desc;

/* Copies the mesh to the device and builds the trees the flags ask for (a VT-only scene builds
 * no edge tree). Errors: NON_FINITE ("vertex 12 has a non-finite coordinate"),
 * INDEX_OUT_OF_RANGE, SIZE_OVERFLOW, INVALID_ARGUMENT (null pointer with non-zero count, stride
 * too small, no query kind, device memory on a CPU device). Release with minkq_scene_release. */
minkq_status minkq_scene_create(minkq_device* device, const minkq_scene_desc* desc, minkq_scene** out_scene);
void minkq_scene_release(minkq_scene* scene);
/* Moves the vertices (same count, any stride/memory) and refits the trees in place. On error
 * the scene keeps its previous positions. A refit keeps the grouping of the last build: after
 * large deformations its boxes overlap more and queries visit more nodes (see
 * minkq_scene_tree_growth); the pairs found never change. */
minkq_status minkq_scene_refit(minkq_scene* scene, minkq_buffer vertices);
/* Moves the vertices like minkq_scene_refit and builds the trees afresh for the new positions
 * (the trees minkq_scene_create builds there; topology and edge numbering are kept). Same
 * errors as minkq_scene_refit; on error the scene keeps its positions and trees. */
minkq_status minkq_scene_rebuild(minkq_scene* scene, minkq_buffer vertices);
/* How far the refits since the last build have stretched the trees: their area cost now over
 * its value right after that build, for the larger of the scene's trees; 1 after a build. The
 * area cost (the surface areas of every node's child boxes, summed, over the root box's) is
 * scale-free and grows with the nodes a query visits. It sees boxes that stretch, not a mesh
 * that folds or flattens into new neighbours: on the benchmark scenes a sheet wrung by three
 * turns after its build read 2.1, and a rebuild cut its nodes per VT query 1.6x, while a cloth
 * pressed flat read 0.72 and a rebuild still cut them 1.5x (bench/results/trees.md). Rebuild
 * when it passes about 1.5, and every so many steps when the mesh changes shape a lot; a
 * rebuild costs about what the build at creation did (several refits). A tree whose root box
 * has no area (every element on one axis-parallel line, or at one point) costs 0: growth 1
 * while it stays so, infinity once it gains area. */
minkq_status minkq_scene_tree_growth(const minkq_scene* scene, double* out_growth);
size_t minkq_scene_vertex_count(const minkq_scene* scene);
size_t minkq_scene_triangle_count(const minkq_scene* scene);
size_t minkq_scene_edge_count(const minkq_scene* scene);
/* Copies the scene's edges (2 int32 each, host memory) into out_edges, which holds
 * 2 * capacity int32. CAPACITY if the scene has more edges than capacity. */
minkq_status minkq_scene_edges(const minkq_scene* scene, int32_t* out_edges, size_t capacity);

/* ---- Queries ------------------------------------------------------------------------------- */
typedef enum minkq_query_kind {
  MINKQ_QUERY_VT = 0, /* pairs (vertex, triangle): vertex within r of triangle */
  MINKQ_QUERY_EE = 1  /* pairs (e, f), e < f: edge e within r of edge f */
} minkq_query_kind;

/* The node test, from fast to tight. Points are zero-length capsules: for VT, capsule_ray is
 * the box test and capsule_exact the sphere test. EE keeps a pair {e, f} when the test passes
 * both ways (e's shape against f's box and f's shape against e's box), so the set does not
 * depend on which edge queried. */
typedef enum minkq_mode {
  MINKQ_MODE_BOX = 0,           /* r-padded box of the query element against node boxes */
  MINKQ_MODE_SPHERE = 1,        /* point-box distance (point queries only: VT, spheres) */
  MINKQ_MODE_CAPSULE_RAY = 2,   /* segment against the r-inflated box (slab test) */
  MINKQ_MODE_CAPSULE_EXACT = 3  /* segment-box distance */
} minkq_mode;

typedef enum minkq_query_flags {
  MINKQ_QUERY_LEAF_EXACT = 1, /* primitive distance test at the leaves: candidates == contacts.
                                 Fastest with MINKQ_MODE_BOX: the finer node tests cost more
                                 than they save once the leaves test distances */
  MINKQ_QUERY_CANONICAL = 2,  /* pairs sorted lexicographically */
  MINKQ_QUERY_DIGEST = 4,     /* compute xxHash64 (seed 0) of the canonical pairs; implies CANONICAL */
  MINKQ_QUERY_STATS = 8       /* count the traversal's work into info->stats (a separately compiled
                                 traversal; the uncounted one carries no counters) */
} minkq_query_flags;

typedef struct minkq_query_desc {
  minkq_query_kind kind;
  minkq_mode mode;
  uint32_t flags; /* minkq_query_flags */
  float radius;   /* r >= 0, finite */
} minkq_query_desc;

/* The work of one query call, with MINKQ_QUERY_STATS. The counts depend only on the tree and
 * the queries, so CPU and CUDA report the same numbers for the same scene. */
typedef struct minkq_query_stats {
  uint64_t nodes_visited;   /* internal node records read */
  uint64_t node_tests;      /* child boxes tested against a query shape */
  uint64_t primitive_tests; /* primitives whose box passed, handed to the leaf filter */
  uint64_t candidates;      /* pairs emitted: equal to count */
} minkq_query_stats;

typedef struct minkq_query_info {
  uint64_t count;          /* exact number of pairs (also when the buffer was too small) */
  uint64_t digest;         /* with MINKQ_QUERY_DIGEST: XXH64 of the little-endian int32 pairs */
  minkq_query_stats stats; /* with MINKQ_QUERY_STATS (also when the buffer was too small); else 0 */
} minkq_query_info;

/* Runs a query and writes pairs (2 int32 each) into out_pairs, which holds 2 * capacity int32
 * in out_memory (device memory on CUDA devices only). If more pairs exist than fit, returns
 * CAPACITY with info->count the exact number needed and writes nothing past the buffer.
 * Leaf-exact pairs lie within r + 2^-19 * S, S the size of the two elements and the distance
 * between them (see core/include/minkq/predicates.h). */
minkq_status minkq_scene_query(minkq_scene* scene, const minkq_query_desc* query, int32_t* out_pairs,
                               size_t capacity, minkq_memory out_memory, minkq_query_info* info);

/* A VT query and an EE query of one scene (created with both) in one pass: one parallel loop on
 * the CPU, one kernel launch and one count readback on CUDA, where two minkq_scene_query calls
 * take two of each. vt_query->kind must be MINKQ_QUERY_VT and ee_query->kind MINKQ_QUERY_EE;
 * modes, flags and radii are each query's own. Each query's pairs, count, digest and stats are
 * exactly those minkq_scene_query gives it alone. Buffers as minkq_scene_query, both in
 * out_memory: a query whose pairs fit is written in full; if either does not fit, returns
 * CAPACITY (the message names VT or EE) with both infos' counts exact. */
minkq_status minkq_scene_query_vt_ee(minkq_scene* scene, const minkq_query_desc* vt_query,
                                     const minkq_query_desc* ee_query, int32_t* vt_pairs, size_t vt_capacity,
                                     int32_t* ee_pairs, size_t ee_capacity, minkq_memory out_memory,
                                     minkq_query_info* vt_info, minkq_query_info* ee_info);

/* ---- Results: library-owned, growing pair buffers ------------------------------------------ */
typedef struct minkq_result minkq_result;

minkq_status minkq_result_create(minkq_result** out_result);
void minkq_result_release(minkq_result* result);
/* Like minkq_scene_query, into a result that grows as needed (host memory). */
minkq_status minkq_scene_query_result(minkq_scene* scene, const minkq_query_desc* query, minkq_result* result);
/* Like minkq_scene_query_vt_ee, into two distinct results that grow as needed (host memory). */
minkq_status minkq_scene_query_vt_ee_result(minkq_scene* scene, const minkq_query_desc* vt_query,
                                            const minkq_query_desc* ee_query, minkq_result* vt_result,
                                            minkq_result* ee_result);
uint64_t minkq_result_count(const minkq_result* result);
/* 2 * count int32, valid until the result is reused or released. */
const int32_t* minkq_result_pairs(const minkq_result* result);
uint64_t minkq_result_digest(const minkq_result* result);
/* The work counts of the last query, with MINKQ_QUERY_STATS (else all 0). */
minkq_query_stats minkq_result_stats(const minkq_result* result);

/* ---- BVH over user boxes ------------------------------------------------------------------- */
typedef struct minkq_bvh minkq_bvh;

/* Builds a BVH over boxes: 6 floats each (lo x, y, z, hi x, y, z), lo <= hi. Errors: NON_FINITE,
 * INVALID_ARGUMENT ("box 3 has lo > hi"), SIZE_OVERFLOW. Release with minkq_bvh_release. */
minkq_status minkq_bvh_create(minkq_device* device, minkq_buffer boxes, minkq_bvh** out_bvh);
void minkq_bvh_release(minkq_bvh* bvh);
/* New boxes (same count); refits in place (the tree keeps the grouping of its last build). */
minkq_status minkq_bvh_refit(minkq_bvh* bvh, minkq_buffer boxes);
/* New boxes (same count); builds the tree afresh, as minkq_bvh_create would. On error the bvh
 * keeps its boxes and tree. */
minkq_status minkq_bvh_rebuild(minkq_bvh* bvh, minkq_buffer boxes);
/* minkq_scene_tree_growth for a bvh. */
minkq_status minkq_bvh_tree_growth(const minkq_bvh* bvh, double* out_growth);

typedef enum minkq_shape {
  MINKQ_SHAPE_SPHERE = 0,  /* first: centres (3 floats); modes box, sphere */
  MINKQ_SHAPE_CAPSULE = 1, /* first, second: segment ends; modes box, capsule_ray, capsule_exact */
  MINKQ_SHAPE_BOX = 2      /* first, second: two opposite corners (any order); mode box; radius 0 */
} minkq_shape;

typedef struct minkq_bvh_query_desc {
  minkq_shape shape;
  minkq_mode mode;
  uint32_t flags;     /* CANONICAL, DIGEST, STATS (LEAF_EXACT does not apply to boxes) */
  float radius;       /* the same r for every query */
  minkq_buffer first;
  minkq_buffer second; /* count 0 for spheres */
} minkq_bvh_query_desc;

/* Pairs (query, box) for every query shape overlapping a box; buffers as minkq_scene_query. */
minkq_status minkq_bvh_query(minkq_bvh* bvh, const minkq_bvh_query_desc* query, int32_t* out_pairs,
                             size_t capacity, minkq_memory out_memory, minkq_query_info* info);

#ifdef __cplusplus
}
#endif

#endif /* MINKQ_H */
