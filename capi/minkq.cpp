// The C ABI front end: argument checks with messages naming the offending element, topology
// (edge derivation), digests and library-owned results; all geometry runs in a backend. This
// file: versions, errors and devices (front_end.h lists the others).
#include "front_end.h"

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
              "kDropIncident and kLeafExact (core/include/minkq/query_sources.h) must be two distinct bits");

using namespace minkq::capi;

thread_local std::string minkq::capi::last_error;

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

}  // extern "C"
