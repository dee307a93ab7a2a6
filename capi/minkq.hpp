// The C++ interface over the C API (minkq.h), installed beside it; header-only, C++17, nothing
// here is part of the ABI.
//   minkq::api   classes for users: Device, Scene (one mesh, or many geometries described by
//                GeometryDesc), Bvh; queries return std::vector<Pair> and take View<T>, a
//                span-like view of a std::vector, std::array, C array or pointer + count; every
//                failure throws minkq::cxx::Error (minkq::api::Error), carrying the status and
//                the library's message. The stream-ordered calls are thin wrappers.
//   minkq::cxx   what the project's own C++ programs use (the CLI, the tests, the fuzzers and the
//                benchmarks): owning handles of the C objects, check(), creation helpers.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "minkq.h"

namespace minkq::cxx {

// A failed call: what was called, the status's name and the library's message.
class Error : public std::runtime_error {
 public:
  Error(minkq_status status, const std::string& call)
      : Error(status, call, minkq_last_error_message()) {}
  // A failure the wrapper finds itself, before calling the library (message: what is wrong).
  Error(minkq_status status, const std::string& call, const std::string& message)
      : std::runtime_error(call + " failed: " + minkq_status_name(status) + ": " + message), status_(status) {}
  minkq_status status() const { return status_; }

 private:
  minkq_status status_;
};

// Throws Error unless status is MINKQ_SUCCESS.
inline void check(minkq_status status, const char* call) {
  if (status != MINKQ_SUCCESS) throw Error(status, call);
}

// Owning handles: each releases its object (minkq_*_release) when it goes.
struct Release {
  void operator()(minkq_device* d) const { minkq_device_release(d); }
  void operator()(minkq_scene* s) const { minkq_scene_release(s); }
  void operator()(minkq_result* r) const { minkq_result_release(r); }
  void operator()(minkq_bvh* b) const { minkq_bvh_release(b); }
};
using Device = std::unique_ptr<minkq_device, Release>;
using Scene = std::unique_ptr<minkq_scene, Release>;
using Result = std::unique_ptr<minkq_result, Release>;
using Bvh = std::unique_ptr<minkq_bvh, Release>;

// `count` records in host memory, `stride` bytes apart (0: packed).
inline minkq_buffer host_buffer(const void* data, size_t count, size_t stride = 0) {
  return minkq_buffer{data, stride, count, MINKQ_MEMORY_HOST};
}

// ---- Creation (each throws Error on failure) -------------------------------------------------

// spec: "cpu", "cuda", "cuda:N" or "auto" (minkq_device_create).
inline Device open_device(const std::string& spec) {
  minkq_device* d = nullptr;
  check(minkq_device_create(spec.c_str(), &d), ("minkq_device_create(\"" + spec + "\")").c_str());
  return Device(d);
}

inline Result new_result() {
  minkq_result* r = nullptr;
  check(minkq_result_create(&r), "minkq_result_create");
  return Result(r);
}

inline Scene new_scene(minkq_device* device, const minkq_scene_desc& desc) {
  minkq_scene* s = nullptr;
  check(minkq_scene_create(device, &desc, &s), "minkq_scene_create");
  return Scene(s);
}

// A scene of packed host vertices (3 floats each) and triangles (3 int32 each), edges derived
// by the library; by default VT + EE with incident pairs dropped.
inline Scene new_mesh_scene(minkq_device* device, const float* xyz, size_t vertex_count, const int32_t* tris,
                            size_t triangle_count,
                            uint32_t flags = MINKQ_SCENE_VT | MINKQ_SCENE_EE | MINKQ_SCENE_DROP_INCIDENT) {
  minkq_scene_desc desc{};
  desc.flags = flags;
  desc.vertices = host_buffer(xyz, vertex_count, 3 * sizeof(float));
  desc.triangles = host_buffer(tris, triangle_count, 3 * sizeof(int32_t));
  desc.edges = host_buffer(nullptr, 0);
  return new_scene(device, desc);
}

// A BVH over user boxes (6 floats each: lo xyz, hi xyz).
inline Bvh new_bvh(minkq_device* device, minkq_buffer boxes) {
  minkq_bvh* b = nullptr;
  check(minkq_bvh_create(device, boxes, &b), "minkq_bvh_create");
  return Bvh(b);
}

}  // namespace minkq::cxx

// ---- minkq::api: the C++ classes ------------------------------------------------------------
namespace minkq::api {

using Error = cxx::Error;

// A pair of element ids, laid out as the C API's two int32: (vertex, triangle) for VT, (e, f)
// with e < f for EE, (v, w) with v < w for VV, (vertex, edge) for EV, (query, box) for a Bvh.
struct Pair {
  int32_t first, second;
  friend bool operator==(const Pair& a, const Pair& b) { return a.first == b.first && a.second == b.second; }
  friend bool operator!=(const Pair& a, const Pair& b) { return !(a == b); }
  friend bool operator<(const Pair& a, const Pair& b) {
    return a.first < b.first || (a.first == b.first && a.second < b.second);
  }
};
static_assert(sizeof(Pair) == 2 * sizeof(int32_t), "Pair is the C API's two int32");

// A read-only view of `size()` values of T in host memory (std::span's role in C++17): from a
// std::vector, a std::array, a C array, or a pointer and a count. It does not own the values;
// they must outlive the call it is given to.
template <class T>
class View {
 public:
  View() = default;
  View(const T* data, size_t size) : data_(data), size_(size) {}
  View(const std::vector<T>& v) : data_(v.data()), size_(v.size()) {}  // NOLINT: implicit, as span's
  template <size_t N>
  View(const std::array<T, N>& a) : data_(a.data()), size_(N) {}  // NOLINT
  template <size_t N>
  View(const T (&a)[N]) : data_(a), size_(N) {}  // NOLINT
  const T* data() const { return data_; }
  size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  const T* begin() const { return data_; }
  const T* end() const { return data_ + size_; }
  const T& operator[](size_t i) const { return data_[i]; }

 private:
  const T* data_ = nullptr;
  size_t size_ = 0;
};

namespace detail {
// A host buffer of `view.size() / width` records of `width` values each; a size that is not a
// multiple of `width` is an INVALID_ARGUMENT error naming `call` and `what`.
template <class T>
minkq_buffer records(View<T> view, size_t width, const char* call, const char* what) {
  if (view.size() % width != 0)
    throw Error(MINKQ_ERROR_INVALID_ARGUMENT, call,
                std::string(what) + " hold " + std::to_string(view.size()) + " values, not a multiple of " +
                    std::to_string(width));
  return minkq_buffer{view.data(), width * sizeof(T), view.size() / width, MINKQ_MEMORY_HOST};
}
// Pairs of a minkq_result, copied out.
inline std::vector<Pair> result_pairs(const minkq_result* r) {
  const uint64_t n = minkq_result_count(r);
  const int32_t* p = minkq_result_pairs(r);
  std::vector<Pair> out(n);
  for (uint64_t i = 0; i < n; ++i) out[i] = Pair{p[2 * i], p[2 * i + 1]};
  return out;
}
// Runs `call(pairs, capacity, info)` into `out`, reusing its storage: with out's capacity first,
// then, on CAPACITY, with room for the exact count. `out` ends with the pairs found.
template <class Call>
minkq_query_info into(std::vector<Pair>& out, const char* name, Call&& call) {
  minkq_query_info info{};
  out.resize(out.capacity());
  minkq_status status = call(reinterpret_cast<int32_t*>(out.data()), out.size(), &info);
  if (status == MINKQ_ERROR_CAPACITY) {
    out.resize(size_t(info.count));
    status = call(reinterpret_cast<int32_t*>(out.data()), out.size(), &info);
  }
  if (status != MINKQ_SUCCESS) out.clear();
  cxx::check(status, name);
  out.resize(size_t(info.count));
  return info;
}
}  // namespace detail

// A device: "cpu", "cuda", "cuda:N" or "auto" (minkq_device_create). Scenes and Bvhs keep a
// pointer to it: it must outlive them.
class Device {
 public:
  explicit Device(const std::string& spec = "auto") : handle_(cxx::open_device(spec)) {}
  minkq_device* get() const { return handle_.get(); }
  minkq_backend backend() const { return minkq_device_backend(get()); }
  std::string name() const { return minkq_device_name(get()); }

 private:
  cxx::Device handle_;
};

// One query of a scene: its kind, radius, node test and flags (minkq_query_flags), with box,
// no flags by default: scene.query({MINKQ_QUERY_EE, 0.01f}).
struct Query {
  minkq_query_kind kind = MINKQ_QUERY_VT;
  float radius = 0;
  minkq_mode mode = MINKQ_MODE_BOX;
  uint32_t flags = 0;
  minkq_query_desc desc() const { return minkq_query_desc{kind, mode, flags, radius}; }
};

// One geometry of a scene of many, over minkq_geometry_desc (defaults of
// minkq_geometry_desc_init: VT + EE, self pairs with incident ones dropped, world 0, group 1,
// every mask bit). The views are read when the scene is created: keep their data alive till then.
class GeometryDesc {
 public:
  GeometryDesc() { minkq_geometry_desc_init(&d_); }
  // xyz per vertex: 3 floats, or 3 doubles (MINKQ_GEOMETRY_FLOAT64).
  GeometryDesc& vertices(View<float> xyz) {
    d_.vertices = detail::records(xyz, 3, "GeometryDesc", "vertices");
    return set_flag(MINKQ_GEOMETRY_FLOAT64, false);
  }
  GeometryDesc& vertices(View<double> xyz) {
    d_.vertices = detail::records(xyz, 3, "GeometryDesc", "vertices");
    return set_flag(MINKQ_GEOMETRY_FLOAT64, true);
  }
  GeometryDesc& triangles(View<int32_t> tris) { return d_.triangles = detail::records(tris, 3, "GeometryDesc", "triangles"), *this; }
  GeometryDesc& edges(View<int32_t> edges) { return d_.edges = detail::records(edges, 2, "GeometryDesc", "edges"), *this; }
  GeometryDesc& thickness(View<float> t) { return d_.thickness = detail::records(t, 1, "GeometryDesc", "thickness"), *this; }
  GeometryDesc& kinds(uint32_t scene_kinds) { return d_.kinds = scene_kinds, *this; }  // MINKQ_SCENE_VT | _EE | _VV | _EV
  GeometryDesc& self(bool on) { return set_flag(MINKQ_GEOMETRY_SELF, on); }
  GeometryDesc& drop_incident(bool on) { return set_flag(MINKQ_GEOMETRY_DROP_INCIDENT, on); }
  GeometryDesc& is_static(bool on) { return set_flag(MINKQ_GEOMETRY_STATIC, on); }
  GeometryDesc& world(int32_t w) { return d_.world = w, *this; }
  GeometryDesc& group(uint32_t bits) { return d_.group = bits, *this; }
  GeometryDesc& mask(uint32_t bits) { return d_.mask = bits, *this; }
  const minkq_geometry_desc& desc() const { return d_; }

 private:
  GeometryDesc& set_flag(uint32_t flag, bool on) { return d_.flags = on ? d_.flags | flag : d_.flags & ~flag, *this; }
  minkq_geometry_desc d_;
};

// A first id and a count: a geometry's vertices, triangles or edges in the scene's numbering.
struct Range {
  size_t first = 0, count = 0;
};

// An element of a scene of many geometries as its geometry sees it: the geometry and the
// element's id within it (Scene::locate).
struct Local {
  uint32_t geometry = 0;
  size_t id = 0;
};

// The pairs of a VT and an EE query run together (Scene::query_vt_ee).
struct VtEePairs {
  std::vector<Pair> vt, ee;
};

// A scene (minkq_scene): one mesh, or many geometries. Move-only; releases the scene when it goes.
// One scene must not be used by two threads at once (minkq.h), so its queries are not const.
class Scene {
 public:
  static constexpr uint32_t kMeshFlags = MINKQ_SCENE_VT | MINKQ_SCENE_EE | MINKQ_SCENE_DROP_INCIDENT;
  // One mesh: vertices (3 floats or, adding MINKQ_SCENE_FLOAT64, 3 doubles each), triangles (3
  // int32 each), edges (2 int32 each; empty: derived from the triangles); minkq_scene_flags.
  Scene(const Device& device, View<float> xyz, View<int32_t> tris, uint32_t flags = kMeshFlags,
        View<int32_t> edges = {})
      : Scene(device, detail::records(xyz, 3, "minkq_scene_create", "vertices"), tris, flags, edges) {}
  Scene(const Device& device, View<double> xyz, View<int32_t> tris, uint32_t flags = kMeshFlags,
        View<int32_t> edges = {})
      : Scene(device, detail::records(xyz, 3, "minkq_scene_create", "vertices"), tris, flags | MINKQ_SCENE_FLOAT64,
              edges) {}
  // Many geometries (minkq_scene_create_geometries), numbered in the order given.
  Scene(const Device& device, const std::vector<GeometryDesc>& geometries) {
    std::vector<minkq_geometry_desc> descs;
    for (const GeometryDesc& g : geometries) descs.push_back(g.desc());
    minkq_scene* s = nullptr;
    cxx::check(minkq_scene_create_geometries(device.get(), descs.data(), descs.size(), &s),
               "minkq_scene_create_geometries");
    handle_.reset(s);
  }
  minkq_scene* get() const { return handle_.get(); }

  size_t vertex_count() const { return minkq_scene_vertex_count(get()); }
  size_t triangle_count() const { return minkq_scene_triangle_count(get()); }
  size_t edge_count() const { return minkq_scene_edge_count(get()); }
  // The edges, (lower, higher) vertex id each, in the scene's numbering.
  std::vector<Pair> edges() const {
    std::vector<Pair> e(edge_count());
    cxx::check(minkq_scene_edges(get(), reinterpret_cast<int32_t*>(e.data()), e.size()), "minkq_scene_edges");
    return e;
  }
  uint32_t geometry_count() const { return minkq_scene_geometry_count(get()); }
  Range geometry_range(uint32_t geometry, minkq_element element) const {
    Range r;
    cxx::check(minkq_scene_geometry_range(get(), geometry, element, &r.first, &r.count), "minkq_scene_geometry_range");
    return r;
  }
  // Which geometry a vertex, triangle or edge id of the scene's numbering (a pair's first or
  // second) belongs to, and its id there: a binary search over the geometries' ranges, which
  // follow one another in geometry order. An id past the scene's elements is INVALID_ARGUMENT.
  Local locate(minkq_element element, int64_t id) const {
    uint32_t lo = 0, hi = geometry_count();  // the answer is the last geometry starting at or before id
    while (hi - lo > 1) {
      const uint32_t mid = lo + (hi - lo) / 2;
      (int64_t(geometry_range(mid, element).first) <= id ? lo : hi) = mid;
    }
    const Range r = geometry_range(lo, element);
    if (id < int64_t(r.first) || id - int64_t(r.first) >= int64_t(r.count))
      throw Error(MINKQ_ERROR_INVALID_ARGUMENT, "minkq::api::Scene::locate",
                  "id " + std::to_string(id) + " is not an element of the scene (" +
                      std::to_string(r.first + r.count) + " of this kind)");
    return Local{lo, size_t(id - int64_t(r.first))};
  }
  bool is_swept() const { return minkq_scene_is_swept(get()) != 0; }
  double tree_growth() const {
    double g = 0;
    cxx::check(minkq_scene_tree_growth(get(), &g), "minkq_scene_tree_growth");
    return g;
  }

  // New positions (3 floats, or 3 doubles on a float64 scene, per vertex) of every vertex that
  // moves (minkq_scene_refit and the rest); the swept forms take both ends of the step.
  void refit(View<float> xyz) { move(minkq_scene_refit, "minkq_scene_refit", xyz); }
  void refit(View<double> xyz) { move(minkq_scene_refit, "minkq_scene_refit", xyz); }
  void rebuild(View<float> xyz) { move(minkq_scene_rebuild, "minkq_scene_rebuild", xyz); }
  void rebuild(View<double> xyz) { move(minkq_scene_rebuild, "minkq_scene_rebuild", xyz); }
  void refit_swept(View<float> x0, View<float> x1) { move(minkq_scene_refit_swept, "minkq_scene_refit_swept", x0, x1); }
  void refit_swept(View<double> x0, View<double> x1) { move(minkq_scene_refit_swept, "minkq_scene_refit_swept", x0, x1); }
  void rebuild_swept(View<float> x0, View<float> x1) { move(minkq_scene_rebuild_swept, "minkq_scene_rebuild_swept", x0, x1); }
  void rebuild_swept(View<double> x0, View<double> x1) { move(minkq_scene_rebuild_swept, "minkq_scene_rebuild_swept", x0, x1); }
  // One geometry's new positions (its vertex count and precision); the others are not touched.
  void geometry_refit(uint32_t g, View<float> xyz) { move(minkq_scene_geometry_refit, "minkq_scene_geometry_refit", g, xyz); }
  void geometry_refit(uint32_t g, View<double> xyz) { move(minkq_scene_geometry_refit, "minkq_scene_geometry_refit", g, xyz); }
  void geometry_rebuild(uint32_t g, View<float> xyz) { move(minkq_scene_geometry_rebuild, "minkq_scene_geometry_rebuild", g, xyz); }
  void geometry_rebuild(uint32_t g, View<double> xyz) { move(minkq_scene_geometry_rebuild, "minkq_scene_geometry_rebuild", g, xyz); }
  void geometry_refit_swept(uint32_t g, View<float> x0, View<float> x1) {
    move(minkq_scene_geometry_refit_swept, "minkq_scene_geometry_refit_swept", g, x0, x1);
  }
  void geometry_refit_swept(uint32_t g, View<double> x0, View<double> x1) {
    move(minkq_scene_geometry_refit_swept, "minkq_scene_geometry_refit_swept", g, x0, x1);
  }
  void geometry_rebuild_swept(uint32_t g, View<float> x0, View<float> x1) {
    move(minkq_scene_geometry_rebuild_swept, "minkq_scene_geometry_rebuild_swept", g, x0, x1);
  }
  void geometry_rebuild_swept(uint32_t g, View<double> x0, View<double> x1) {
    move(minkq_scene_geometry_rebuild_swept, "minkq_scene_geometry_rebuild_swept", g, x0, x1);
  }

  // The pairs of a query (minkq_scene_query; CANONICAL in q.flags sorts them).
  std::vector<Pair> query(const Query& q) {
    cxx::Result r = cxx::new_result();
    const minkq_query_desc d = q.desc();
    cxx::check(minkq_scene_query_result(get(), &d, r.get()), "minkq_scene_query_result");
    return detail::result_pairs(r.get());
  }
  // The pairs of a query into `out`, whose storage is reused and grown as needed; returns the
  // count and the digest and stats q.flags ask for (MINKQ_QUERY_DIGEST, MINKQ_QUERY_STATS).
  minkq_query_info query(const Query& q, std::vector<Pair>& out) {
    const minkq_query_desc d = q.desc();
    return detail::into(out, "minkq_scene_query", [&](int32_t* p, size_t capacity, minkq_query_info* info) {
      return minkq_scene_query(get(), &d, p, capacity, MINKQ_MEMORY_HOST, info);
    });
  }
  // The number of pairs only (MINKQ_QUERY_COUNT), with the stats when q.flags ask for them.
  uint64_t count(const Query& q, minkq_query_stats* stats = nullptr) {
    minkq_query_desc d = q.desc();
    d.flags |= MINKQ_QUERY_COUNT;
    minkq_query_info info{};
    cxx::check(minkq_scene_query(get(), &d, nullptr, 0, MINKQ_MEMORY_HOST, &info), "minkq_scene_query");
    if (stats) *stats = info.stats;
    return info.count;
  }
  // A VT and an EE query in one pass (minkq_scene_query_vt_ee).
  VtEePairs query_vt_ee(const Query& vt, const Query& ee) {
    cxx::Result rv = cxx::new_result(), re = cxx::new_result();
    const minkq_query_desc dv = vt.desc(), de = ee.desc();
    cxx::check(minkq_scene_query_vt_ee_result(get(), &dv, &de, rv.get(), re.get()), "minkq_scene_query_vt_ee_result");
    return VtEePairs{detail::result_pairs(rv.get()), detail::result_pairs(re.get())};
  }

  // ---- Stream-ordered calls: thin wrappers, buffers as the C calls take them (device memory
  // on CUDA); each throws Error on a status other than MINKQ_SUCCESS.
  void reserve(uint32_t reserve_flags, size_t canonical_capacity = 0) {
    cxx::check(minkq_scene_reserve(get(), reserve_flags, canonical_capacity), "minkq_scene_reserve");
  }
  void refit_async(minkq_buffer xyz, minkq_stream stream) {
    cxx::check(minkq_scene_refit_async(get(), xyz, stream), "minkq_scene_refit_async");
  }
  void rebuild_async(minkq_buffer xyz, minkq_stream stream) {
    cxx::check(minkq_scene_rebuild_async(get(), xyz, stream), "minkq_scene_rebuild_async");
  }
  void refit_swept_async(minkq_buffer x0, minkq_buffer x1, minkq_stream stream) {
    cxx::check(minkq_scene_refit_swept_async(get(), x0, x1, stream), "minkq_scene_refit_swept_async");
  }
  void rebuild_swept_async(minkq_buffer x0, minkq_buffer x1, minkq_stream stream) {
    cxx::check(minkq_scene_rebuild_swept_async(get(), x0, x1, stream), "minkq_scene_rebuild_swept_async");
  }
  void query_async(const Query& q, int32_t* pairs, size_t capacity, uint64_t* count, minkq_stream stream) {
    const minkq_query_desc d = q.desc();
    cxx::check(minkq_scene_query_async(get(), &d, pairs, capacity, count, stream), "minkq_scene_query_async");
  }
  void query_vt_ee_async(const Query& vt, const Query& ee, int32_t* vt_pairs, size_t vt_capacity, uint64_t* vt_count,
                         int32_t* ee_pairs, size_t ee_capacity, uint64_t* ee_count, minkq_stream stream) {
    const minkq_query_desc dv = vt.desc(), de = ee.desc();
    cxx::check(minkq_scene_query_vt_ee_async(get(), &dv, &de, vt_pairs, vt_capacity, vt_count, ee_pairs, ee_capacity,
                                             ee_count, stream),
               "minkq_scene_query_vt_ee_async");
  }
  // Waits for the stream's work and throws the scene's pending error, if any.
  void async_status(minkq_stream stream) { cxx::check(minkq_scene_async_status(get(), stream), "minkq_scene_async_status"); }

 private:
  Scene(const Device& device, minkq_buffer vertices, View<int32_t> tris, uint32_t flags, View<int32_t> edges) {
    minkq_scene_desc desc{};
    desc.flags = flags;
    desc.vertices = vertices;
    desc.triangles = detail::records(tris, 3, "minkq_scene_create", "triangles");
    desc.edges = detail::records(edges, 2, "minkq_scene_create", "edges");
    handle_ = cxx::new_scene(device.get(), desc);
  }
  // call(scene, vertex buffers...) or call(scene, g, vertex buffers...), checked.
  template <class Call, class... T>
  void move(Call call, const char* name, View<T>... xyz) {
    cxx::check(call(get(), detail::records(xyz, 3, name, "vertices")...), name);
  }
  template <class Call, class... T>
  void move(Call call, const char* name, uint32_t g, View<T>... xyz) {
    cxx::check(call(get(), g, detail::records(xyz, 3, name, "vertices")...), name);
  }
  cxx::Scene handle_;
};

// A BVH over boxes (minkq_bvh), each 6 floats: lo x, y, z, hi x, y, z. Move-only.
class Bvh {
 public:
  Bvh(const Device& device, View<float> boxes) : handle_(cxx::new_bvh(device.get(), boxes_of(boxes, "minkq_bvh_create"))) {}
  minkq_bvh* get() const { return handle_.get(); }
  void refit(View<float> boxes) { cxx::check(minkq_bvh_refit(get(), boxes_of(boxes, "minkq_bvh_refit")), "minkq_bvh_refit"); }
  void rebuild(View<float> boxes) { cxx::check(minkq_bvh_rebuild(get(), boxes_of(boxes, "minkq_bvh_rebuild")), "minkq_bvh_rebuild"); }
  double tree_growth() const {
    double g = 0;
    cxx::check(minkq_bvh_tree_growth(get(), &g), "minkq_bvh_tree_growth");
    return g;
  }
  // (query, box) pairs of spheres (centres: 3 floats each) within `radius` of a box; modes box, sphere.
  std::vector<Pair> spheres(View<float> centres, float radius, minkq_mode mode = MINKQ_MODE_BOX, uint32_t flags = 0) {
    return run(MINKQ_SHAPE_SPHERE, mode, flags, radius, centres, {});
  }
  // Segments a[i] -> b[i] (3 floats per point) within `radius`; modes box, capsule_ray, capsule_exact.
  std::vector<Pair> capsules(View<float> a, View<float> b, float radius, minkq_mode mode = MINKQ_MODE_BOX,
                             uint32_t flags = 0) {
    return run(MINKQ_SHAPE_CAPSULE, mode, flags, radius, a, b);
  }
  // Boxes with opposite corners a[i] and b[i] that overlap a box.
  std::vector<Pair> boxes(View<float> a, View<float> b, uint32_t flags = 0) {
    return run(MINKQ_SHAPE_BOX, MINKQ_MODE_BOX, flags, 0, a, b);
  }

 private:
  static minkq_buffer boxes_of(View<float> boxes, const char* call) { return detail::records(boxes, 6, call, "boxes"); }
  std::vector<Pair> run(minkq_shape shape, minkq_mode mode, uint32_t flags, float radius, View<float> first,
                        View<float> second) {
    minkq_bvh_query_desc d{shape, mode, flags, radius, detail::records(first, 3, "minkq_bvh_query", "query points"),
                           detail::records(second, 3, "minkq_bvh_query", "query points")};
    std::vector<Pair> out;
    detail::into(out, "minkq_bvh_query", [&](int32_t* p, size_t capacity, minkq_query_info* info) {
      return minkq_bvh_query(get(), &d, p, capacity, MINKQ_MEMORY_HOST, info);
    });
    return out;
  }
  cxx::Bvh handle_;
};

}  // namespace minkq::api
