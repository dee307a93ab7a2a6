/*
 * minkq: which pairs of mesh elements may lie within distance r of each other?
 *
 * A stable C99 ABI over the C++/CUDA core. Objects are opaque handles created and released by
 * the library; scenes and bvhs belong to a device. Functions that can fail return a
 * minkq_status; on failure minkq_last_error_message() holds a message naming the offending
 * argument or element. Arrays are passed as minkq_buffer: pointer, byte stride, element count
 * and memory kind (host or device). A call that rejects its arguments changes nothing.
 *
 * Guarantee: every pair of elements within r is reported (zero false negatives), in every
 * mode, for every finite input; finer modes report subsets of coarser ones:
 *   true contacts <= capsule_exact <= capsule_ray <= box   (EE)
 *   true contacts <= sphere <= box                         (VT)
 * and MINKQ_QUERY_LEAF_EXACT keeps, of any mode's pairs, the true contacts (plus at most pairs
 * within the leaf test's slack, stated at minkq_scene_query). For a MINKQ_SCENE_FLOAT64 scene
 * the guarantee is in double: every pair whose distance in the double input is within r.
 *
 * Thread safety: different objects may be used from different threads at once. One object
 * (device, scene, bvh, result) must not be used by two threads at the same time; a device
 * may be shared by scenes used from different threads. On CUDA, creating and rebuilding
 * scenes and bvhs frees temporary device memory, which waits for all work on the GPU: such
 * calls are safe from several threads but do not overlap other threads' GPU work. Each call
 * selects its device for its duration and gives the calling thread's current device back.
 * While a thread captures a CUDA graph in cudaStreamCaptureModeGlobal, a blocking minkq call
 * on another thread (it may allocate, free and synchronise) invalidates that capture: capture
 * in cudaStreamCaptureModeThreadLocal, or make no blocking calls until the capture ends.
 *
 * Memory: the library copies what it keeps (vertices, topology, boxes); a caller's arrays are
 * read during the call only. On CUDA, device arrays are read and written in place on the
 * calling thread's per-thread default stream, which each call synchronises before returning.
 * A buffer marked MINKQ_MEMORY_DEVICE is checked to be memory the device can use (its own
 * device memory, managed memory, mapped pinned memory, or any host memory where the device
 * reads pageable memory); anything else is MINKQ_ERROR_INVALID_ARGUMENT, naming the buffer,
 * before a kernel could fault on it. Host memory that passes (mapped pinned, or pageable on such
 * a device) is accepted and read as it is: the results are those of the same data in device or
 * host memory. Debugging: with the environment variable MINKQ_CUDA_SYNC
 * set (not "0"), every kernel launch waits for its kernel, so a fault is reported, with the
 * kernel's name, by the call that launched it.
 *
 * No measured figures here: what the modes, flags and rebuild advice cost and save on the
 * benchmark scenes is in docs/design-notes.md and bench/results/ in the minkq repository.
 */
#ifndef MINKQ_H
#define MINKQ_H

#include <stddef.h>
#include <stdint.h>

/* MINKQ_API marks each function the library exports: it is built with every other symbol
 * hidden, and its linker version script lets out only minkq_* at version MINKQ_<ABI>. */
#if defined(__GNUC__) || defined(__clang__)
#define MINKQ_API __attribute__((visibility("default")))
#else
#define MINKQ_API
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* ---- Versions ------------------------------------------------------------------------------ */
#define MINKQ_VERSION_MAJOR 0
#define MINKQ_VERSION_MINOR 3
#define MINKQ_VERSION_PATCH 0
/* Bumped whenever a struct layout, enum value or function signature changes. */
#define MINKQ_ABI_VERSION 2

/* Returns the version of the library loaded at run time, MAJOR * 10000 + MINOR * 100 + PATCH.
 * Never fails; any thread. */
MINKQ_API uint32_t minkq_version(void);
/* Returns the ABI version of the library loaded at run time. A program compares it with
 * MINKQ_ABI_VERSION, the version it was compiled against, to detect a mismatched library.
 * Never fails; any thread. */
MINKQ_API uint32_t minkq_abi_version(void);

/* ---- Errors -------------------------------------------------------------------------------- */
typedef enum minkq_status {
  MINKQ_SUCCESS = 0,
  MINKQ_ERROR_INVALID_ARGUMENT = 1,   /* null pointer, bad enum, stride or flag combination */
  MINKQ_ERROR_NON_FINITE = 2,         /* NaN or infinity in a coordinate or radius */
  MINKQ_ERROR_INDEX_OUT_OF_RANGE = 3, /* negative or too large vertex index */
  MINKQ_ERROR_SIZE_OVERFLOW = 4,      /* count whose byte size overflows, or over its limit: 2^31 - 2
                                         query elements, 2^30 + 1 elements of a tree (vertices,
                                         triangles, edges, boxes: the tree links' encoding) */
  MINKQ_ERROR_CAPACITY = 5,           /* output buffer too small; the exact count is returned */
  MINKQ_ERROR_UNSUPPORTED = 6,        /* e.g. CUDA asked for where there is none */
  MINKQ_ERROR_OUT_OF_MEMORY = 7,
  MINKQ_ERROR_DEVICE = 8,             /* a CUDA runtime call failed */
  MINKQ_ERROR_INTERNAL = 9
} minkq_status;

/* Returns the message of the last failed call on the calling thread, naming the argument or
 * element at fault ("vertex 12 has a non-finite coordinate (nan, 0, 1)"); "" when that
 * thread's last status-returning call succeeded. Owned by the library, valid until the next
 * minkq call on this thread. Thread safety: each thread has its own message. */
MINKQ_API const char* minkq_last_error_message(void);
/* Returns a static name for a status ("MINKQ_ERROR_CAPACITY"), or "unknown minkq_status" for a
 * value outside the enum. Never fails; any thread. */
MINKQ_API const char* minkq_status_name(minkq_status status);

/* ---- Buffers ------------------------------------------------------------------------------- */
typedef enum minkq_memory {
  MINKQ_MEMORY_HOST = 0,  /* ordinary host memory */
  MINKQ_MEMORY_DEVICE = 1 /* memory the object's CUDA device reads (CUDA devices only; checked) */
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

/* Creates a device from a spec: "cpu" (all cores, through a thread pool), "cuda" (GPU 0),
 * "cuda:N" or "auto" (GPU 0 when minkq_cuda_device_count() > 0, else the CPU), and stores it
 * in *out_device (NULL on failure). Errors: INVALID_ARGUMENT (NULL argument, unknown or
 * malformed spec), UNSUPPORTED (CUDA asked for where minkq was built without it, or no such
 * GPU), DEVICE (a CUDA runtime call failed). Release with minkq_device_release. */
MINKQ_API minkq_status minkq_device_create(const char* spec, minkq_device** out_device);
/* Releases a device. Every scene and bvh created on it must be released first. NULL is
 * ignored. */
MINKQ_API void minkq_device_release(minkq_device* device);
/* Returns the device's backend (MINKQ_BACKEND_CPU for NULL). */
MINKQ_API minkq_backend minkq_device_backend(const minkq_device* device);
/* Returns a description such as "cpu (8 threads, avx2)" or "cuda:0 (NVIDIA H100 80GB HBM3)", owned
 * by the device and valid until it is released ("" for NULL). */
MINKQ_API const char* minkq_device_name(const minkq_device* device);
/* Returns the number of usable CUDA devices: 0 where minkq was built without CUDA or no GPU is
 * present. Never fails; any thread. */
MINKQ_API int minkq_cuda_device_count(void);

/* ---- Mesh scenes: VT and EE queries ------------------------------------------------------- */
typedef struct minkq_scene minkq_scene;

typedef enum minkq_scene_flags {
  MINKQ_SCENE_VT = 1,           /* build the triangle tree for vertex-triangle queries */
  MINKQ_SCENE_EE = 2,           /* build the edge tree for edge-edge queries */
  MINKQ_SCENE_DROP_INCIDENT = 4, /* drop (v, t) with v a vertex of t, and edges sharing a vertex */
  /* Vertices are 3 doubles (x, y, z) each, stride >= 24, at creation and in every refit and
   * rebuild (blocking and stream-ordered). The scene rounds them to nearest float, the
   * precision of its trees and tests, and keeps rho, the farthest the rounding moved a vertex;
   * its queries then run with radius r + 2 rho (rounded up), so that every pair within r in
   * double is reported, in every mode. Extras (pairs beyond r) therefore lie within r + 2 rho
   * plus the slack of float input; rho is at most sqrt(3)/2 ulp (float) of the largest
   * coordinate, and 0 for vertices that are floats already. A double beyond the float range
   * (about 3.4e38) is NON_FINITE, as a NaN or infinity is. */
  MINKQ_SCENE_FLOAT64 = 8,
  /* Codimensional elements (particles, rods, yarn): a vertex tree for vertex-vertex queries,
   * and the edge tree for edge-vertex queries. Such scenes may hold no triangles (count 0)
   * and take their edges from desc->edges. */
  MINKQ_SCENE_VV = 16,
  MINKQ_SCENE_EV = 32
} minkq_scene_flags;

typedef struct minkq_scene_desc {
  uint32_t flags;         /* minkq_scene_flags; at least one of VT, EE, VV and EV */
  minkq_buffer vertices;  /* 3 floats (x, y, z) each, stride >= 12; with MINKQ_SCENE_FLOAT64 3 doubles */
  minkq_buffer triangles; /* 3 int32 vertex indices each; stride >= 12 */
  /* 2 int32 vertex indices each, or count 0 to derive them from the triangles: every distinct
   * undirected triangle edge, numbered in lexicographic order of (min vertex, max vertex). */
  minkq_buffer edges;
} minkq_scene_desc;

/* Creates a scene on a device: copies the mesh (host or, on a CUDA device, device memory),
 * derives the edges when desc->edges is empty and the flags ask for EE or EV, builds the trees
 * the flags ask for (a VT-only scene builds no edge tree) and stores the scene in *out_scene
 * (NULL on failure). Errors: INVALID_ARGUMENT (NULL pointer, a NULL buffer with a non-zero count,
 * unknown flag bits, none of VT, EE, VV and EV, a stride under the element's size, device memory on a
 * CPU device), NON_FINITE ("vertex 12 has a non-finite coordinate (...)"), INDEX_OUT_OF_RANGE
 * ("triangle 3 references vertex 9 but the scene has 8 vertices"), SIZE_OVERFLOW (more than
 * 2^30 + 1 = 1073741825 vertices, triangles or edges, derived ones included: a tree's limit,
 * refused before the buffers are read), OUT_OF_MEMORY, DEVICE. The scene holds its device, which must outlive
 * it. Release with minkq_scene_release. */
MINKQ_API minkq_status minkq_scene_create(minkq_device* device, const minkq_scene_desc* desc, minkq_scene** out_scene);
/* Releases a scene and its trees. NULL is ignored. */
MINKQ_API void minkq_scene_release(minkq_scene* scene);
/* Moves the vertices (the scene's vertex count, any stride, host or device memory) and refits
 * the trees in place: cheaper than a rebuild, with the same pairs. A refit keeps the grouping of
 * the last build, so after large deformations its boxes overlap more and queries visit more
 * nodes (see minkq_scene_tree_growth). Errors: INVALID_ARGUMENT (NULL scene, another vertex
 * count, a bad buffer as at creation), NON_FINITE; the scene then keeps its positions. */
MINKQ_API minkq_status minkq_scene_refit(minkq_scene* scene, minkq_buffer vertices);
/* Moves the vertices like minkq_scene_refit and builds the trees afresh for the new positions:
 * the trees minkq_scene_create would build there, at about its cost; topology and edge
 * numbering are kept. Same errors as minkq_scene_refit; the scene then keeps its positions and
 * trees. */
MINKQ_API minkq_status minkq_scene_rebuild(minkq_scene* scene, minkq_buffer vertices);
/* Swept positions, for continuous collision detection (CCD): every vertex moves linearly from
 * x0 to x1 over the step (both buffers as for minkq_scene_refit: the scene's vertex count and
 * precision, host or device memory, finite). The scene keeps both, boxes each element over both
 * positions, and refits its trees to those boxes (minkq_scene_refit_swept) or builds them afresh
 * (minkq_scene_rebuild_swept). Its queries are then swept until the next minkq_scene_refit or
 * minkq_scene_rebuild: they report every pair whose two elements come within r at some time t
 * in [0, 1] (x(t) = x0 + t (x1 - x0) for each vertex), the candidates a CCD narrow phase then
 * decides. The modes, as node and primitive tests against the elements' swept boxes:
 *   VT  the vertex is its path, the segment x0 -> x1: box (the segment's box grown by r),
 *       capsule_ray and capsule_exact (the capsule of radius r around the path, as for
 *       segments), sphere = capsule_exact (the sphere swept along the path);
 *   EE  box (the edge's swept box grown by r); the segment modes are UNSUPPORTED.
 * MINKQ_QUERY_LEAF_EXACT is UNSUPPORTED (it would need the time of closest approach); the
 * scene's DROP_INCIDENT and the once-per-pair EE rule apply as for static queries. At x0 == x1
 * the pairs are exactly the static queries' (box and capsule_ray the static box mode's; VT
 * capsule_exact and sphere the static sphere mode's): a vertex that does not move is tested as
 * the point it is, whatever the others do.
 * Errors: those of minkq_scene_refit for either buffer (the message names the call); on error
 * the scene keeps its positions and trees. minkq_scene_is_swept returns 1 while the scene's
 * positions are swept ones, else 0 (also for NULL). */
MINKQ_API minkq_status minkq_scene_refit_swept(minkq_scene* scene, minkq_buffer x0, minkq_buffer x1);
MINKQ_API minkq_status minkq_scene_rebuild_swept(minkq_scene* scene, minkq_buffer x0, minkq_buffer x1);
MINKQ_API int minkq_scene_is_swept(const minkq_scene* scene);
/* Writes to *out_growth how far the refits since the last build have stretched the trees: their
 * area cost now over its value right after that build, for the larger of the scene's trees;
 * 1 after a build. The area cost (the surface areas of every node's child boxes, summed, over
 * the root box's) is scale-free and grows with the nodes a query visits. It sees boxes that
 * stretch, not a mesh that folds or flattens into new neighbours (where a rebuild can still
 * help). Rebuild when it passes about 1.5, and every so many steps when the mesh changes shape
 * a lot: that advice, and what rebuilds bought on the benchmark scenes, are measured in
 * docs/design-notes.md in the minkq repository. A tree whose root box has no area (every element on
 * one axis-parallel line, or at one point) costs 0: growth 1 while it stays so, infinity once
 * it gains area. Errors: INVALID_ARGUMENT (NULL scene or out_growth). */
MINKQ_API minkq_status minkq_scene_tree_growth(const minkq_scene* scene, double* out_growth);
/* Return the scene's vertex, triangle and edge counts (edges: the derived ones when the scene
 * derived them); 0 for NULL. */
MINKQ_API size_t minkq_scene_vertex_count(const minkq_scene* scene);
MINKQ_API size_t minkq_scene_triangle_count(const minkq_scene* scene);
MINKQ_API size_t minkq_scene_edge_count(const minkq_scene* scene);
/* Copies the scene's edges, in the numbering EE pairs use (2 int32 each, host memory), into
 * out_edges, which holds 2 * capacity int32. Errors: INVALID_ARGUMENT (NULL scene, NULL
 * out_edges with a non-zero capacity), CAPACITY when the scene has more edges than capacity
 * (nothing is written; minkq_scene_edge_count gives the number). */
MINKQ_API minkq_status minkq_scene_edges(const minkq_scene* scene, int32_t* out_edges, size_t capacity);

/* ---- Scenes of many geometries --------------------------------------------------------------
 *
 * A scene may hold any number of geometries: triangle meshes, edge sets (rods) and vertex sets
 * (particles), each with its own vertices, topology, pair kinds, thickness, world, collision
 * group and mask, and each moving or static. Each geometry has its own trees: a static one is
 * built once and never touched again, and a step refits or rebuilds only what moves. A query
 * (minkq_scene_query and every call that takes a scene) then reports, for its kind:
 *   - self pairs within geometry g, when g has MINKQ_GEOMETRY_SELF (its incident pairs dropped
 *     with MINKQ_GEOMETRY_DROP_INCIDENT), as a scene of g alone would;
 *   - cross pairs between geometries a != b when both take part in the kind, they share a world
 *     (equal world ids, or either is -1: part of every world) and each one's group has a bit in
 *     the other's mask ((a.group & b.mask) && (b.group & a.mask), as PhysX and Embree filter).
 *     VT and EV pairs run both ways (a's vertices against b's triangles or edges, and b's
 *     against a's); EE and VV pairs are unordered. No pair ever joins two worlds, and geometries
 *     of different worlds are never tested against each other.
 * Numbering: pairs use one global numbering, that of the geometries concatenated in the order
 * given: geometry g's vertices, triangles and edges come after those of geometries 0..g-1
 * (minkq_scene_geometry_range gives each geometry's first id and count), and a geometry's edges
 * are numbered as a one-mesh scene numbers them. EE and VV pairs are (lower, higher) global id.
 * minkq_scene_vertex_count, _triangle_count, _edge_count and minkq_scene_edges give the whole
 * scene in that numbering (edges by global vertex ids).
 * Thickness: a geometry may give a thickness t >= 0 per vertex; an element's is the largest of
 * its vertices' (0 without). A pair of elements a, b is then within reach when its distance is
 * <= r + t(a) + t(b): every mode reports every such pair, LEAF_EXACT keeps exactly those (with
 * the slack stated at minkq_scene_query, relative to r + t(a) + t(b)), a float64 geometry keeps
 * the guarantee in double and swept queries use the same reach. The finer node tests (sphere,
 * capsules) test a query's shape against the boxes grown by thickness, so with thickness they
 * keep more pairs beyond reach than without; LEAF_EXACT drops those.
 * All of a query's self and cross jobs run in one pass (one parallel loop, one kernel launch);
 * minkq_scene_query_vt_ee runs its VT and its EE query one after the other on such a scene.
 * A one-mesh scene (minkq_scene_create) is the scene of one moving geometry with MINKQ_GEOMETRY_SELF
 * and its flags' kinds, DROP_INCIDENT and FLOAT64. */
typedef enum minkq_geometry_flags {
  MINKQ_GEOMETRY_SELF = 1,          /* report pairs of elements within this geometry */
  MINKQ_GEOMETRY_DROP_INCIDENT = 2, /* self pairs drop incident ones (MINKQ_SCENE_DROP_INCIDENT) */
  MINKQ_GEOMETRY_FLOAT64 = 4,       /* vertices are 3 doubles each (MINKQ_SCENE_FLOAT64), here and in its refits */
  MINKQ_GEOMETRY_STATIC = 8         /* never moves: built once; refits and rebuilds skip it or refuse it */
} minkq_geometry_flags;

/* One geometry of a scene. Later versions add fields at the end only: struct_size says which
 * ones the caller knows (fields past it take the defaults of minkq_geometry_desc_init), so a
 * program compiled against this header keeps working with later libraries. */
typedef struct minkq_geometry_desc {
  uint32_t struct_size; /* sizeof(minkq_geometry_desc) as the caller compiled it */
  uint32_t kinds;       /* the pairs it takes part in: MINKQ_SCENE_VT | _EE | _VV | _EV, at least one */
  uint32_t flags;       /* minkq_geometry_flags */
  int32_t world;        /* its world, >= 0, or -1: part of every world */
  uint32_t group;       /* collision group bits: a cross pair needs (a.group & b.mask) && (b.group & a.mask) */
  uint32_t mask;
  minkq_buffer vertices;  /* 3 floats each (3 doubles with MINKQ_GEOMETRY_FLOAT64); at least one */
  minkq_buffer triangles; /* 3 int32 indices into this geometry's vertices; count 0 for none */
  minkq_buffer edges;     /* 2 int32 indices, or count 0 to derive them from the triangles (EE, EV) */
  minkq_buffer thickness; /* count 0 for none, or one float per vertex, finite and >= 0 */
} minkq_geometry_desc;

/* Fills *desc with the defaults: struct_size = sizeof(minkq_geometry_desc), kinds VT | EE,
 * flags SELF | DROP_INCIDENT, world 0, group 1, mask all bits, empty buffers in host memory.
 * NULL is ignored. */
MINKQ_API void minkq_geometry_desc_init(minkq_geometry_desc* desc);

/* Creates a scene of `count` geometries (count >= 1), descriptions geometries[0..count-1] each
 * geometries[0].struct_size bytes apart (all with that struct_size), and stores it in *out_scene
 * (NULL on failure). Each geometry is checked and built as minkq_scene_create checks and builds a
 * mesh (edges derived when it gives none and takes part in EE or EV); messages name the geometry
 * ("geometry 2: triangle 3 references vertex 9 but the geometry has 8 vertices"). The scene's
 * kinds (the query kinds it answers) are the union of its geometries'. Errors: those of
 * minkq_scene_create; INVALID_ARGUMENT also for count 0, a struct_size under that of this
 * header's first version or differing between descriptions, unknown flag or kind bits, a
 * negative world other than -1, a thickness count other than the vertex count; NON_FINITE or
 * INVALID_ARGUMENT for a non-finite or negative thickness; SIZE_OVERFLOW for more than 2^31 - 2
 * vertices, triangles or edges in all (the global ids are int32). */
MINKQ_API minkq_status minkq_scene_create_geometries(minkq_device* device, const minkq_geometry_desc* geometries,
                                                     size_t count, minkq_scene** out_scene);
/* Returns the number of geometries of a scene (1 for a one-mesh scene, 0 for NULL). */
MINKQ_API uint32_t minkq_scene_geometry_count(const minkq_scene* scene);

typedef enum minkq_element {
  MINKQ_ELEMENT_VERTEX = 0,
  MINKQ_ELEMENT_TRIANGLE = 1,
  MINKQ_ELEMENT_EDGE = 2
} minkq_element;
/* Writes geometry g's first global id and its count of `element`s (edges: the derived ones when
 * it derived them). Errors: INVALID_ARGUMENT (NULL scene or output, g out of range, not a
 * minkq_element value). */
MINKQ_API minkq_status minkq_scene_geometry_range(const minkq_scene* scene, uint32_t geometry, minkq_element element,
                                                  size_t* out_first, size_t* out_count);

/* Moves one geometry's vertices (its vertex count and precision) and refits its trees
 * (minkq_scene_geometry_refit) or builds them afresh (minkq_scene_geometry_rebuild); the swept
 * forms take its positions at both ends of the step, as minkq_scene_refit_swept does for a
 * scene. The other geometries are not touched. minkq_scene_refit, _rebuild and their swept forms
 * move every geometry that is not static at once: their buffers hold those geometries'
 * vertices one after another, in geometry order, all of one precision. A geometry's swept
 * positions last until its next plain refit or rebuild; while any geometry is swept the scene's
 * queries are swept (minkq_scene_is_swept returns 1) under the rules of minkq_scene_refit_swept.
 * Errors: those of minkq_scene_refit, messages naming the geometry; INVALID_ARGUMENT for a static
 * geometry, g out of range, or (whole-scene calls) moving geometries of mixed precision; the
 * scene then keeps its positions and trees. */
MINKQ_API minkq_status minkq_scene_geometry_refit(minkq_scene* scene, uint32_t geometry, minkq_buffer vertices);
MINKQ_API minkq_status minkq_scene_geometry_rebuild(minkq_scene* scene, uint32_t geometry, minkq_buffer vertices);
MINKQ_API minkq_status minkq_scene_geometry_refit_swept(minkq_scene* scene, uint32_t geometry, minkq_buffer x0,
                                                        minkq_buffer x1);
MINKQ_API minkq_status minkq_scene_geometry_rebuild_swept(minkq_scene* scene, uint32_t geometry, minkq_buffer x0,
                                                          minkq_buffer x1);

/* ---- Queries ------------------------------------------------------------------------------- */
typedef enum minkq_query_kind {
  MINKQ_QUERY_VT = 0, /* pairs (vertex, triangle): vertex within r of triangle */
  MINKQ_QUERY_EE = 1, /* pairs (e, f), e < f: edge e within r of edge f */
  MINKQ_QUERY_VV = 2, /* pairs (v, w), v < w: vertex v within r of vertex w (MINKQ_SCENE_VV) */
  MINKQ_QUERY_EV = 3  /* pairs (vertex, edge): vertex within r of edge (MINKQ_SCENE_EV); with
                         DROP_INCIDENT, without the vertex's own edges */
} minkq_query_kind;

/* The node test, from fast to tight. Points are zero-length capsules: for VT, VV and EV,
 * capsule_ray is the box test and capsule_exact the sphere test. EE and VV keep a pair {a, b}
 * when the test passes both ways (a's shape against b's box and b's shape against a's box),
 * so the set does not depend on which element queried. */
typedef enum minkq_mode {
  MINKQ_MODE_BOX = 0,           /* r-padded box of the query element against node boxes */
  MINKQ_MODE_SPHERE = 1,        /* point-box distance (point queries only: VT, VV, EV, spheres) */
  MINKQ_MODE_CAPSULE_RAY = 2,   /* segment against the r-inflated box (slab test) */
  MINKQ_MODE_CAPSULE_EXACT = 3  /* segment-box distance */
} minkq_mode;

typedef enum minkq_query_flags {
  MINKQ_QUERY_LEAF_EXACT = 1, /* primitive distance test at the leaves: candidates == contacts.
                                 Meant for MINKQ_MODE_BOX: once the leaves test distances, the
                                 finer node tests cost more than they save (measured in
                                 docs/design-notes.md in the minkq repository) */
  MINKQ_QUERY_CANONICAL = 2,  /* pairs sorted lexicographically */
  MINKQ_QUERY_DIGEST = 4,     /* compute xxHash64 (seed 0) of the canonical pairs; implies CANONICAL */
  MINKQ_QUERY_STATS = 8,      /* count the traversal's work into info->stats (a separately compiled
                                 traversal; the uncounted one carries no counters) */
  MINKQ_QUERY_COUNT = 16      /* count the pairs only: info->count (async: *out_count) gets the
                                 exact number, no pair is written or kept, out_pairs may be NULL
                                 and capacity is ignored; never CAPACITY. For callers that size
                                 their buffers first; cheaper than a query that stores the
                                 pairs. Not with CANONICAL or DIGEST */
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

/* Runs a VT, EE, VV or EV query on a scene and writes its pairs (2 int32 each: (vertex,
 * triangle) for VT, (e, f) with e < f for EE, (v, w) with v < w for VV, (vertex, edge) for EV)
 * into out_pairs, which holds 2 * capacity int32 in out_memory
 * (device memory on CUDA devices only); CANONICAL sorts them, else their order is unspecified.
 * *info is zeroed, then gets the exact count, and the digest and stats its flags ask for. If
 * more pairs exist than fit, returns CAPACITY with info->count the exact number needed and
 * writes nothing past the buffer: grow it and call again. Leaf-exact pairs lie within
 * r + 2^-19 * S, S the operands' size: the largest distance between the query element's first
 * point and the other element's points (EE: or the edge's length); the leaf test computes
 * distances in double to within 2^-21 * S and accepts those up to r + 2^-20 * S. On a
 * MINKQ_SCENE_FLOAT64 scene r is first grown by 2 rho (minkq_scene_flags). On a scene of several
 * geometries the pairs are those and in the numbering its section states, with thickness added to
 * r pair by pair.
 * Errors: INVALID_ARGUMENT (NULL scene, query or info;
 * unknown kind, mode or flag bits; a kind the scene was created without; sphere mode for EE;
 * a negative radius; a NULL out_pairs with a non-zero capacity; device memory on a CPU
 * device; COUNT with CANONICAL or DIGEST), NON_FINITE (radius), SIZE_OVERFLOW (capacity),
 * CAPACITY, OUT_OF_MEMORY, DEVICE. With MINKQ_QUERY_COUNT only info is written. */
MINKQ_API minkq_status minkq_scene_query(minkq_scene* scene, const minkq_query_desc* query, int32_t* out_pairs,
                                         size_t capacity, minkq_memory out_memory, minkq_query_info* info);

/* A VT query and an EE query of one scene (created with both) in one pass: one parallel loop on
 * the CPU, one kernel launch and one count readback on CUDA, where two minkq_scene_query calls
 * take two of each (what that saves is measured in docs/design-notes.md in the minkq repository).
 * vt_query->kind must be MINKQ_QUERY_VT and ee_query->kind MINKQ_QUERY_EE; modes, flags and radii
 * are each query's own. Each query's pairs, count, digest and stats are exactly those
 * minkq_scene_query gives it alone. Buffers as minkq_scene_query, both in out_memory: a query
 * whose pairs fit is written in full; if either does not fit, returns CAPACITY (the message names
 * VT or EE) with both infos' counts exact. Errors: those of minkq_scene_query for either query,
 * and INVALID_ARGUMENT when a kind is the wrong one or vt_info and ee_info are the same struct. */
MINKQ_API minkq_status minkq_scene_query_vt_ee(minkq_scene* scene, const minkq_query_desc* vt_query,
                                               const minkq_query_desc* ee_query, int32_t* vt_pairs, size_t vt_capacity,
                                               int32_t* ee_pairs, size_t ee_capacity, minkq_memory out_memory,
                                               minkq_query_info* vt_info, minkq_query_info* ee_info);

/* ---- Stream-ordered calls: minkq_async.h --------------------------------------------------
 * minkq_scene_reserve and the *_async calls, which enqueue a scene's work on a stream (CUDA
 * graph capture), in a header of their own. */
#include "minkq_async.h"

/* ---- Results: library-owned, growing pair buffers ------------------------------------------ */
typedef struct minkq_result minkq_result;

/* Creates an empty result: a host pair buffer that the library owns and grows as queries need,
 * usable with any scene, and stores it in *out_result. Reusing one result every step keeps its
 * memory. Errors: INVALID_ARGUMENT (NULL out_result), OUT_OF_MEMORY. Release with
 * minkq_result_release. */
MINKQ_API minkq_status minkq_result_create(minkq_result** out_result);
/* Releases a result and its pairs. NULL is ignored. */
MINKQ_API void minkq_result_release(minkq_result* result);
/* Like minkq_scene_query, into a result (host memory): when its buffer is too small it grows to
 * the exact count and an eighth more, and the query runs again, so the call does not return
 * CAPACITY. A count that grows by less than that from one call to the next (a moving mesh's
 * contacts, step to step) fits: the buffer stays where it is and the query runs once. On failure
 * the result holds no pairs. Errors: those of minkq_scene_query, INVALID_ARGUMENT for a NULL
 * result, OUT_OF_MEMORY when it cannot grow. */
MINKQ_API minkq_status minkq_scene_query_result(minkq_scene* scene, const minkq_query_desc* query,
                                              minkq_result* result);
/* Like minkq_scene_query_vt_ee, into two distinct results that grow as needed (host memory), as
 * minkq_scene_query_result does. INVALID_ARGUMENT for a NULL or shared result. */
MINKQ_API minkq_status minkq_scene_query_vt_ee_result(minkq_scene* scene, const minkq_query_desc* vt_query,
                                                      const minkq_query_desc* ee_query, minkq_result* vt_result,
                                                      minkq_result* ee_result);
/* Returns the number of pairs of the result's last query (0 after a failed one, or for NULL). */
MINKQ_API uint64_t minkq_result_count(const minkq_result* result);
/* Returns the result's pairs, 2 * count int32, valid until the result is reused or released
 * (may be NULL when count is 0; NULL after a MINKQ_QUERY_COUNT query, which keeps no pairs). */
MINKQ_API const int32_t* minkq_result_pairs(const minkq_result* result);
/* Returns the last query's digest, with MINKQ_QUERY_DIGEST (else 0). */
MINKQ_API uint64_t minkq_result_digest(const minkq_result* result);
/* Returns the work counts of the last query, with MINKQ_QUERY_STATS (else all 0). */
MINKQ_API minkq_query_stats minkq_result_stats(const minkq_result* result);

/* ---- BVH over user boxes ------------------------------------------------------------------- */
typedef struct minkq_bvh minkq_bvh;

/* Creates a BVH on a device over boxes, 6 floats each (lo x, y, z, hi x, y, z) with lo <= hi on
 * every axis, in host or (on a CUDA device) device memory; copies them, builds the tree and
 * stores the bvh in *out_bvh (NULL on failure). Errors: INVALID_ARGUMENT (NULL pointer, a bad
 * buffer as for scenes, "box 3 has lo > hi"), NON_FINITE, SIZE_OVERFLOW (more than 2^30 + 1
 * boxes, a tree's limit), OUT_OF_MEMORY, DEVICE. The bvh holds its device, which must outlive it. Release with minkq_bvh_release. */
MINKQ_API minkq_status minkq_bvh_create(minkq_device* device, minkq_buffer boxes, minkq_bvh** out_bvh);
/* Releases a bvh and its tree. NULL is ignored. */
MINKQ_API void minkq_bvh_release(minkq_bvh* bvh);
/* Moves the boxes (the bvh's count, checked as at creation) and refits the tree in place, keeping
 * the grouping of its last build. Errors: those of minkq_bvh_create, INVALID_ARGUMENT for NULL
 * or another box count; the bvh then keeps its boxes. */
MINKQ_API minkq_status minkq_bvh_refit(minkq_bvh* bvh, minkq_buffer boxes);
/* Moves the boxes like minkq_bvh_refit and builds the tree afresh, as minkq_bvh_create would.
 * Same errors; the bvh then keeps its boxes and tree. */
MINKQ_API minkq_status minkq_bvh_rebuild(minkq_bvh* bvh, minkq_buffer boxes);
/* minkq_scene_tree_growth for a bvh: its tree's area cost over its value at the last build.
 * Errors: INVALID_ARGUMENT (NULL bvh or out_growth). */
MINKQ_API minkq_status minkq_bvh_tree_growth(const minkq_bvh* bvh, double* out_growth);

typedef enum minkq_shape {
  MINKQ_SHAPE_SPHERE = 0,  /* first: centres (3 floats); modes box, sphere */
  MINKQ_SHAPE_CAPSULE = 1, /* first, second: segment ends; modes box, capsule_ray, capsule_exact */
  MINKQ_SHAPE_BOX = 2      /* first, second: two opposite corners (any order); mode box; radius 0 */
} minkq_shape;

typedef struct minkq_bvh_query_desc {
  minkq_shape shape;
  minkq_mode mode;
  uint32_t flags;     /* CANONICAL, DIGEST, STATS, COUNT (LEAF_EXACT does not apply to boxes) */
  float radius;       /* the same r for every query */
  minkq_buffer first;
  minkq_buffer second; /* count 0 for spheres */
} minkq_bvh_query_desc;

/* Runs one query per shape of query->first (and ->second) against a bvh and writes the pairs
 * (query index, box index) of every query shape within radius of a box (box queries: every
 * query box overlapping a box) into out_pairs; buffers, info and CAPACITY as
 * minkq_scene_query. Errors: INVALID_ARGUMENT (NULL bvh, query or info; unknown shape, mode
 * or flag bits; LEAF_EXACT; sphere mode for capsules; a mode other than box, or a radius
 * other than 0, for boxes; second not empty for spheres, or not first's count otherwise;
 * a bad buffer), NON_FINITE (radius, a query point), SIZE_OVERFLOW, CAPACITY, OUT_OF_MEMORY,
 * DEVICE. */
MINKQ_API minkq_status minkq_bvh_query(minkq_bvh* bvh, const minkq_bvh_query_desc* query, int32_t* out_pairs,
                                       size_t capacity, minkq_memory out_memory, minkq_query_info* info);

#ifdef __cplusplus
}
#endif

#endif /* MINKQ_H */
