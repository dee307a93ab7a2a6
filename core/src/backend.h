// Internal interface between the C API front end (capi/: validation, topology,
// digests) and a backend (cpu/, cuda/) that owns the arrays and runs build, refit and queries.
// Both backends serve it with the same two stores (store.h) over their own executor.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "minkq/query_sources.h"
#include "minkq/traversal.h"

namespace minkq {

// Numbered as the C API's minkq_status.
enum class Status : int {
  kSuccess = 0,
  kInvalidArgument = 1,
  kNonFinite = 2,
  kIndexOutOfRange = 3,
  kSizeOverflow = 4,
  kCapacity = 5,
  kUnsupported = 6,
  kOutOfMemory = 7,
  kDevice = 8,
  kInternal = 9,
};

struct Failure : std::runtime_error {
  Status status;
  Failure(Status s, const std::string& message) : std::runtime_error(message), status(s) {}
};
[[noreturn]] inline void fail(Status status, const std::string& message) { throw Failure(status, message); }

enum class Memory : int { kHost = 0, kDevice = 1 };
// The scalar type of a record's coordinates: float, or (vertices only) double, rounded to
// nearest float on the way in (minkq/float64.h).
enum class Scalar : int { kFloat32 = 0, kFloat64 = 1 };

// `count` records, each starting `stride` bytes after the previous one.
struct Strided {
  const void* data;
  size_t stride;
  int64_t count;
  Memory memory;
  Scalar scalar = Scalar::kFloat32;
};

enum class QueryKind : int {
  kVertexTriangle, kEdgeEdge, kUserSpheres, kUserCapsules, kUserBoxes, kVertexVertex, kVertexEdge
};
constexpr int kQueryKinds = 7;

// The trees a mesh store builds (from the scene's flags) and whether it keeps the vertices'
// Morton order, the query order of VT and EV.
struct MeshTrees {
  bool triangles = false, edges = false, vertices = false;
  bool vertex_order = false;
};

// The bit of a query kind in a geometry's kinds.
constexpr uint32_t kind_bit(QueryKind kind) { return 1u << int(kind); }

// How a geometry of a mesh store takes part in queries (the C API's minkq_geometry_desc).
struct GeometryRole {
  uint32_t kinds = 0;  // kind_bit of each kind it takes part in
  bool self = true;    // pairs within it are reported
  bool drop_incident = false;
  bool is_static = false;  // never moved: built once
  int32_t world = 0;       // -1: every world
  uint32_t group = 1, mask = ~0u;
};

// One geometry of a mesh store, checked by the caller: its vertices, topology (edges derived
// already), thickness per vertex (or none), the trees its kinds need, and its role.
struct GeometryInput {
  Strided vertices;
  std::vector<Triangle> triangles;
  std::vector<Edge> edges;
  std::vector<float> thickness;  // one per vertex, finite and >= 0, or empty
  MeshTrees trees;
  GeometryRole role;
};

struct QueryRequest {
  QueryKind kind;
  Mode mode;
  uint32_t filters;  // kDropIncident | kLeafExact
  float r;
  Strided first;   // user queries: sphere centres, capsule starts or box lows (float3)
  Strided second;  // user queries: capsule ends or box highs (float3)
};

// The stream of an asynchronous call (a cudaStream_t on CUDA; unused on the CPU).
using Stream = void*;

struct PairOutput {
  int32_t* pairs;  // 2 * capacity int32
  size_t capacity;
  Memory memory;
  bool canonical;  // lexicographic order
  // Asynchronous queries: the exact count goes here (executor memory), pairs are written up to
  // the capacity, and nothing is read back. Null for blocking queries.
  uint64_t* count = nullptr;
};

// What a scene has reserved for its asynchronous calls (minkq_scene_reserve).
struct Reservation {
  bool refit = false;    // a staging copy of the vertices and the pending error
  bool rebuild = false;  // the tree builds' scratch, kept
  bool swept = false;    // the end positions of swept steps and their staging copy
  size_t canonical_capacity = 0;  // pairs the canonical sort's scratch holds
};

// The first data error of the asynchronous refits and rebuilds since it was last taken.
struct PendingError {
  enum Call : int { kNone = 0, kRefit = 1, kRebuild = 2, kRefitSwept = 3, kRebuildSwept = 4 };
  Call call = kNone;
  int64_t vertex = -1;  // the first vertex with a non-finite coordinate in that call
};

// One query of a call: what to run, where its pairs go, and where its work is counted (or null).
struct QueryJob {
  QueryRequest request;
  PairOutput out;
  WorkCounts* work;
};

// One scene's arrays and trees on a backend.
class Store {
 public:
  virtual ~Store() = default;
  // New positions for the same vertices (mesh stores) or boxes (box stores); refits the trees.
  virtual void refit(const Strided& values) = 0;
  // The same, building the trees afresh (as at creation).
  virtual void rebuild(const Strided& values) = 0;
  // The largest of the trees' area costs now over their values at the last build (growth()).
  virtual double tree_growth() = 0;
  // Runs a query; returns the exact pair count and writes the pairs only if they all fit.
  // With `work`, also counts the traversal's work into it (a separately compiled traversal:
  // the uncounted one carries no counters).
  virtual uint64_t query(const QueryRequest& request, const PairOutput& out, WorkCounts* work) = 0;
};

// A mesh scene's store: one or more geometries (GeometryInput), each with its own trees, and the
// pairs within and between them (the C API's minkq_geometry_desc rules) in one global numbering:
// the geometries' vertices, triangles and edges one after another, in order. It holds the scene's
// only copy of the topology (the C API keeps none): triangles where a geometry has a triangle
// tree, edges always (minkq_scene_edges). refit, rebuild and their swept forms move every
// geometry that is not static, their buffers holding those geometries' vertices one after
// another; move_geometry moves one. The asynchronous calls serve a scene of one geometry (the
// caller refuses the others).
class MeshStore : public Store {
 public:
  // The scene's edges in the global numbering (global vertex ids), copied to host memory.
  virtual void copy_edges(Edge* host_out) = 0;
  // Geometry g (not static) to new positions, x1 for swept ones, refitting or rebuilding its
  // trees.
  virtual void move_geometry(int32_t g, const Strided& x0, const Strided* x1, bool rebuild) = 0;
  // Swept positions: the vertices move linearly from x0 to x1 over the step, and the trees box
  // each element over both (refit or build afresh); queries are then swept (query_sources.h) until a
  // plain refit or rebuild. The caller checks the buffers and the queries a swept scene runs.
  virtual void refit_swept(const Strided& x0, const Strided& x1) = 0;
  virtual void rebuild_swept(const Strided& x0, const Strided& x1) = 0;
  virtual bool swept() const = 0;
  // A VT and an EE query in one pass (one parallel loop; on CUDA one kernel launch and one
  // count readback): each query's total, pairs and work as query() gives them alone.
  virtual std::array<uint64_t, 2> query_vt_ee(const QueryJob& vt, const QueryJob& ee) = 0;

  // ---- Asynchronous calls (minkq.h's stream-ordered section): enqueued on `stream`, with no
  // synchronisation, allocation or host read on CUDA; run to completion on the CPU.
  // Grows the reservation to cover `wanted` (a blocking call).
  virtual void reserve(const Reservation& wanted) = 0;
  virtual const Reservation& reservation() const = 0;
  // New positions in executor memory, checked on the device: with a non-finite coordinate the
  // scene keeps its positions (rebuild_async then builds for them) and the pending error is
  // recorded. Need reservation().refit (rebuild_async: .rebuild); the caller checks that.
  virtual void refit_async(const Strided& vertices, Stream stream) = 0;
  virtual void rebuild_async(const Strided& vertices, Stream stream) = 0;
  // refit_swept / rebuild_swept, enqueued: with a non-finite coordinate in either buffer the
  // scene keeps its positions at rest (x1 = x0). Need reservation().swept too.
  virtual void refit_swept_async(const Strided& x0, const Strided& x1, Stream stream) = 0;
  virtual void rebuild_swept_async(const Strided& x0, const Strided& x1, Stream stream) = 0;
  // Queries whose outputs have `count` set (executor memory); canonical ones within the
  // reserved canonical capacity (the caller checks). No work counts.
  virtual void query_async(const QueryRequest& request, const PairOutput& out, Stream stream) = 0;
  virtual void query_vt_ee_async(const QueryRequest& vt, const PairOutput& vt_out, const QueryRequest& ee,
                                 const PairOutput& ee_out, Stream stream) = 0;
  // Waits for `stream`, then returns the pending error and clears it (a blocking call).
  virtual PendingError take_pending_error(Stream stream) = 0;
};

class Backend {
 public:
  virtual ~Backend() = default;
  virtual std::string name() const = 0;
  virtual bool is_cuda() const = 0;
  // First record (of `floats` coordinates each) holding a NaN or infinity, or -1; for float64
  // records also a coordinate beyond the float range (it would round to an infinity).
  virtual int64_t first_non_finite(const Strided& values, int floats) = 0;
  // Copies `bytes` from host or device memory to the host.
  virtual void copy_to_host(void* dst, const void* src, size_t bytes, Memory memory) = 0;
  // Throws Failure(kInvalidArgument), naming `what`, unless `data` (not null) is memory this
  // backend's kernels may read and write as device memory (a buffer marked kDevice).
  virtual void check_device_pointer(const void* data, const std::string& what) = 0;
  // Takes the geometries over (host vectors, validated by the caller; at least one).
  virtual std::unique_ptr<MeshStore> create_mesh_store(std::vector<GeometryInput> geometries) = 0;
  virtual std::unique_ptr<Store> create_box_store(const Strided& boxes) = 0;
};

std::unique_ptr<Backend> make_cpu_backend();
// Throws Failure(kUnsupported) where minkq was built without CUDA or no such device exists.
std::unique_ptr<Backend> make_cuda_backend(int ordinal);
int cuda_device_count();  // 0 where built without CUDA or no device/driver
bool built_with_cuda();

// Record i of host `values` into `out` (float records: Vec3, Box).
template <class T>
void gather_record(const Strided& values, int64_t i, T& out) {
  std::memcpy(&out, static_cast<const char*>(values.data) + size_t(i) * values.stride, sizeof(T));
}

// The first record of host `values` (of `floats` coordinates each) holding a NaN or infinity,
// or (float64 records) a coordinate that rounds to one, or -1.
inline int64_t first_non_finite_host(const Strided& values, int floats) {
  const char* base = static_cast<const char*>(values.data);
  for (int64_t i = 0; i < values.count; ++i) {
    const char* record = base + size_t(i) * values.stride;
    for (int k = 0; k < floats; ++k) {
      float f;
      if (values.scalar == Scalar::kFloat64) {
        double d;
        std::memcpy(&d, record + sizeof(double) * size_t(k), sizeof d);
        f = float(d);
      } else {
        std::memcpy(&f, record + sizeof(float) * size_t(k), sizeof f);
      }
      if (!std::isfinite(f)) return i;
    }
  }
  return -1;
}

// Float64 vertex i of host `values` rounded to nearest float into `out`; returns how far the
// rounding moved it (minkq/float64.h).
inline float round_float64_record(const Strided& values, int64_t i, Vec3& out) {
  double p[3];
  std::memcpy(p, static_cast<const char*>(values.data) + size_t(i) * values.stride, sizeof p);
  out = round_to_float(p);
  return rounding_distance(p, out);
}

// The gathers of host memory both backends use (the CPU backend's stores, the CUDA one's
// uploads), in parallel over blocks of records (TBB; defined in cpu/backend.cpp, so that no
// CUDA translation unit compiles TBB). Records of host `values` packed into `out`, room for
// values.count of them (float records: Vec3, Box).
void gather_host(const Strided& values, Vec3* out);
void gather_host(const Strided& values, Box* out);
// Host float64 vertices rounded into `out` (room for values.count), each by
// round_float64_record; returns rho, the farthest the rounding moved one. The maximum is exact
// and taken over all records, so it does not depend on how they were split. A NaN input moves
// by NaN, which the maximum drops (std::max keeps its first argument); callers reject
// non-finite input first.
float gather_float64_host(const Strided& values, Vec3* out);

}  // namespace minkq
