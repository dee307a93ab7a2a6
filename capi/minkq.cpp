// The C ABI front end: argument checks with messages naming the offending element, topology
// (edge derivation), digests and library-owned results; all geometry runs in a backend.
#include "minkq.h"

#include <xxhash.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <new>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "backend.h"

static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "digests hash little-endian int32 pairs in place");
static_assert(sizeof(minkq::Triangle) == 12 && sizeof(minkq::Edge) == 8 && sizeof(minkq::Box) == 24, "layouts");

// The C++ enums cross this file by static_cast (statuses out; memory kinds and modes in), so
// each must keep its C counterpart's values.
namespace {
template <class Cxx, class C>
constexpr bool same(Cxx cxx, C c) {
  return static_cast<long long>(cxx) == static_cast<long long>(c);
}
}  // namespace
static_assert(same(minkq::Status::kSuccess, MINKQ_SUCCESS) &&
                  same(minkq::Status::kInvalidArgument, MINKQ_ERROR_INVALID_ARGUMENT) &&
                  same(minkq::Status::kNonFinite, MINKQ_ERROR_NON_FINITE) &&
                  same(minkq::Status::kIndexOutOfRange, MINKQ_ERROR_INDEX_OUT_OF_RANGE) &&
                  same(minkq::Status::kSizeOverflow, MINKQ_ERROR_SIZE_OVERFLOW) &&
                  same(minkq::Status::kCapacity, MINKQ_ERROR_CAPACITY) &&
                  same(minkq::Status::kUnsupported, MINKQ_ERROR_UNSUPPORTED) &&
                  same(minkq::Status::kOutOfMemory, MINKQ_ERROR_OUT_OF_MEMORY) &&
                  same(minkq::Status::kDevice, MINKQ_ERROR_DEVICE) && same(minkq::Status::kInternal, MINKQ_ERROR_INTERNAL),
              "minkq::Status (core/src/backend.h) must equal minkq_status value by value");
static_assert(same(minkq::Memory::kHost, MINKQ_MEMORY_HOST) && same(minkq::Memory::kDevice, MINKQ_MEMORY_DEVICE),
              "minkq::Memory (core/src/backend.h) must equal minkq_memory");
static_assert(same(minkq::Mode::kBox, MINKQ_MODE_BOX) && same(minkq::Mode::kSphere, MINKQ_MODE_SPHERE) &&
                  same(minkq::Mode::kCapsuleRay, MINKQ_MODE_CAPSULE_RAY) &&
                  same(minkq::Mode::kCapsuleExact, MINKQ_MODE_CAPSULE_EXACT),
              "minkq::Mode (core/include/minkq/shapes.h) must equal minkq_mode");
// Scene query kinds are chosen by name below (the user-box kinds by minkq_shape); they are
// numbered alike all the same.
static_assert(same(minkq::QueryKind::kVertexTriangle, MINKQ_QUERY_VT) && same(minkq::QueryKind::kEdgeEdge, MINKQ_QUERY_EE),
              "minkq::QueryKind (core/src/backend.h) must number VT and EE as minkq_query_kind");
// The filter bits are set one C flag at a time (checked_scene_request): MINKQ_SCENE_DROP_INCIDENT
// gives kDropIncident, MINKQ_QUERY_LEAF_EXACT gives kLeafExact. They are not the C flags'
// values (kLeafExact is 2, MINKQ_QUERY_LEAF_EXACT 1), so what must hold is that they are two
// distinct bits.
static_assert(minkq::kDropIncident != 0 && minkq::kLeafExact != 0 && (minkq::kDropIncident & minkq::kLeafExact) == 0 &&
                  (minkq::kDropIncident & (minkq::kDropIncident - 1)) == 0 &&
                  (minkq::kLeafExact & (minkq::kLeafExact - 1)) == 0,
              "kDropIncident and kLeafExact (core/include/minkq/queries.h) must be two distinct bits");

using minkq::Failure;
using minkq::fail;
using minkq::Status;

struct minkq_device {
  std::unique_ptr<minkq::Backend> backend;
  std::string name;
  minkq_backend kind;
};

struct minkq_scene {
  minkq_device* device;
  uint32_t flags;
  size_t vertex_count, triangle_count, edge_count;
  std::unique_ptr<minkq::MeshStore> store;  // holds the scene's only copy of its topology
};

struct minkq_bvh {
  minkq_device* device;
  size_t box_count;
  std::unique_ptr<minkq::Store> store;
};

struct minkq_result {
  std::vector<int32_t> pairs;
  uint64_t count = 0;
  uint64_t digest = 0;
  minkq_query_stats stats{};
};

namespace {

thread_local std::string last_error;

template <class Fn>
minkq_status guarded(Fn&& fn) {
  try {
    fn();
    last_error.clear();
    return MINKQ_SUCCESS;
  } catch (const Failure& failure) {
    last_error = failure.what();
    return static_cast<minkq_status>(failure.status);
  } catch (const std::bad_alloc&) {
    last_error = "out of host memory";
    return MINKQ_ERROR_OUT_OF_MEMORY;
  } catch (const std::exception& e) {
    last_error = std::string("internal error: ") + e.what();
    return MINKQ_ERROR_INTERNAL;
  }
}

// The integer a caller stored in an enum-typed field or argument. C lets any int live there,
// but loading a value outside the enumerators' range as the C++ enum type is undefined
// behaviour, so enum arguments are validated through their object representation.
template <class E>
int64_t enum_value(const E& value) {
  std::underlying_type_t<E> raw;
  static_assert(sizeof raw == sizeof value, "enum layout");
  std::memcpy(&raw, &value, sizeof raw);
  return int64_t(raw);
}

void require(bool condition, Status status, const std::string& message) {
  if (!condition) fail(status, message);
}

std::string format_float(float v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.9g", double(v));
  return text;
}

// Checks a buffer's pointer, stride, count and memory kind; returns it as a Strided view.
minkq::Strided checked_buffer(const minkq_device* device, const minkq_buffer& buffer, size_t element_size,
                              const char* what) {
  const std::string name(what);
  const int64_t memory = enum_value(buffer.memory);
  require(memory == MINKQ_MEMORY_HOST || memory == MINKQ_MEMORY_DEVICE, Status::kInvalidArgument,
          name + ".memory is not a minkq_memory value");
  require(buffer.memory == MINKQ_MEMORY_HOST || device->kind == MINKQ_BACKEND_CUDA, Status::kInvalidArgument,
          name + " is in device memory but the device is " + device->name);
  require(buffer.count == 0 || buffer.data != nullptr, Status::kInvalidArgument,
          name + ".data is NULL but " + name + ".count is " + std::to_string(buffer.count));
  const size_t stride = buffer.byte_stride == 0 ? element_size : buffer.byte_stride;
  require(stride >= element_size, Status::kInvalidArgument,
          name + ".byte_stride " + std::to_string(stride) + " is smaller than one element (" +
              std::to_string(element_size) + " bytes)");
  if (buffer.memory == MINKQ_MEMORY_DEVICE && buffer.count > 0) device->backend->check_device_pointer(buffer.data, name + ".data");
  require(buffer.count <= size_t(minkq::kMaxPrimitives), Status::kSizeOverflow,
          name + ".count " + std::to_string(buffer.count) + " exceeds the limit of 2^31 - 2 elements");
  require(buffer.count == 0 || stride <= SIZE_MAX / buffer.count, Status::kSizeOverflow,
          name + ": " + std::to_string(buffer.count) + " elements of stride " + std::to_string(stride) +
              " bytes overflow the address space");
  return {buffer.data, stride, int64_t(buffer.count), static_cast<minkq::Memory>(buffer.memory)};
}

// Copies the records of a strided buffer (host or device) into a packed host vector.
template <class T>
std::vector<T> host_copy(minkq::Backend& backend, const minkq::Strided& values) {
  std::vector<T> out(static_cast<size_t>(values.count));
  if (values.count == 0) return out;
  const size_t span = size_t(values.count - 1) * values.stride + sizeof(T);
  std::vector<char> raw(span);
  backend.copy_to_host(raw.data(), values.data, span, values.memory);
  for (size_t i = 0; i < out.size(); ++i) std::memcpy(&out[i], raw.data() + i * values.stride, sizeof(T));
  return out;
}

void require_finite(minkq::Backend& backend, const minkq::Strided& values, int floats, const char* element) {
  const int64_t bad = backend.first_non_finite(values, floats);
  if (bad < 0) return;
  const char* record = static_cast<const char*>(values.data) + size_t(bad) * values.stride;
  std::string coords;
  if (values.scalar == minkq::Scalar::kFloat64) {
    double d[3];
    backend.copy_to_host(d, record, sizeof(double) * size_t(floats), values.memory);
    for (int k = 0; k < floats; ++k) {
      char text[40];
      std::snprintf(text, sizeof text, "%.17g", d[k]);
      coords += (k ? ", " : "") + std::string(text);
    }
    fail(Status::kNonFinite, std::string(element) + " " + std::to_string(bad) +
                                 " has a coordinate that is not finite or beyond the float range (" + coords + ")");
  }
  float f[6];
  backend.copy_to_host(f, record, sizeof(float) * size_t(floats), values.memory);
  for (int k = 0; k < floats; ++k) coords += (k ? ", " : "") + format_float(f[k]);
  fail(Status::kNonFinite, std::string(element) + " " + std::to_string(bad) + " has a non-finite coordinate (" +
                               coords + ")");
}

// "vertices", or "x1 vertices" for a buffer named otherwise (the swept calls' x0 and x1).
std::string vertices_named(const std::string& what) { return what == "vertices" ? what : what + " vertices"; }

// A scene's vertex buffer, checked: 3 floats each, or 3 doubles for a MINKQ_SCENE_FLOAT64 scene.
minkq::Strided checked_vertex_buffer(const minkq_device* device, const minkq_buffer& buffer, uint32_t scene_flags,
                                     const char* what = "vertices") {
  const bool float64 = (scene_flags & MINKQ_SCENE_FLOAT64) != 0;
  minkq::Strided values = checked_buffer(device, buffer, float64 ? 24 : 12, what);
  values.scalar = float64 ? minkq::Scalar::kFloat64 : minkq::Scalar::kFloat32;
  return values;
}

template <int N, class T>
void require_indices(const std::vector<T>& elements, size_t vertex_count, const char* element) {
  for (size_t i = 0; i < elements.size(); ++i)
    for (int k = 0; k < N; ++k) {
      const int32_t v = elements[i].v[k];
      if (v < 0 || size_t(v) >= vertex_count)
        fail(Status::kIndexOutOfRange, std::string(element) + " " + std::to_string(i) + " references vertex " +
                                           std::to_string(v) + " but the scene has " +
                                           std::to_string(vertex_count) + " vertices");
    }
}

// User boxes need lo <= hi on every axis (validated on the host: device boxes are copied).
void require_ordered_boxes(minkq::Backend& backend, const minkq::Strided& values) {
  const std::vector<minkq::Box> boxes = host_copy<minkq::Box>(backend, values);
  for (size_t i = 0; i < boxes.size(); ++i) {
    const minkq::Box& b = boxes[i];
    require(b.lo.x <= b.hi.x && b.lo.y <= b.hi.y && b.lo.z <= b.hi.z, Status::kInvalidArgument,
            "box " + std::to_string(i) + " has lo > hi");
  }
}

// Every distinct undirected triangle edge as (min, max), in lexicographic order. A triangle
// with a repeated vertex contributes its zero-length edge (v, v) too.
std::vector<minkq::Edge> derive_edges(const std::vector<minkq::Triangle>& triangles) {
  std::vector<uint64_t> keys;
  keys.reserve(triangles.size() * 3);
  for (const auto& t : triangles)
    for (int k = 0; k < 3; ++k) {
      const int32_t a = t.v[k], b = t.v[(k + 1) % 3];  // non-negative (require_indices ran)
      keys.push_back(minkq::pack_pair(std::min(a, b), std::max(a, b)));
    }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  std::vector<minkq::Edge> edges(keys.size());
  for (size_t i = 0; i < keys.size(); ++i) {
    const minkq::Pair pair = minkq::unpack_pair(keys[i]);
    edges[i] = {{pair.first, pair.second}};
  }
  return edges;
}

void require_radius(float r) {
  require(std::isfinite(r), Status::kNonFinite, "radius " + format_float(r) + " is not finite");
  require(r >= 0.0f, Status::kInvalidArgument, "radius " + format_float(r) + " is negative");
}

constexpr uint32_t kKnownQueryFlags =
    MINKQ_QUERY_LEAF_EXACT | MINKQ_QUERY_CANONICAL | MINKQ_QUERY_DIGEST | MINKQ_QUERY_STATS;

// The parameter names of an output buffer, for messages.
struct OutputNames {
  std::string pairs, capacity, info;
};

// A pair buffer's pointer against its capacity (in pairs of 2 int32), named in messages.
void require_pair_capacity(const int32_t* pairs, size_t capacity, const std::string& pairs_name,
                           const std::string& capacity_name) {
  require(capacity == 0 || pairs != nullptr, Status::kInvalidArgument,
          pairs_name + " is NULL but " + capacity_name + " is " + std::to_string(capacity));
  require(capacity <= SIZE_MAX / (2 * sizeof(int32_t)), Status::kSizeOverflow,
          capacity_name + " " + std::to_string(capacity) + " pairs overflows the address space");
}

// A caller's output buffer, checked.
minkq::PairOutput checked_output(const minkq_device* device, int32_t* out_pairs, size_t capacity,
                                 const minkq_memory& out_memory, uint32_t flags, const minkq_query_info* info,
                                 const OutputNames& name) {
  require(info != nullptr, Status::kInvalidArgument, name.info + " is NULL");
  const int64_t memory = enum_value(out_memory);
  require(memory == MINKQ_MEMORY_HOST || memory == MINKQ_MEMORY_DEVICE, Status::kInvalidArgument,
          "out_memory is not a minkq_memory value");
  require(out_memory == MINKQ_MEMORY_HOST || device->kind == MINKQ_BACKEND_CUDA, Status::kInvalidArgument,
          name.pairs + " is in device memory but the device is " + device->name);
  require_pair_capacity(out_pairs, capacity, name.pairs, name.capacity);
  if (out_memory == MINKQ_MEMORY_DEVICE && capacity > 0) device->backend->check_device_pointer(out_pairs, name.pairs);
  return {out_pairs, capacity, static_cast<minkq::Memory>(out_memory),
          (flags & (MINKQ_QUERY_DIGEST | MINKQ_QUERY_CANONICAL)) != 0};
}

// Fills info (zeroed before the query ran) from a query's count and work, and its digest when
// asked for and the pairs fit. Returns whether they fit.
bool report(const minkq_device* device, const minkq::PairOutput& out, uint32_t flags, uint64_t count,
            const minkq::WorkCounts& work, minkq_query_info* info) {
  info->count = count;
  info->stats = {work.nodes_visited, work.node_tests, work.primitive_tests, work.candidates};
  if (count > out.capacity) return false;
  if (flags & MINKQ_QUERY_DIGEST) {
    const size_t bytes = size_t(count) * 2 * sizeof(int32_t);
    if (out.memory == minkq::Memory::kHost) {
      info->digest = XXH64(out.pairs, bytes, 0);
    } else {
      std::vector<int32_t> host(size_t(count) * 2);
      device->backend->copy_to_host(host.data(), out.pairs, bytes, minkq::Memory::kDevice);
      info->digest = XXH64(host.data(), bytes, 0);
    }
  }
  return true;
}

std::string capacity_message(uint64_t count, size_t capacity) {
  return std::to_string(count) + " pairs found but the buffer holds " + std::to_string(capacity);
}

// Runs a request against a store with the common output checks, CAPACITY and digest.
void run_and_report(minkq_device* device, minkq::Store& store, const minkq::QueryRequest& request, uint32_t flags,
                    int32_t* out_pairs, size_t capacity, const minkq_memory& out_memory, minkq_query_info* info) {
  const minkq::PairOutput out = checked_output(device, out_pairs, capacity, out_memory, flags, info,
                                                    {"out_pairs", "capacity", "info"});
  *info = minkq_query_info{};
  minkq::WorkCounts work;
  const uint64_t count = store.query(request, out, (flags & MINKQ_QUERY_STATS) ? &work : nullptr);
  if (!report(device, out, flags, count, work, info)) fail(Status::kCapacity, capacity_message(count, capacity));
}

// A scene query's description, checked; `name` names it in messages ("query", "vt_query").
minkq::QueryRequest checked_scene_request(const minkq_scene* scene, const minkq_query_desc* query,
                                          const std::string& name) {
  require(query != nullptr, Status::kInvalidArgument, name + " is NULL");
  const int64_t kind = enum_value(query->kind), mode = enum_value(query->mode);
  require(kind >= MINKQ_QUERY_VT && kind <= MINKQ_QUERY_EV, Status::kInvalidArgument,
          name + "->kind is not a minkq_query_kind value");
  require(mode >= MINKQ_MODE_BOX && mode <= MINKQ_MODE_CAPSULE_EXACT, Status::kInvalidArgument,
          name + "->mode is not a minkq_mode value");
  require((query->flags & ~kKnownQueryFlags) == 0, Status::kInvalidArgument, name + "->flags has unknown bits");
  static const char* const kKindNames[] = {"VT", "EE", "VV", "EV"};
  static const uint32_t kKindFlags[] = {MINKQ_SCENE_VT, MINKQ_SCENE_EE, MINKQ_SCENE_VV, MINKQ_SCENE_EV};
  const std::string kind_name = kKindNames[kind];
  require(scene->flags & kKindFlags[kind], Status::kInvalidArgument,
          kind_name + " query on a scene created without MINKQ_SCENE_" + kind_name);
  const bool ee = kind == MINKQ_QUERY_EE;
  require(!ee || query->mode != MINKQ_MODE_SPHERE, Status::kInvalidArgument,
          "sphere mode needs point queries; use capsule_ray or capsule_exact for EE");
  require_radius(query->radius);
  if (scene->store->swept()) {
    require(!(query->flags & MINKQ_QUERY_LEAF_EXACT), Status::kUnsupported,
            name + "->flags asks for MINKQ_QUERY_LEAF_EXACT on swept positions: that needs a narrow phase "
                   "(the time of closest approach), which minkq leaves to the caller; query without it");
    require(!ee || query->mode == MINKQ_MODE_BOX, Status::kUnsupported,
            name + ": swept EE queries run box mode only (a moving edge sweeps no segment)");
  }
  uint32_t filters = 0;
  if (scene->flags & MINKQ_SCENE_DROP_INCIDENT) filters |= minkq::kDropIncident;
  if (query->flags & MINKQ_QUERY_LEAF_EXACT) filters |= minkq::kLeafExact;
  static const minkq::QueryKind kKinds[] = {minkq::QueryKind::kVertexTriangle, minkq::QueryKind::kEdgeEdge,
                                            minkq::QueryKind::kVertexVertex, minkq::QueryKind::kVertexEdge};
  return {kKinds[kind], static_cast<minkq::Mode>(query->mode), filters, query->radius, {}, {}};
}

// The two descriptions of a fused VT + EE call, checked (the scene too).
std::array<minkq::QueryRequest, 2> checked_vt_ee_requests(const minkq_scene* scene, const minkq_query_desc* vt_query,
                                                          const minkq_query_desc* ee_query) {
  require(scene != nullptr, Status::kInvalidArgument, "scene is NULL");
  const minkq::QueryRequest vt = checked_scene_request(scene, vt_query, "vt_query");
  const minkq::QueryRequest ee = checked_scene_request(scene, ee_query, "ee_query");
  require(vt_query->kind == MINKQ_QUERY_VT, Status::kInvalidArgument, "vt_query->kind is not MINKQ_QUERY_VT");
  require(ee_query->kind == MINKQ_QUERY_EE, Status::kInvalidArgument, "ee_query->kind is not MINKQ_QUERY_EE");
  return {vt, ee};
}

// New vertex positions for a scene, validated: `verb` names the call in messages.
minkq::Strided checked_vertices(const minkq_scene* scene, minkq_buffer vertices, const char* verb,
                                const char* what = "vertices") {
  require(scene != nullptr, Status::kInvalidArgument, "scene is NULL");
  const minkq::Strided values = checked_vertex_buffer(scene->device, vertices, scene->flags, what);
  require(size_t(values.count) == scene->vertex_count, Status::kInvalidArgument,
          std::string(verb) + " with " + std::to_string(values.count) + " " + vertices_named(what) +
              " but the scene has " + std::to_string(scene->vertex_count));
  const std::string element = std::string(what) == "vertices" ? "vertex" : std::string(what) + " vertex";
  require_finite(*scene->device->backend, values, 3, element.c_str());
  return values;
}

// New boxes for a bvh, validated: `verb` names the call in messages.
minkq::Strided checked_new_boxes(const minkq_bvh* bvh, minkq_buffer boxes, const char* verb) {
  require(bvh != nullptr, Status::kInvalidArgument, "bvh is NULL");
  const minkq::Strided values = checked_buffer(bvh->device, boxes, 24, "boxes");
  require(size_t(values.count) == bvh->box_count, Status::kInvalidArgument,
          std::string(verb) + " with " + std::to_string(values.count) + " boxes but the bvh has " +
              std::to_string(bvh->box_count));
  require_finite(*bvh->device->backend, values, 6, "box");
  require_ordered_boxes(*bvh->device->backend, values);
  return values;
}

// Runs query(infos), a call writing into the results' buffers, so that the results grow as
// needed: on CAPACITY each short buffer grows to its exact count and the call runs again.
template <size_t N, class Query>
minkq_status query_into_results(const std::array<minkq_result*, N>& results, Query&& query) {
  std::array<minkq_query_info, N> info{};
  minkq_status status = query(info);
  if (status == MINKQ_ERROR_CAPACITY) {
    const minkq_status grown = guarded([&] {
      for (size_t k = 0; k < N; ++k)
        if (results[k]->pairs.size() / 2 < info[k].count) results[k]->pairs.resize(size_t(info[k].count) * 2);
    });
    if (grown != MINKQ_SUCCESS) return grown;
    status = query(info);
  }
  for (size_t k = 0; k < N; ++k) {
    results[k]->count = status == MINKQ_SUCCESS ? info[k].count : 0;
    results[k]->digest = status == MINKQ_SUCCESS ? info[k].digest : 0;
    results[k]->stats = status == MINKQ_SUCCESS ? info[k].stats : minkq_query_stats{};
  }
  return status;
}

// ---- Asynchronous calls ---------------------------------------------------------------------

// The memory asynchronous calls read and write: device memory on a CUDA device, host memory on
// the CPU.
minkq_memory async_memory(const minkq_device* device) {
  return device->kind == MINKQ_BACKEND_CUDA ? MINKQ_MEMORY_DEVICE : MINKQ_MEMORY_HOST;
}

// New vertex positions for an asynchronous refit or rebuild, validated as far as the host can
// (their coordinates are checked on the device), with the reservation the call needs.
minkq::Strided checked_async_vertices(const minkq_scene* scene, minkq_buffer vertices, const char* call,
                                      bool rebuild, bool swept = false, const char* what = "vertices") {
  require(scene != nullptr, Status::kInvalidArgument, "scene is NULL");
  const minkq::Reservation& reserved = scene->store->reservation();
  require((rebuild ? reserved.rebuild : reserved.refit) && (!swept || reserved.swept), Status::kInvalidArgument,
          std::string(call) + " needs scratch reserved first: minkq_scene_reserve(scene, " +
              (rebuild ? "MINKQ_RESERVE_REBUILD" : "MINKQ_RESERVE_REFIT") + (swept ? " | MINKQ_RESERVE_SWEPT" : "") +
              ", ...)");
  const minkq::Strided values = checked_vertex_buffer(scene->device, vertices, scene->flags, what);
  require(enum_value(vertices.memory) == async_memory(scene->device), Status::kInvalidArgument,
          std::string(what) + " are host memory but " + call + " on " + scene->device->name +
              " reads device memory (MINKQ_MEMORY_DEVICE)");
  require(size_t(values.count) == scene->vertex_count, Status::kInvalidArgument,
          std::string(call) + " with " + std::to_string(values.count) + " " + vertices_named(what) +
              " but the scene has " + std::to_string(scene->vertex_count));
  return values;
}

// An asynchronous query's outputs, checked: pairs and count in the call's memory, flags the
// path supports, canonical order within the reservation. `prefix` names the query ("", "vt_").
minkq::PairOutput checked_async_output(const minkq_scene* scene, const minkq_query_desc* query, int32_t* out_pairs,
                                       size_t capacity, uint64_t* out_count, const std::string& prefix) {
  const minkq_device* device = scene->device;
  const std::string pairs = prefix.empty() ? "out_pairs" : prefix + "pairs";
  const std::string count = prefix.empty() ? "out_count" : prefix + "count";
  const std::string cap = prefix + "capacity";
  const std::string name = prefix.empty() ? "query" : prefix + "query";
  require((query->flags & (MINKQ_QUERY_DIGEST | MINKQ_QUERY_STATS)) == 0, Status::kUnsupported,
          name + "->flags asks for a digest or stats, which need a host read: asynchronous queries support "
                 "MINKQ_QUERY_LEAF_EXACT and MINKQ_QUERY_CANONICAL");
  require(out_count != nullptr, Status::kInvalidArgument, count + " is NULL");
  require_pair_capacity(out_pairs, capacity, pairs, cap);
  const bool canonical = (query->flags & MINKQ_QUERY_CANONICAL) != 0;
  const size_t reserved = scene->store->reservation().canonical_capacity;
  require(!canonical || capacity <= reserved, Status::kInvalidArgument,
          "canonical order for " + cap + " " + std::to_string(capacity) + " needs that many pairs reserved: " +
              "minkq_scene_reserve(scene, flags, " + std::to_string(capacity) + ") (reserved: " +
              std::to_string(reserved) + ")");
  if (device->kind == MINKQ_BACKEND_CUDA) {
    if (capacity > 0) device->backend->check_device_pointer(out_pairs, pairs);
    device->backend->check_device_pointer(out_count, count);
  }
  return {out_pairs, capacity, static_cast<minkq::Memory>(async_memory(device)), canonical, out_count};
}

}  // namespace

extern "C" {

uint32_t minkq_version(void) { return MINKQ_VERSION_MAJOR * 10000 + MINKQ_VERSION_MINOR * 100 + MINKQ_VERSION_PATCH; }
uint32_t minkq_abi_version(void) { return MINKQ_ABI_VERSION; }
const char* minkq_last_error_message(void) { return last_error.c_str(); }

const char* minkq_status_name(minkq_status status) {
  switch (enum_value(status)) {
    case MINKQ_SUCCESS: return "MINKQ_SUCCESS";
    case MINKQ_ERROR_INVALID_ARGUMENT: return "MINKQ_ERROR_INVALID_ARGUMENT";
    case MINKQ_ERROR_NON_FINITE: return "MINKQ_ERROR_NON_FINITE";
    case MINKQ_ERROR_INDEX_OUT_OF_RANGE: return "MINKQ_ERROR_INDEX_OUT_OF_RANGE";
    case MINKQ_ERROR_SIZE_OVERFLOW: return "MINKQ_ERROR_SIZE_OVERFLOW";
    case MINKQ_ERROR_CAPACITY: return "MINKQ_ERROR_CAPACITY";
    case MINKQ_ERROR_UNSUPPORTED: return "MINKQ_ERROR_UNSUPPORTED";
    case MINKQ_ERROR_OUT_OF_MEMORY: return "MINKQ_ERROR_OUT_OF_MEMORY";
    case MINKQ_ERROR_DEVICE: return "MINKQ_ERROR_DEVICE";
    case MINKQ_ERROR_INTERNAL: return "MINKQ_ERROR_INTERNAL";
  }
  return "unknown minkq_status";
}

int minkq_cuda_device_count(void) { return minkq::cuda_device_count(); }

minkq_status minkq_device_create(const char* spec, minkq_device** out_device) {
  return guarded([&] {
    require(out_device != nullptr, Status::kInvalidArgument, "out_device is NULL");
    *out_device = nullptr;
    require(spec != nullptr, Status::kInvalidArgument, "spec is NULL (use \"cpu\", \"cuda\", \"cuda:N\" or \"auto\")");
    const std::string text(spec);
    auto device = std::make_unique<minkq_device>();
    int ordinal = -1;
    if (text == "cuda") {
      ordinal = 0;
    } else if (text.rfind("cuda:", 0) == 0) {
      const std::string digits = text.substr(5);
      require(!digits.empty() && digits.size() < 6 && digits.find_first_not_of("0123456789") == std::string::npos,
              Status::kInvalidArgument, "device spec \"" + text + "\": expected cuda:N with N a device number");
      ordinal = std::stoi(digits);
    } else if (text == "auto") {
      ordinal = minkq::cuda_device_count() > 0 ? 0 : -1;
    } else {
      require(text == "cpu", Status::kInvalidArgument,
              "unknown device spec \"" + text + "\" (use \"cpu\", \"cuda\", \"cuda:N\" or \"auto\")");
    }
    if (ordinal >= 0) {
      device->backend = minkq::make_cuda_backend(ordinal);
      device->kind = MINKQ_BACKEND_CUDA;
    } else {
      device->backend = minkq::make_cpu_backend();
      device->kind = MINKQ_BACKEND_CPU;
    }
    device->name = device->backend->name();
    *out_device = device.release();
  });
}

void minkq_device_release(minkq_device* device) { delete device; }
minkq_backend minkq_device_backend(const minkq_device* device) { return device ? device->kind : MINKQ_BACKEND_CPU; }
const char* minkq_device_name(const minkq_device* device) { return device ? device->name.c_str() : ""; }

minkq_status minkq_scene_create(minkq_device* device, const minkq_scene_desc* desc, minkq_scene** out_scene) {
  return guarded([&] {
    require(out_scene != nullptr, Status::kInvalidArgument, "out_scene is NULL");
    *out_scene = nullptr;
    require(device != nullptr, Status::kInvalidArgument, "device is NULL");
    require(desc != nullptr, Status::kInvalidArgument, "desc is NULL");
    const uint32_t kinds = MINKQ_SCENE_VT | MINKQ_SCENE_EE | MINKQ_SCENE_VV | MINKQ_SCENE_EV;
    const uint32_t known = kinds | MINKQ_SCENE_DROP_INCIDENT | MINKQ_SCENE_FLOAT64;
    require((desc->flags & ~known) == 0, Status::kInvalidArgument, "desc->flags has unknown bits");
    require(desc->flags & kinds, Status::kInvalidArgument,
            "desc->flags asks for no query: set one or more of MINKQ_SCENE_VT, MINKQ_SCENE_EE, MINKQ_SCENE_VV and "
            "MINKQ_SCENE_EV");
    minkq::Backend& backend = *device->backend;
    const minkq::Strided vertices = checked_vertex_buffer(device, desc->vertices, desc->flags);
    const minkq::Strided triangles = checked_buffer(device, desc->triangles, 12, "triangles");
    const minkq::Strided edges = checked_buffer(device, desc->edges, 8, "edges");
    require_finite(backend, vertices, 3, "vertex");
    auto scene = std::make_unique<minkq_scene>();
    scene->device = device;
    scene->flags = desc->flags;
    scene->vertex_count = size_t(vertices.count);
    std::vector<minkq::Triangle> triangle_list = host_copy<minkq::Triangle>(backend, triangles);
    require_indices<3>(triangle_list, scene->vertex_count, "triangle");
    std::vector<minkq::Edge> edge_list;
    if (edges.count > 0) {
      edge_list = host_copy<minkq::Edge>(backend, edges);
      require_indices<2>(edge_list, scene->vertex_count, "edge");
    } else if (desc->flags & (MINKQ_SCENE_EE | MINKQ_SCENE_EV)) {
      edge_list = derive_edges(triangle_list);
      require(edge_list.size() <= size_t(minkq::kMaxPrimitives), Status::kSizeOverflow,
              "the triangles have more than 2^31 - 2 edges");
    }
    scene->triangle_count = triangle_list.size();
    scene->edge_count = edge_list.size();
    minkq::MeshTrees trees;
    trees.triangles = desc->flags & MINKQ_SCENE_VT;
    trees.edges = desc->flags & (MINKQ_SCENE_EE | MINKQ_SCENE_EV);
    trees.vertices = desc->flags & MINKQ_SCENE_VV;
    trees.vertex_order = desc->flags & (MINKQ_SCENE_VT | MINKQ_SCENE_EV);
    scene->store = backend.create_mesh_store(vertices, std::move(triangle_list), std::move(edge_list), trees);
    *out_scene = scene.release();
  });
}

void minkq_scene_release(minkq_scene* scene) { delete scene; }
size_t minkq_scene_vertex_count(const minkq_scene* scene) { return scene ? scene->vertex_count : 0; }
size_t minkq_scene_triangle_count(const minkq_scene* scene) { return scene ? scene->triangle_count : 0; }
size_t minkq_scene_edge_count(const minkq_scene* scene) { return scene ? scene->edge_count : 0; }

minkq_status minkq_scene_edges(const minkq_scene* scene, int32_t* out_edges, size_t capacity) {
  return guarded([&] {
    require(scene != nullptr, Status::kInvalidArgument, "scene is NULL");
    require(capacity == 0 || out_edges != nullptr, Status::kInvalidArgument, "out_edges is NULL");
    require(scene->edge_count <= capacity, Status::kCapacity,
            "the scene has " + std::to_string(scene->edge_count) + " edges but the buffer holds " +
                std::to_string(capacity));
    if (scene->edge_count) scene->store->copy_edges(reinterpret_cast<minkq::Edge*>(out_edges));
  });
}

minkq_status minkq_scene_refit(minkq_scene* scene, minkq_buffer vertices) {
  return guarded([&] {
    const minkq::Strided values = checked_vertices(scene, vertices, "refit");  // checks scene first
    scene->store->refit(values);
  });
}

minkq_status minkq_scene_rebuild(minkq_scene* scene, minkq_buffer vertices) {
  return guarded([&] {
    const minkq::Strided values = checked_vertices(scene, vertices, "rebuild");  // checks scene first
    scene->store->rebuild(values);
  });
}

minkq_status minkq_scene_refit_swept(minkq_scene* scene, minkq_buffer x0, minkq_buffer x1) {
  return guarded([&] {
    const minkq::Strided start = checked_vertices(scene, x0, "refit_swept", "x0");  // checks scene first
    const minkq::Strided end = checked_vertices(scene, x1, "refit_swept", "x1");
    scene->store->refit_swept(start, end);
  });
}

minkq_status minkq_scene_rebuild_swept(minkq_scene* scene, minkq_buffer x0, minkq_buffer x1) {
  return guarded([&] {
    const minkq::Strided start = checked_vertices(scene, x0, "rebuild_swept", "x0");  // checks scene first
    const minkq::Strided end = checked_vertices(scene, x1, "rebuild_swept", "x1");
    scene->store->rebuild_swept(start, end);
  });
}

int minkq_scene_is_swept(const minkq_scene* scene) { return scene && scene->store->swept() ? 1 : 0; }

minkq_status minkq_scene_tree_growth(const minkq_scene* scene, double* out_growth) {
  return guarded([&] {
    require(scene != nullptr, Status::kInvalidArgument, "scene is NULL");
    require(out_growth != nullptr, Status::kInvalidArgument, "out_growth is NULL");
    *out_growth = scene->store->tree_growth();
  });
}

minkq_status minkq_scene_query(minkq_scene* scene, const minkq_query_desc* query, int32_t* out_pairs,
                               size_t capacity, minkq_memory out_memory, minkq_query_info* info) {
  return guarded([&] {
    require(scene != nullptr, Status::kInvalidArgument, "scene is NULL");
    const minkq::QueryRequest request = checked_scene_request(scene, query, "query");
    run_and_report(scene->device, *scene->store, request, query->flags, out_pairs, capacity, out_memory, info);
  });
}

minkq_status minkq_scene_query_vt_ee(minkq_scene* scene, const minkq_query_desc* vt_query,
                                     const minkq_query_desc* ee_query, int32_t* vt_pairs, size_t vt_capacity,
                                     int32_t* ee_pairs, size_t ee_capacity, minkq_memory out_memory,
                                     minkq_query_info* vt_info, minkq_query_info* ee_info) {
  return guarded([&] {
    const auto [vt, ee] = checked_vt_ee_requests(scene, vt_query, ee_query);
    const minkq::PairOutput vt_out =
        checked_output(scene->device, vt_pairs, vt_capacity, out_memory, vt_query->flags, vt_info,
                       {"vt_pairs", "vt_capacity", "vt_info"});
    const minkq::PairOutput ee_out =
        checked_output(scene->device, ee_pairs, ee_capacity, out_memory, ee_query->flags, ee_info,
                       {"ee_pairs", "ee_capacity", "ee_info"});
    require(vt_info != ee_info, Status::kInvalidArgument, "vt_info and ee_info are the same struct");
    *vt_info = minkq_query_info{};
    *ee_info = minkq_query_info{};
    minkq::WorkCounts vt_work, ee_work;
    const std::array<uint64_t, 2> counts = scene->store->query_vt_ee(
        {vt, vt_out, (vt_query->flags & MINKQ_QUERY_STATS) ? &vt_work : nullptr},
        {ee, ee_out, (ee_query->flags & MINKQ_QUERY_STATS) ? &ee_work : nullptr});
    const bool vt_fits = report(scene->device, vt_out, vt_query->flags, counts[0], vt_work, vt_info);
    const bool ee_fits = report(scene->device, ee_out, ee_query->flags, counts[1], ee_work, ee_info);
    if (!vt_fits) fail(Status::kCapacity, "VT: " + capacity_message(counts[0], vt_capacity));
    if (!ee_fits) fail(Status::kCapacity, "EE: " + capacity_message(counts[1], ee_capacity));
  });
}

constexpr uint32_t kKnownReserveFlags = MINKQ_RESERVE_REFIT | MINKQ_RESERVE_REBUILD | MINKQ_RESERVE_SWEPT;

minkq_status minkq_scene_reserve(minkq_scene* scene, uint32_t flags, size_t canonical_capacity) {
  return guarded([&] {
    require(scene != nullptr, Status::kInvalidArgument, "scene is NULL");
    require((flags & ~kKnownReserveFlags) == 0, Status::kInvalidArgument, "flags has unknown bits");
    require(canonical_capacity <= SIZE_MAX / (2 * sizeof(uint64_t)), Status::kSizeOverflow,
            "canonical_capacity " + std::to_string(canonical_capacity) + " pairs overflows the address space");
    minkq::Reservation wanted;
    wanted.refit = (flags & (MINKQ_RESERVE_REFIT | MINKQ_RESERVE_REBUILD)) != 0;
    wanted.rebuild = (flags & MINKQ_RESERVE_REBUILD) != 0;
    wanted.swept = (flags & MINKQ_RESERVE_SWEPT) != 0;
    wanted.canonical_capacity = canonical_capacity;
    scene->store->reserve(wanted);
  });
}

minkq_status minkq_scene_refit_async(minkq_scene* scene, minkq_buffer vertices, minkq_stream stream) {
  return guarded([&] {
    const minkq::Strided values = checked_async_vertices(scene, vertices, "minkq_scene_refit_async", false);
    scene->store->refit_async(values, stream);
  });
}

minkq_status minkq_scene_rebuild_async(minkq_scene* scene, minkq_buffer vertices, minkq_stream stream) {
  return guarded([&] {
    const minkq::Strided values = checked_async_vertices(scene, vertices, "minkq_scene_rebuild_async", true);
    scene->store->rebuild_async(values, stream);
  });
}

minkq_status minkq_scene_refit_swept_async(minkq_scene* scene, minkq_buffer x0, minkq_buffer x1, minkq_stream stream) {
  return guarded([&] {
    const char* call = "minkq_scene_refit_swept_async";
    const minkq::Strided start = checked_async_vertices(scene, x0, call, false, true, "x0");
    const minkq::Strided end = checked_async_vertices(scene, x1, call, false, true, "x1");
    scene->store->refit_swept_async(start, end, stream);
  });
}

minkq_status minkq_scene_rebuild_swept_async(minkq_scene* scene, minkq_buffer x0, minkq_buffer x1,
                                             minkq_stream stream) {
  return guarded([&] {
    const char* call = "minkq_scene_rebuild_swept_async";
    const minkq::Strided start = checked_async_vertices(scene, x0, call, true, true, "x0");
    const minkq::Strided end = checked_async_vertices(scene, x1, call, true, true, "x1");
    scene->store->rebuild_swept_async(start, end, stream);
  });
}

minkq_status minkq_scene_query_async(minkq_scene* scene, const minkq_query_desc* query, int32_t* out_pairs,
                                     size_t capacity, uint64_t* out_count, minkq_stream stream) {
  return guarded([&] {
    require(scene != nullptr, Status::kInvalidArgument, "scene is NULL");
    const minkq::QueryRequest request = checked_scene_request(scene, query, "query");
    const minkq::PairOutput out = checked_async_output(scene, query, out_pairs, capacity, out_count, "");
    scene->store->query_async(request, out, stream);
  });
}

minkq_status minkq_scene_query_vt_ee_async(minkq_scene* scene, const minkq_query_desc* vt_query,
                                           const minkq_query_desc* ee_query, int32_t* vt_pairs, size_t vt_capacity,
                                           uint64_t* vt_count, int32_t* ee_pairs, size_t ee_capacity,
                                           uint64_t* ee_count, minkq_stream stream) {
  return guarded([&] {
    const auto [vt, ee] = checked_vt_ee_requests(scene, vt_query, ee_query);
    const minkq::PairOutput vt_out = checked_async_output(scene, vt_query, vt_pairs, vt_capacity, vt_count, "vt_");
    const minkq::PairOutput ee_out = checked_async_output(scene, ee_query, ee_pairs, ee_capacity, ee_count, "ee_");
    require(vt_count != ee_count, Status::kInvalidArgument, "vt_count and ee_count are the same pointer");
    scene->store->query_vt_ee_async(vt, vt_out, ee, ee_out, stream);
  });
}

minkq_status minkq_scene_async_status(minkq_scene* scene, minkq_stream stream) {
  return guarded([&] {
    require(scene != nullptr, Status::kInvalidArgument, "scene is NULL");
    const minkq::PendingError pending = scene->store->take_pending_error(stream);
    if (pending.call == minkq::PendingError::kNone) return;
    using Call = minkq::PendingError::Call;
    const bool rebuild = pending.call == Call::kRebuild || pending.call == Call::kRebuildSwept;
    const bool swept = pending.call == Call::kRefitSwept || pending.call == Call::kRebuildSwept;
    const std::string call = std::string("minkq_scene_") + (rebuild ? "rebuild" : "refit") + (swept ? "_swept" : "") + "_async";
    fail(Status::kNonFinite, call + ": vertex " + std::to_string(pending.vertex) +
                                 (swept ? " has a non-finite coordinate (in x0 or x1); the scene kept its positions, at rest"
                                        : " has a non-finite coordinate; the scene kept its positions") +
                                 (rebuild ? " and built its trees for them" : ""));
  });
}

minkq_status minkq_result_create(minkq_result** out_result) {
  return guarded([&] {
    require(out_result != nullptr, Status::kInvalidArgument, "out_result is NULL");
    *out_result = new minkq_result();
  });
}
void minkq_result_release(minkq_result* result) { delete result; }
uint64_t minkq_result_count(const minkq_result* result) { return result ? result->count : 0; }
const int32_t* minkq_result_pairs(const minkq_result* result) { return result ? result->pairs.data() : nullptr; }
uint64_t minkq_result_digest(const minkq_result* result) { return result ? result->digest : 0; }
minkq_query_stats minkq_result_stats(const minkq_result* result) { return result ? result->stats : minkq_query_stats{}; }

minkq_status minkq_scene_query_result(minkq_scene* scene, const minkq_query_desc* query, minkq_result* result) {
  if (result == nullptr) {
    last_error = "result is NULL";
    return MINKQ_ERROR_INVALID_ARGUMENT;
  }
  return query_into_results<1>({result}, [&](std::array<minkq_query_info, 1>& info) {
    return minkq_scene_query(scene, query, result->pairs.data(), result->pairs.size() / 2, MINKQ_MEMORY_HOST,
                             &info[0]);
  });
}

minkq_status minkq_scene_query_vt_ee_result(minkq_scene* scene, const minkq_query_desc* vt_query,
                                            const minkq_query_desc* ee_query, minkq_result* vt_result,
                                            minkq_result* ee_result) {
  if (vt_result == nullptr || ee_result == nullptr || vt_result == ee_result) {
    last_error = vt_result == nullptr   ? "vt_result is NULL"
                 : ee_result == nullptr ? "ee_result is NULL"
                                        : "vt_result and ee_result are the same result";
    return MINKQ_ERROR_INVALID_ARGUMENT;
  }
  return query_into_results<2>({vt_result, ee_result}, [&](std::array<minkq_query_info, 2>& info) {
    return minkq_scene_query_vt_ee(scene, vt_query, ee_query, vt_result->pairs.data(), vt_result->pairs.size() / 2,
                                   ee_result->pairs.data(), ee_result->pairs.size() / 2, MINKQ_MEMORY_HOST, &info[0],
                                   &info[1]);
  });
}

minkq_status minkq_bvh_create(minkq_device* device, minkq_buffer boxes, minkq_bvh** out_bvh) {
  return guarded([&] {
    require(out_bvh != nullptr, Status::kInvalidArgument, "out_bvh is NULL");
    *out_bvh = nullptr;
    require(device != nullptr, Status::kInvalidArgument, "device is NULL");
    const minkq::Strided values = checked_buffer(device, boxes, 24, "boxes");
    require_finite(*device->backend, values, 6, "box");
    require_ordered_boxes(*device->backend, values);
    auto bvh = std::make_unique<minkq_bvh>();
    bvh->device = device;
    bvh->box_count = size_t(values.count);
    bvh->store = device->backend->create_box_store(values);
    *out_bvh = bvh.release();
  });
}

void minkq_bvh_release(minkq_bvh* bvh) { delete bvh; }

minkq_status minkq_bvh_refit(minkq_bvh* bvh, minkq_buffer boxes) {
  return guarded([&] {
    const minkq::Strided values = checked_new_boxes(bvh, boxes, "refit");  // checks bvh first
    bvh->store->refit(values);
  });
}

minkq_status minkq_bvh_rebuild(minkq_bvh* bvh, minkq_buffer boxes) {
  return guarded([&] {
    const minkq::Strided values = checked_new_boxes(bvh, boxes, "rebuild");  // checks bvh first
    bvh->store->rebuild(values);
  });
}

minkq_status minkq_bvh_tree_growth(const minkq_bvh* bvh, double* out_growth) {
  return guarded([&] {
    require(bvh != nullptr, Status::kInvalidArgument, "bvh is NULL");
    require(out_growth != nullptr, Status::kInvalidArgument, "out_growth is NULL");
    *out_growth = bvh->store->tree_growth();
  });
}

minkq_status minkq_bvh_query(minkq_bvh* bvh, const minkq_bvh_query_desc* query, int32_t* out_pairs, size_t capacity,
                             minkq_memory out_memory, minkq_query_info* info) {
  return guarded([&] {
    require(bvh != nullptr, Status::kInvalidArgument, "bvh is NULL");
    require(query != nullptr, Status::kInvalidArgument, "query is NULL");
    const int64_t shape = enum_value(query->shape), mode = enum_value(query->mode);
    require(shape >= MINKQ_SHAPE_SPHERE && shape <= MINKQ_SHAPE_BOX, Status::kInvalidArgument,
            "query->shape is not a minkq_shape value");
    require(mode >= MINKQ_MODE_BOX && mode <= MINKQ_MODE_CAPSULE_EXACT, Status::kInvalidArgument,
            "query->mode is not a minkq_mode value");
    require((query->flags & ~kKnownQueryFlags) == 0, Status::kInvalidArgument, "query->flags has unknown bits");
    require(!(query->flags & MINKQ_QUERY_LEAF_EXACT), Status::kInvalidArgument,
            "MINKQ_QUERY_LEAF_EXACT applies to mesh scenes only: a bvh's leaves are boxes");
    require(query->shape != MINKQ_SHAPE_CAPSULE || query->mode != MINKQ_MODE_SPHERE, Status::kInvalidArgument,
            "sphere mode needs point queries; use capsule_ray or capsule_exact for capsules");
    require(query->shape != MINKQ_SHAPE_BOX || query->mode == MINKQ_MODE_BOX, Status::kInvalidArgument,
            "box queries support only MINKQ_MODE_BOX");
    require_radius(query->radius);
    require(query->shape != MINKQ_SHAPE_BOX || query->radius == 0.0f, Status::kInvalidArgument,
            "box queries take radius 0 (radius " + format_float(query->radius) + "): grow the query boxes instead");
    minkq_device* device = bvh->device;
    const minkq::Strided first = checked_buffer(device, query->first, 12, "first");
    const minkq::Strided second = checked_buffer(device, query->second, 12, "second");
    const bool spheres = query->shape == MINKQ_SHAPE_SPHERE;
    require(spheres ? second.count == 0 : second.count == first.count, Status::kInvalidArgument,
            spheres ? "second must be empty for sphere queries"
                    : "second.count " + std::to_string(second.count) + " differs from first.count " +
                          std::to_string(first.count));
    require_finite(*device->backend, first, 3, "query point");
    require_finite(*device->backend, second, 3, "query point");
    const minkq::QueryKind kind = spheres ? minkq::QueryKind::kUserSpheres
                                          : (query->shape == MINKQ_SHAPE_CAPSULE ? minkq::QueryKind::kUserCapsules
                                                                                 : minkq::QueryKind::kUserBoxes);
    const minkq::QueryRequest request{kind, static_cast<minkq::Mode>(query->mode), 0u, query->radius, first, second};
    run_and_report(device, *bvh->store, request, query->flags, out_pairs, capacity, out_memory, info);
  });
}

}  // extern "C"
