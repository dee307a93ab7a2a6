// C++ conveniences over the C API for the project's own C++ programs (the minkq CLI and the
// benchmarks): owning handles and a status check that throws with the library's message.
#pragma once

#include <memory>
#include <stdexcept>
#include <string>

#include "minkq.h"

namespace minkq::cxx {

inline void check(minkq_status status, const char* call) {
  if (status != MINKQ_SUCCESS)
    throw std::runtime_error(std::string(call) + " failed: " + minkq_status_name(status) + ": " +
                             minkq_last_error_message());
}

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

}  // namespace minkq::cxx
