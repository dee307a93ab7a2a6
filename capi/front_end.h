// The C ABI front end's shared parts (one translation unit per concern: minkq.cpp devices and
// errors, scene.cpp scenes and their updates, query.cpp queries and results, bvh.cpp the
// user-box BVH): the handle structs, error capture, and the argument checks whose messages name
// the offending element.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <new>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <xxhash.h>

#include "backend.h"
#include "minkq.h"

struct minkq_device {
  std::unique_ptr<minkq::Backend> backend;
  std::string name;
  minkq_backend kind;
};

struct minkq_scene {
  minkq_device* device;
  // The query kinds it answers (MINKQ_SCENE_VT ... EV), and MINKQ_SCENE_FLOAT64 when the vertices
  // of its moving geometries are doubles (those of whole-scene refits and rebuilds).
  uint32_t flags;
  size_t vertex_count, triangle_count, edge_count;  // all geometries'
  // One geometry's flags (minkq_geometry_flags) and its first global id and count of vertices,
  // triangles and edges (minkq_element order).
  struct Geometry {
    uint32_t flags;
    size_t first[3], count[3];
  };
  std::vector<Geometry> geometries;
  size_t moving_vertex_count;  // the vertices of whole-scene refits and rebuilds
  bool mixed_precision;        // moving geometries of both precisions: whole-scene moves refused
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

namespace minkq::capi {

using minkq::Failure;
using minkq::fail;
using minkq::Status;

// The calling thread's last error message (minkq_last_error_message); defined in minkq.cpp.
extern thread_local std::string last_error;

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

inline void require(bool condition, Status status, const std::string& message) {
  if (!condition) fail(status, message);
}

inline std::string format_float(float v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.9g", double(v));
  return text;
}

// Checks a buffer's pointer, stride, count and memory kind; returns it as a Strided view.
inline minkq::Strided checked_buffer(const minkq_device* device, const minkq_buffer& buffer, size_t element_size,
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

// The elements a tree may be built over (a scene's vertices, triangles and edges, a bvh's boxes)
// number at most minkq::kMaxTreePrimitives (bvh.h: the encoding of the tree's links). Checked at
// creation, before anything is read; refits and rebuilds must keep the count.
inline void require_tree_size(size_t count, const std::string& what) {
  require(count <= size_t(minkq::kMaxTreePrimitives), Status::kSizeOverflow,
          what + " " + std::to_string(count) + " exceeds the limit of " + std::to_string(minkq::kMaxTreePrimitives) +
              " (2^30 + 1) elements a tree holds");
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

inline void require_finite(minkq::Backend& backend, const minkq::Strided& values, int floats, const char* element) {
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
inline std::string vertices_named(const std::string& what) { return what == "vertices" ? what : what + " vertices"; }

// A scene's vertex buffer, checked: 3 floats each, or 3 doubles for a MINKQ_SCENE_FLOAT64 scene.
inline minkq::Strided checked_vertex_buffer(const minkq_device* device, const minkq_buffer& buffer, uint32_t scene_flags,
                                     const char* what = "vertices") {
  const bool float64 = (scene_flags & MINKQ_SCENE_FLOAT64) != 0;
  minkq::Strided values = checked_buffer(device, buffer, float64 ? 24 : 12, what);
  values.scalar = float64 ? minkq::Scalar::kFloat64 : minkq::Scalar::kFloat32;
  return values;
}

// `owner`: what holds the vertices, in messages ("scene", or "geometry" for one of several).
template <int N, class T>
void require_indices(const std::vector<T>& elements, size_t vertex_count, const char* element,
                     const char* owner = "scene") {
  for (size_t i = 0; i < elements.size(); ++i)
    for (int k = 0; k < N; ++k) {
      const int32_t v = elements[i].v[k];
      if (v < 0 || size_t(v) >= vertex_count)
        fail(Status::kIndexOutOfRange, std::string(element) + " " + std::to_string(i) + " references vertex " +
                                           std::to_string(v) + " but the " + owner + " has " +
                                           std::to_string(vertex_count) + " vertices");
    }
}

// User boxes need lo <= hi on every axis (validated on the host: device boxes are copied).
inline void require_ordered_boxes(minkq::Backend& backend, const minkq::Strided& values) {
  const std::vector<minkq::Box> boxes = host_copy<minkq::Box>(backend, values);
  for (size_t i = 0; i < boxes.size(); ++i) {
    const minkq::Box& b = boxes[i];
    require(b.lo.x <= b.hi.x && b.lo.y <= b.hi.y && b.lo.z <= b.hi.z, Status::kInvalidArgument,
            "box " + std::to_string(i) + " has lo > hi");
  }
}

inline void require_radius(float r) {
  require(std::isfinite(r), Status::kNonFinite, "radius " + format_float(r) + " is not finite");
  require(r >= 0.0f, Status::kInvalidArgument, "radius " + format_float(r) + " is negative");
}

constexpr uint32_t kKnownQueryFlags =
    MINKQ_QUERY_LEAF_EXACT | MINKQ_QUERY_CANONICAL | MINKQ_QUERY_DIGEST | MINKQ_QUERY_STATS | MINKQ_QUERY_COUNT;

// A count-only query (MINKQ_QUERY_COUNT) asks for no pair order or digest: those need pairs.
// `name` names the description in messages ("query", "vt_query").
inline void require_count_alone(uint32_t flags, const std::string& name) {
  require(!(flags & MINKQ_QUERY_COUNT) || !(flags & (MINKQ_QUERY_CANONICAL | MINKQ_QUERY_DIGEST)),
          Status::kInvalidArgument,
          name + "->flags asks for MINKQ_QUERY_COUNT with CANONICAL or DIGEST: a count-only query keeps no pairs to "
                 "order or hash");
}

// The parameter names of an output buffer, for messages.
struct OutputNames {
  std::string pairs, capacity, info;
};

// A pair buffer's pointer against its capacity (in pairs of 2 int32), named in messages.
inline void require_pair_capacity(const int32_t* pairs, size_t capacity, const std::string& pairs_name,
                           const std::string& capacity_name) {
  require(capacity == 0 || pairs != nullptr, Status::kInvalidArgument,
          pairs_name + " is NULL but " + capacity_name + " is " + std::to_string(capacity));
  require(capacity <= SIZE_MAX / (2 * sizeof(int32_t)), Status::kSizeOverflow,
          capacity_name + " " + std::to_string(capacity) + " pairs overflows the address space");
}

// A caller's output buffer, checked. A count-only query (MINKQ_QUERY_COUNT) ignores the pairs
// and capacity: its output has no room, so the backends only count.
inline minkq::PairOutput checked_output(const minkq_device* device, int32_t* out_pairs, size_t capacity,
                                        const minkq_memory& out_memory, uint32_t flags, const minkq_query_info* info,
                                        const OutputNames& name) {
  require(info != nullptr, Status::kInvalidArgument, name.info + " is NULL");
  const int64_t memory = enum_value(out_memory);
  require(memory == MINKQ_MEMORY_HOST || memory == MINKQ_MEMORY_DEVICE, Status::kInvalidArgument,
          "out_memory is not a minkq_memory value");
  require(out_memory == MINKQ_MEMORY_HOST || device->kind == MINKQ_BACKEND_CUDA, Status::kInvalidArgument,
          name.pairs + " is in device memory but the device is " + device->name);
  if (flags & MINKQ_QUERY_COUNT) return {nullptr, 0, static_cast<minkq::Memory>(out_memory), false};
  require_pair_capacity(out_pairs, capacity, name.pairs, name.capacity);
  if (out_memory == MINKQ_MEMORY_DEVICE && capacity > 0) device->backend->check_device_pointer(out_pairs, name.pairs);
  return {out_pairs, capacity, static_cast<minkq::Memory>(out_memory),
          (flags & (MINKQ_QUERY_DIGEST | MINKQ_QUERY_CANONICAL)) != 0};
}

// Fills info (zeroed before the query ran) from a query's count and work, and its digest when
// asked for and the pairs fit. Returns whether they fit (a count-only query's always do).
inline bool report(const minkq_device* device, const minkq::PairOutput& out, uint32_t flags, uint64_t count,
                   const minkq::WorkCounts& work, minkq_query_info* info) {
  info->count = count;
  info->stats = {work.nodes_visited, work.node_tests, work.primitive_tests, work.candidates};
  if (flags & MINKQ_QUERY_COUNT) return true;
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

inline std::string capacity_message(uint64_t count, size_t capacity) {
  return std::to_string(count) + " pairs found but the buffer holds " + std::to_string(capacity);
}

// Runs a request against a store with the common output checks, CAPACITY and digest.
inline void run_and_report(minkq_device* device, minkq::Store& store, const minkq::QueryRequest& request,
                           uint32_t flags, int32_t* out_pairs, size_t capacity, const minkq_memory& out_memory,
                           minkq_query_info* info) {
  const minkq::PairOutput out = checked_output(device, out_pairs, capacity, out_memory, flags, info,
                                                    {"out_pairs", "capacity", "info"});
  *info = minkq_query_info{};
  minkq::WorkCounts work;
  const uint64_t count = store.query(request, out, (flags & MINKQ_QUERY_STATS) ? &work : nullptr);
  if (!report(device, out, flags, count, work, info)) fail(Status::kCapacity, capacity_message(count, capacity));
}

// The memory asynchronous calls read and write: device memory on a CUDA device, host memory on
// the CPU.
inline minkq_memory async_memory(const minkq_device* device) {
  return device->kind == MINKQ_BACKEND_CUDA ? MINKQ_MEMORY_DEVICE : MINKQ_MEMORY_HOST;
}

}  // namespace minkq::capi
