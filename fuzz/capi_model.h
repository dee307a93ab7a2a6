// The C API fuzzer's model of the contract (capi/minkq.h): the misuses found in a call's
// arguments and the check of its status against them (expect), the objects held across calls
// (devices, scenes with their reservation and pending error, bvhs, results), the checks of a
// successful query's pairs and the digests of a scene's or bvh's state. Shared by the
// Session's ops (capi_session.h); see fuzz_capi.cpp for the contract model as a whole.
#pragma once

#include <xxhash.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <utility>
#include <vector>

#include "minkq.h"
#include "minkq.hpp"

// capi_shim.c: arguments passed exactly as C code does (enum fields holding any int).
extern "C" {
minkq_buffer shim_buffer(const void* data, size_t byte_stride, size_t count, int memory);
void shim_query_desc(minkq_query_desc* d, int kind, int mode, uint32_t flags, float radius);
void shim_bvh_query_desc(minkq_bvh_query_desc* d, int shape, int mode, uint32_t flags, float radius, minkq_buffer first,
                         minkq_buffer second);
minkq_status shim_scene_query(minkq_scene* scene, const minkq_query_desc* query, int32_t* out_pairs, size_t capacity,
                              int out_memory, minkq_query_info* info);
minkq_status shim_bvh_query(minkq_bvh* bvh, const minkq_bvh_query_desc* query, int32_t* out_pairs, size_t capacity,
                            int out_memory, minkq_query_info* info);
minkq_status shim_scene_query_vt_ee(minkq_scene* scene, const minkq_query_desc* vt_query,
                                    const minkq_query_desc* ee_query, int32_t* vt_pairs, size_t vt_capacity,
                                    int32_t* ee_pairs, size_t ee_capacity, int out_memory, minkq_query_info* vt_info,
                                    minkq_query_info* ee_info);
const char* shim_status_name(int status);
minkq_status shim_scene_geometry_range(const minkq_scene* scene, uint32_t geometry, int element, size_t* out_first,
                                       size_t* out_count);
}

namespace minkq::capi_fuzz {

constexpr size_t kMaxElements = size_t(INT32_MAX) - 1;  // 2^31 - 2, minkq.h's SIZE_OVERFLOW limit
inline uint64_t g_calls = 0, g_inputs = 0, g_errors = 0;
// Stream-ordered calls that got past the checks: refits/rebuilds with finite and with
// non-finite vertices, queries whose pairs fit and did not, pending errors reported.
inline uint64_t g_async_moves = 0, g_async_non_finite = 0, g_async_fit = 0, g_async_short = 0, g_async_pending = 0;
inline bool g_verbose = false;  // MINKQ_FUZZ_VERBOSE=1: print every input's calls
// MINKQ_FUZZ_INJECT=1 (self-test): the model records each pending error one vertex too far on,
// so the first NON_FINITE minkq_scene_async_status reports must fail the message check.
inline bool g_inject = false;

inline std::string log_text;
inline void note(const std::string& line) {
  if (log_text.size() < 20000) log_text += line + "\n";
}

[[noreturn]] inline void failure(const std::string& what) {
  std::fprintf(stderr, "\n==== minkq C API fuzzer: FAILURE ====\n%s\n---- calls of this input ----\n%s\n", what.c_str(),
               log_text.c_str());
  std::fflush(stderr);
  std::abort();
}

inline std::string name(minkq_status s) { return minkq_status_name(s); }

// The misuses found in one call's arguments, each with the status the contract gives it.
struct Misuse {
  std::vector<minkq_status> codes;
  std::string why;
  void add(bool present, minkq_status code, const std::string& what) {
    if (!present) return;
    codes.push_back(code);
    why += (why.empty() ? "" : "; ") + what;
  }
  void merge(const Misuse& other) {
    codes.insert(codes.end(), other.codes.begin(), other.codes.end());
    if (!other.why.empty()) why += (why.empty() ? "" : "; ") + other.why;
  }
  bool none() const { return codes.empty(); }
};

// Checks a status against the model; `clean` is the status expected without misuse.
inline void expect(const char* call, minkq_status got, const Misuse& misuse, minkq_status clean = MINKQ_SUCCESS) {
  ++g_calls;
  const std::string message = minkq_last_error_message();
  note(std::string(call) + " -> " + name(got) + (misuse.none() ? "" : "   [misuse: " + misuse.why + "]") +
       (message.empty() ? "" : "   \"" + message + "\""));
  if (misuse.none()) {
    if (got != clean) failure(std::string(call) + ": expected " + name(clean) + ", got " + name(got) + " (" + message + ")");
  } else {
    ++g_errors;
    if (std::find(misuse.codes.begin(), misuse.codes.end(), got) == misuse.codes.end())
      failure(std::string(call) + ": misuse (" + misuse.why + ") answered " + name(got));
  }
  if (got == MINKQ_SUCCESS && !message.empty()) failure(std::string(call) + ": success left an error message: " + message);
  if (got != MINKQ_SUCCESS && message.empty()) failure(std::string(call) + ": " + name(got) + " without a message");
}

// ---- Objects held across calls ----------------------------------------------------------------

// The pending error of a scene's asynchronous refits and rebuilds, as minkq.h defines it: the
// first non-finite vertex of the first failing call since the last minkq_scene_async_status.
struct PendingModel {
  int call = 0;  // 0 none, 1 minkq_scene_refit_async, 2 minkq_scene_rebuild_async
  int64_t vertex = -1;
};
struct SceneSlot {
  minkq_scene* handle = nullptr;
  int device = -1;
  uint32_t flags = 0;
  size_t vertices = 0, triangles = 0, edges = 0;
  // minkq_scene_reserve so far (reservations only grow): REFIT (or REBUILD) allows
  // refit_async, REBUILD rebuild_async; canonical asynchronous queries up to this capacity.
  bool reserved_refit = false, reserved_rebuild = false;
  size_t reserved_canonical = 0;
  PendingModel pending;

  // A scene just created on device slot `device`: its counts as the library reports them, no
  // reservation, no pending error.
  static SceneSlot of(minkq_scene* handle, int device, uint32_t flags) {
    SceneSlot slot;
    slot.handle = handle;
    slot.device = device;
    slot.flags = flags;
    slot.vertices = minkq_scene_vertex_count(handle);
    slot.triangles = minkq_scene_triangle_count(handle);
    slot.edges = minkq_scene_edge_count(handle);
    return slot;
  }
};
struct BvhSlot {
  minkq_bvh* handle = nullptr;
  int device = -1;
  size_t boxes = 0;
};

struct State {
  minkq_device* devices[2] = {nullptr, nullptr};
  SceneSlot scenes[3];
  BvhSlot bvhs[2];
  minkq_result* results[2] = {nullptr, nullptr};
  ~State() {
    for (auto& s : scenes) minkq_scene_release(s.handle);
    for (auto& b : bvhs) minkq_bvh_release(b.handle);
    for (auto* r : results) minkq_result_release(r);
    for (auto* d : devices) minkq_device_release(d);
  }
  bool device_in_use(int d) const {
    for (const auto& s : scenes)
      if (s.handle && s.device == d) return true;
    for (const auto& b : bvhs)
      if (b.handle && b.device == d) return true;
    return false;
  }
};

// Checks the pairs of a successful query: in range, ordered for EE, canonical when asked,
// no duplicates, digest as documented.
inline void check_pairs(const char* call, const int32_t* pairs, uint64_t count, size_t queries, size_t prims, bool ee,
                        uint32_t flags, uint64_t digest) {
  std::vector<std::pair<int32_t, int32_t>> list(count);
  for (uint64_t i = 0; i < count; ++i) {
    const int32_t q = pairs[2 * i], p = pairs[2 * i + 1];
    if (q < 0 || size_t(q) >= queries || p < 0 || size_t(p) >= prims || (ee && !(q < p)))
      failure(std::string(call) + ": invalid pair (" + std::to_string(q) + ", " + std::to_string(p) + ")");
    list[i] = {q, p};
  }
  const bool canonical = flags & (MINKQ_QUERY_CANONICAL | MINKQ_QUERY_DIGEST);
  if (canonical && !std::is_sorted(list.begin(), list.end())) failure(std::string(call) + ": canonical pairs not sorted");
  if ((flags & MINKQ_QUERY_DIGEST) && digest != XXH64(pairs, size_t(count) * 8, 0))
    failure(std::string(call) + ": digest is not XXH64 of the pairs");
  std::sort(list.begin(), list.end());
  if (std::adjacent_find(list.begin(), list.end()) != list.end()) failure(std::string(call) + ": duplicate pairs");
}

// A result for the fuzzer's own trusted queries (not the calls under test).
inline minkq::cxx::Result own_result() {
  minkq_result* r = nullptr;
  if (minkq_result_create(&r) != MINKQ_SUCCESS) failure("minkq_result_create");
  return minkq::cxx::Result(r);
}

// The digest of a fixed query: a scene's state, compared before and after a failed refit.
inline uint64_t scene_state(const SceneSlot& s) {
  const minkq::cxx::Result r = own_result();
  minkq_query_desc d;
  shim_query_desc(&d, (s.flags & MINKQ_SCENE_VT) ? MINKQ_QUERY_VT : MINKQ_QUERY_EE, MINKQ_MODE_BOX, MINKQ_QUERY_DIGEST,
                  0.5f);
  const minkq_status st = minkq_scene_query_result(s.handle, &d, r.get());
  const uint64_t digest = minkq_result_digest(r.get()) ^ minkq_result_count(r.get());
  if (st != MINKQ_SUCCESS) failure("state query failed: " + name(st));
  return digest;
}
// A fuller digest of a scene's state for the asynchronous calls: every kind the scene has, in
// box mode and in a finer mode with leaf-exact filtering, counts and digests of canonical pairs.
inline uint64_t scene_full_state(const SceneSlot& s) {
  const minkq::cxx::Result r = own_result();
  std::vector<uint64_t> parts;
  for (int kind = 0; kind < 2; ++kind) {
    if (!(s.flags & (kind == MINKQ_QUERY_VT ? MINKQ_SCENE_VT : MINKQ_SCENE_EE))) continue;
    for (int fine = 0; fine < 2; ++fine) {
      minkq_query_desc d;
      const int mode = !fine ? MINKQ_MODE_BOX : kind == MINKQ_QUERY_VT ? MINKQ_MODE_SPHERE : MINKQ_MODE_CAPSULE_EXACT;
      shim_query_desc(&d, kind, mode, MINKQ_QUERY_DIGEST | (fine ? MINKQ_QUERY_LEAF_EXACT : 0u), fine ? 0.25f : 0.5f);
      const minkq_status st = minkq_scene_query_result(s.handle, &d, r.get());
      if (st != MINKQ_SUCCESS) failure("state query failed: " + name(st));
      parts.push_back(minkq_result_digest(r.get()));
      parts.push_back(minkq_result_count(r.get()));
    }
  }
  return XXH64(parts.data(), parts.size() * sizeof(uint64_t), 0);
}
inline double scene_growth(const SceneSlot& s) {
  double g = -1.0;
  const minkq_status st = minkq_scene_tree_growth(s.handle, &g);
  if (st != MINKQ_SUCCESS) failure("minkq_scene_tree_growth failed: " + name(st));
  return g;
}

inline uint64_t bvh_state(const BvhSlot& b) {
  const float points[6] = {0, 0, 0, 1, 1, 1};
  minkq_bvh_query_desc d;
  shim_bvh_query_desc(&d, MINKQ_SHAPE_SPHERE, MINKQ_MODE_BOX, MINKQ_QUERY_DIGEST, 1.0f,
                      shim_buffer(points, 0, 2, MINKQ_MEMORY_HOST), shim_buffer(nullptr, 0, 0, MINKQ_MEMORY_HOST));
  minkq_query_info info{};
  std::vector<int32_t> out(2 * 2 * (b.boxes + 1));
  const minkq_status st = shim_bvh_query(b.handle, &d, out.data(), out.size() / 2, MINKQ_MEMORY_HOST, &info);
  if (st != MINKQ_SUCCESS) failure("bvh state query failed: " + name(st));
  return info.digest ^ info.count;
}

}  // namespace minkq::capi_fuzz
