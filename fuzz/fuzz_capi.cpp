// C API fuzzer: random call sequences with random, often wrong, arguments (null pointers, NaN
// and infinite coordinates and radii, wrong counts and strides, overflowing sizes, out-of-range
// indices and enum values, tiny output buffers, refits and rebuilds with another vertex count,
// tree growth, BVH calls), under ASan, UBSan and LSan. Every buffer the harness passes is allocated to exactly the bytes
// it declares, so a read or write past it is an ASan report; buffers that declare more than
// they hold are passed only where the declaration itself must be rejected.
//
// A model of the documented contract (capi/minkq.h) lists, for each call, the misuses in its
// arguments; the call must return one of their codes (any one: the order of checks is not part
// of the contract), or MINKQ_SUCCESS (MINKQ_ERROR_CAPACITY where the output is too small) when
// there is none. Failed calls must leave a message, successful ones none; a failed refit or
// rebuild must leave the previous positions; successful queries must return valid, canonical, duplicate-free
// pairs whose count and digest match the library-owned result path.
//
// The stream-ordered calls (minkq_scene_reserve, the *_async calls, minkq_scene_async_status)
// are about 30% of the ops. The model keeps each scene's reservation and pending error (the
// call and first non-finite vertex of the first failing asynchronous refit or rebuild since the
// last status call); asynchronous refits and rebuilds must give what the blocking call with the
// same vertices gives, asynchronous queries the blocking query's count and pairs, within their
// capacity (guard words after it), and the status call the modelled error once.
//
// The parts: capi_model.h (the misuse model and expect, the objects held across calls, pair
// checks and state digests), capi_generator.h (buffers and the argument generator),
// capi_session.h (the Session, one input's calls), its ops in capi_scene_ops.cpp,
// capi_query_ops.cpp, capi_bvh_ops.cpp and capi_async_ops.cpp; this file holds the op
// dispatch, the remaining calls (misc) and the libFuzzer entry points.
#include <fuzzer/FuzzedDataProvider.h>
#include <tbb/global_control.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>

#include "capi_session.h"

namespace minkq::capi_fuzz {

void Session::run() {
  const int ops = in_.ConsumeIntegralInRange<int>(1, 40);
  for (int i = 0; i < ops && in_.remaining_bytes() > 0; ++i) {
    // 0-13: the blocking calls; 14-19 (30%): the stream-ordered ones.
    switch (gen_.choice(20)) {
      case 0: device_create(); break;
      case 1: device_release(); break;
      case 2: case 3: scene_create(); break;
      case 4: scene_release(); break;
      case 5: scene_refit(); break;
      case 6: case 7: scene_query(); break;
      case 8:
        if (gen_.choice(2)) scene_query_result(); else scene_query_vt_ee();
        break;
      case 9:
        if (gen_.choice(2)) scene_edges(); else geometry_scene();
        break;
      case 10: bvh_create(); break;
      case 11: bvh_refit(); break;
      case 12: bvh_query(); break;
      case 13: misc(); break;
      case 14: scene_reserve(); break;
      case 15: case 16: scene_refit_async(); break;
      case 17: scene_query_async(); break;
      case 18:
        if (gen_.choice(2)) scene_query_async(); else scene_query_vt_ee_async();
        break;
      default: scene_async_status(); break;
    }
  }
}

void Session::misc() {
  switch (gen_.choice(6)) {
    case 0: {
      const int status = gen_.choice(3) == 0 ? in_.ConsumeIntegral<int>() : gen_.choice(12);
      const char* text = shim_status_name(status);
      if (text == nullptr || *text == 0) failure("minkq_status_name returned nothing");
      note(std::string("minkq_status_name(") + std::to_string(status) + ") = " + text);
      break;
    }
    case 1:
      if (minkq_scene_vertex_count(nullptr) || minkq_scene_triangle_count(nullptr) || minkq_scene_edge_count(nullptr) ||
          minkq_result_count(nullptr) || minkq_result_pairs(nullptr) || minkq_result_digest(nullptr))
        failure("accessors of NULL handles must return 0");
      if (minkq_device_name(nullptr) == nullptr) failure("minkq_device_name(NULL) returned NULL");
      minkq_scene_release(nullptr);
      minkq_bvh_release(nullptr);
      minkq_result_release(nullptr);
      minkq_device_release(nullptr);
      note("NULL accessors and releases");
      break;
    case 2: {
      const int which = gen_.choice(2);
      minkq_result_release(st_.results[which]);
      st_.results[which] = nullptr;
      const bool null_out = gen_.choice(4) == 0;
      Misuse m;
      m.add(null_out, MINKQ_ERROR_INVALID_ARGUMENT, "out_result NULL");
      expect("minkq_result_create", minkq_result_create(null_out ? nullptr : &st_.results[which]), m);
      break;
    }
    case 3:
      if (minkq_version() != MINKQ_VERSION_MAJOR * 10000 + MINKQ_VERSION_MINOR * 100 + MINKQ_VERSION_PATCH ||
          minkq_abi_version() != MINKQ_ABI_VERSION)
        failure("version mismatch");
      break;
    case 4: {
      const int b = gen_.choice(2);
      minkq_bvh_release(st_.bvhs[b].handle);
      st_.bvhs[b] = {};
      note("minkq_bvh_release");
      break;
    }
    default: {
      const int d = gen_.choice(2);
      if (st_.devices[d]) note(std::string("device ") + minkq_device_name(st_.devices[d]));
      break;
    }
  }
}

}  // namespace minkq::capi_fuzz

namespace {

using namespace minkq::capi_fuzz;

void at_exit() {
  std::fprintf(stderr, "minkq_fuzz_capi at exit: inputs %llu, calls checked %llu (of which misuses answered with an "
                       "error %llu), failures 0; stream-ordered past the checks: %llu refits/rebuilds (+%llu non-finite, "
                       "%llu pending errors reported), %llu queries fitting, %llu not\n",
               (unsigned long long)g_inputs, (unsigned long long)g_calls, (unsigned long long)g_errors,
               (unsigned long long)g_async_moves, (unsigned long long)g_async_non_finite,
               (unsigned long long)g_async_pending, (unsigned long long)g_async_fit,
               (unsigned long long)g_async_short);
}

std::unique_ptr<tbb::global_control> g_threads;

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  const char* threads = std::getenv("MINKQ_FUZZ_THREADS");
  const int n = threads ? std::atoi(threads) : 1;
  if (n > 0) g_threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, n);
  g_verbose = std::getenv("MINKQ_FUZZ_VERBOSE") != nullptr;
  const char* inject = std::getenv("MINKQ_FUZZ_INJECT");
  g_inject = inject && std::strcmp(inject, "0") != 0;
  std::atexit(at_exit);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  FuzzedDataProvider in(data, size);
  log_text.clear();
  ++g_inputs;
  {
    Session session(in);
    session.run();
  }
  if (g_verbose) std::fprintf(stderr, "---- input %llu\n%s", (unsigned long long)g_inputs, log_text.c_str());
  return 0;
}
