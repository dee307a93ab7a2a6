// The C API fuzzer's Session: one input's sequence of calls, over the objects held across calls
// (State, capi_model.h), their arguments drawn by the Generator (capi_generator.h). One class;
// its ops are defined by family: devices and scenes in capi_scene_ops.cpp, the blocking scene
// queries in capi_query_ops.cpp, the BVH calls in capi_bvh_ops.cpp, the stream-ordered calls in
// capi_async_ops.cpp, the op dispatch (run) and the remaining calls (misc) in fuzz_capi.cpp.
#pragma once

#include <fuzzer/FuzzedDataProvider.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "capi_generator.h"
#include "capi_model.h"

namespace minkq::capi_fuzz {

// One geometry's description as drawn, with its buffers and the misuses they hold.
struct GeometryArgs {
  minkq_geometry_desc desc{};
  Buffer vertices, triangles, edges, thickness;
  Misuse misuse;
};

class Session {
 public:
  Session(FuzzedDataProvider& in) : in_(in), gen_(in) {}

  void run();  // the op dispatch (fuzz_capi.cpp)

 private:
  // ---- Devices and scenes (capi_scene_ops.cpp)
  minkq_device* device(int* index);
  void device_create();
  void device_release();
  void scene_create();
  void scene_release();
  SceneSlot* scene(bool* null_scene);
  SceneSlot* live_scene(bool* null_scene);
  SceneSlot* valid_scene();
  void scene_refit();

  // A tree-growth call on `handle` (NULL: a misuse), its out pointer sometimes NULL too: never
  // NaN or negative, and exactly 1 right after a successful rebuild.
  template <class Handle>
  void check_tree_growth(const char* call, minkq_status (*growth_of)(const Handle*, double*), const Handle* handle,
                         bool rebuilt) {
    const bool null_out = gen_.rarely();
    double growth = -1.0;
    Misuse m;
    m.add(handle == nullptr, MINKQ_ERROR_INVALID_ARGUMENT, "handle NULL");
    m.add(null_out, MINKQ_ERROR_INVALID_ARGUMENT, "out_growth NULL");
    const minkq_status status = growth_of(handle, null_out ? nullptr : &growth);
    expect(call, status, m);
    if (status == MINKQ_SUCCESS && (!(growth >= 0.0) || (rebuilt && growth != 1.0)))
      failure(std::string(call) + " returned " + std::to_string(growth));
  }

  // ---- Blocking scene queries (capi_query_ops.cpp)

  // The arguments of a scene query, with the misuses they contain.
  struct QueryArgs {
    minkq_query_desc desc{};
    bool null_desc = false;
    int kind = 0, mode = 0;
    uint32_t flags = 0;
    float r = 0;
    Misuse misuse;
  };
  QueryArgs query_args(const SceneSlot* s, bool null_scene, int want_kind = -1, bool async = false);
  size_t queries_of(const SceneSlot& s, int kind) const { return kind == MINKQ_QUERY_VT ? s.vertices : s.edges; }
  size_t prims_of(const SceneSlot& s, int kind) const { return kind == MINKQ_QUERY_VT ? s.triangles : s.edges; }

  // Output arguments: a buffer of exactly `capacity` pairs, or a declared size that must be rejected.
  struct Output {
    std::vector<int32_t> pairs;
    int32_t* data = nullptr;
    size_t capacity = 0;
    int memory = MINKQ_MEMORY_HOST;
    bool null_info = false;
    Misuse misuse;
  };
  Output output(uint64_t needed, bool own_memory = true);
  bool reference_count(minkq_scene* scene, const minkq_query_desc& d, uint64_t* count, std::vector<int32_t>* pairs);
  void scene_query();
  void scene_query_vt_ee();
  void scene_query_result();
  void scene_edges();

  // ---- BVH calls (capi_bvh_ops.cpp)
  void bvh_create();
  void bvh_refit();
  void bvh_query();

  // ---- Stream-ordered calls (capi_async_ops.cpp)
  minkq_stream stream();
  uint32_t reserve_flags();
  size_t reserve_capacity();
  void reserve_on(SceneSlot* s, bool null_scene, uint32_t flags, size_t capacity);
  void scene_reserve();
  void scene_refit_async();

  // An asynchronous query's outputs: exactly `capacity` pairs followed by guard words (all
  // preset), a count word, or declarations that must be rejected.
  static constexpr int32_t kGuard = -777;
  static constexpr size_t kGuardWords = 6;
  static constexpr uint64_t kCountSentinel = 0xDEADBEEFCAFEull;
  struct AsyncOutput {
    std::vector<int32_t> raw;  // 2 * capacity + kGuardWords (only the guards for declared-only capacities)
    int32_t* data = nullptr;
    size_t capacity = 0;
    bool declared_only = false;  // capacity not held: rejected
    Misuse misuse;
  };
  AsyncOutput async_output(uint64_t needed);
  void check_async_output(const char* call, bool ok, const AsyncOutput& o, const uint64_t* count_word,
                          uint64_t count_value, const SceneSlot& s, const QueryArgs& a, uint64_t needed,
                          const std::vector<int32_t>& expected);
  void async_desc_misuse(Misuse& m, const QueryArgs& a, const SceneSlot* s, bool null_scene, size_t capacity,
                         const char* which);
  void scene_query_async();
  void scene_query_async_on(SceneSlot* s, bool null_scene);
  void scene_query_vt_ee_async();
  void scene_async_status();
  void async_status_on(SceneSlot* s, bool null_scene);

  // ---- Scenes of many geometries (capi_geometry_ops.cpp): a scene made, used and released
  // within one op, so that the one-mesh ops' models never meet it
  void geometry_scene();
  minkq_status create_geometries(std::vector<GeometryArgs>& args, minkq_scene** out);
  void geometry_ranges(minkq_scene* scene, const std::vector<GeometryArgs>& args);
  void geometry_move(minkq_scene* scene, const std::vector<GeometryArgs>& args);

  // ---- The remaining calls: status names, NULL handles, results, versions, releases (fuzz_capi.cpp)
  void misc();

  FuzzedDataProvider& in_;
  Generator gen_;
  State st_;
};

}  // namespace minkq::capi_fuzz
