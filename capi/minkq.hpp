// C++ conveniences over the C API (minkq.h), installed beside it and used by the project's own
// C++ programs (the CLI, the tests, the fuzzers and the benchmarks): owning handles, a status
// check that throws with the library's message, and small creation helpers. Header-only;
// nothing here is part of the ABI.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>

#include "minkq.h"

namespace minkq::cxx {

// A failed call: what was called, the status's name and the library's message.
class Error : public std::runtime_error {
 public:
  Error(minkq_status status, const std::string& call)
      : std::runtime_error(call + " failed: " + minkq_status_name(status) + ": " + minkq_last_error_message()),
        status_(status) {}
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
