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
#include <fuzzer/FuzzedDataProvider.h>
#include <tbb/global_control.h>
#include <xxhash.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "minkq.h"
#include "minkq.hpp"

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
}

namespace {

constexpr size_t kMaxElements = size_t(INT32_MAX) - 1;  // 2^31 - 2, minkq.h's SIZE_OVERFLOW limit
uint64_t g_calls = 0, g_inputs = 0, g_errors = 0;
// Stream-ordered calls that got past the checks: refits/rebuilds with finite and with
// non-finite vertices, queries whose pairs fit and did not, pending errors reported.
uint64_t g_async_moves = 0, g_async_non_finite = 0, g_async_fit = 0, g_async_short = 0, g_async_pending = 0;
bool g_verbose = false;  // MINKQ_FUZZ_VERBOSE=1: print every input's calls
// MINKQ_FUZZ_INJECT=1 (self-test): the model records each pending error one vertex too far on,
// so the first NON_FINITE minkq_scene_async_status reports must fail the message check.
bool g_inject = false;

std::string log_text;
void note(const std::string& line) {
  if (log_text.size() < 20000) log_text += line + "\n";
}

[[noreturn]] void failure(const std::string& what) {
  std::fprintf(stderr, "\n==== minkq C API fuzzer: FAILURE ====\n%s\n---- calls of this input ----\n%s\n", what.c_str(),
               log_text.c_str());
  std::fflush(stderr);
  std::abort();
}

std::string name(minkq_status s) { return minkq_status_name(s); }

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
void expect(const char* call, minkq_status got, const Misuse& misuse, minkq_status clean = MINKQ_SUCCESS) {
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

// ---- Buffers --------------------------------------------------------------------------------

enum class Fill { kCoordinates, kBoxes, kIndices };

struct Buffer {
  std::vector<char> storage;  // exactly the declared bytes (fewer only when the declaration is invalid)
  minkq_buffer desc{};
  Misuse misuse;
  size_t count = 0, stride = 0;
  bool non_finite = false, unordered_box = false;
  int32_t max_index = 0, min_index = 0;
  bool honest = true;
  const float* floats(size_t i) const { return reinterpret_cast<const float*>(storage.data() + i * stride); }
  // The first record (3 floats) with a non-finite coordinate, from the bytes generated: -1 if
  // none. Only meaningful for an honest buffer whose records do not overlap (stride >= 12).
  int64_t first_non_finite3() const {
    if (!honest || stride < 12) return -1;
    for (size_t i = 0; i < count; ++i) {
      float f[3];
      std::memcpy(f, storage.data() + i * stride, sizeof f);
      if (!std::isfinite(f[0]) || !std::isfinite(f[1]) || !std::isfinite(f[2])) return int64_t(i);
    }
    return -1;
  }
  // Replaces the non-finite coordinates of every record (3 floats) by finite ones: most
  // generated vertex buffers of a few dozen records hold a NaN somewhere.
  void make_finite3() {
    if (!honest || stride < 12) return;
    for (size_t i = 0; i < count; ++i) {
      float f[3];
      std::memcpy(f, storage.data() + i * stride, sizeof f);
      for (float& x : f)
        if (!std::isfinite(x)) x = 0.5f;
      std::memcpy(storage.data() + i * stride, f, sizeof f);
    }
    non_finite = false;
  }
};

class Generator {
 public:
  explicit Generator(FuzzedDataProvider& in) : in_(in) {}

  int choice(int n) { return in_.ConsumeIntegralInRange<int>(0, n - 1); }
  bool rarely() { return choice(8) == 0; }

  float coordinate() {
    switch (choice(16)) {
      case 0: return std::numeric_limits<float>::quiet_NaN();
      case 1: return choice(2) ? INFINITY : -INFINITY;
      case 2: return choice(2) ? FLT_MAX : -FLT_MAX;
      case 3: return choice(2) ? 1.4e-45f : -0.0f;
      case 4: {
        const uint32_t bits = in_.ConsumeIntegral<uint32_t>();
        float f;
        std::memcpy(&f, &bits, 4);
        return f;
      }
      case 5: return float(in_.ConsumeIntegralInRange<int>(-8, 8)) * 1e7f;
      default: return float(in_.ConsumeIntegralInRange<int>(-16, 16)) / 8.0f;  // exact, often equal
    }
  }

  float radius() {
    switch (choice(12)) {
      case 0: return std::numeric_limits<float>::quiet_NaN();
      case 1: return choice(2) ? INFINITY : -INFINITY;
      case 2: return -float(choice(3) + 1) * 0.5f;
      case 3: return -0.0f;
      case 4: return 0.0f;
      case 5: return choice(2) ? FLT_MAX : 1.4e-45f;
      case 6: return 1e30f;
      default: return float(choice(20)) / 8.0f;
    }
  }

  int memory() {
    const int c = choice(24);
    return c == 0 ? MINKQ_MEMORY_DEVICE : c == 1 ? 7 + choice(3) : c == 2 ? -1 : MINKQ_MEMORY_HOST;
  }

  // A buffer of `element` bytes per record. `preferred`: the count the call wants (a refit).
  Buffer buffer(size_t element, Fill fill, const char* what, size_t preferred = SIZE_MAX, int32_t vertex_count = 0,
                size_t max_count = 24) {
    Buffer b;
    b.count = (preferred != SIZE_MAX && choice(4) != 0) ? preferred : size_t(in_.ConsumeIntegralInRange<size_t>(0, max_count));
    size_t declared_stride = 0;
    switch (choice(12)) {
      case 0: declared_stride = element; break;
      case 1: declared_stride = element + 4; break;
      case 2: declared_stride = element + 1; break;  // unaligned records: allowed
      case 3: declared_stride = element >= 8 ? element - 4 : 1; break;
      case 4: declared_stride = choice(2) ? 1 : element - 1; break;
      case 5: declared_stride = choice(2) ? SIZE_MAX : SIZE_MAX / 2 + 1; break;
      default: declared_stride = 0; break;  // packed
    }
    const int memory = choice(6) == 0 ? this->memory() : MINKQ_MEMORY_HOST;
    if (rarely() && choice(4) == 0) b.count = choice(2) ? kMaxElements + 1 : SIZE_MAX / 2;
    const bool null_data = rarely() && choice(2) == 0;
    b.stride = declared_stride == 0 ? element : declared_stride;
    const std::string name(what);
    b.misuse.add(memory != MINKQ_MEMORY_HOST && memory != MINKQ_MEMORY_DEVICE, MINKQ_ERROR_INVALID_ARGUMENT,
                 name + ".memory invalid");
    b.misuse.add(memory == MINKQ_MEMORY_DEVICE, MINKQ_ERROR_INVALID_ARGUMENT, name + " in device memory on a CPU device");
    b.misuse.add(b.count > 0 && null_data, MINKQ_ERROR_INVALID_ARGUMENT, name + ".data NULL");
    b.misuse.add(b.stride < element, MINKQ_ERROR_INVALID_ARGUMENT, name + " stride too small");
    b.misuse.add(b.count > kMaxElements, MINKQ_ERROR_SIZE_OVERFLOW, name + ".count over 2^31 - 2");
    b.misuse.add(b.count > 0 && b.stride > SIZE_MAX / b.count, MINKQ_ERROR_SIZE_OVERFLOW, name + " size overflows");
    b.honest = b.count <= 64 && !(b.count > 0 && b.stride > SIZE_MAX / b.count);
    size_t span = element;  // dishonest declarations get one record: they must be rejected unread
    if (b.honest) span = b.count == 0 ? 0 : (b.count - 1) * b.stride + element;
    if (span > (size_t(1) << 20)) {  // a declaration this large must be rejected unread too
      b.honest = false;
      span = element;
    }
    b.storage.assign(span, char(0));
    // Bytes between records are NaN patterns: a reader that strays into them sees non-finite
    // coordinates or wild indices, and the model's expectation breaks.
    if (!b.storage.empty()) std::memset(b.storage.data(), 0xff, b.storage.size());
    const size_t records = b.honest ? b.count : std::min<size_t>(1, span / element);
    b.min_index = INT32_MAX;
    b.max_index = INT32_MIN;
    for (size_t i = 0; i < records; ++i) {
      char* at = b.storage.data() + i * (b.honest ? b.stride : element);
      if (fill == Fill::kIndices) {
        const size_t n = element / 4;
        for (size_t k = 0; k < n; ++k) {
          int32_t v;
          switch (choice(20)) {
            case 0: v = -1; break;
            case 1: v = vertex_count; break;
            case 2: v = choice(2) ? INT32_MAX : INT32_MIN; break;
            default: v = vertex_count > 0 ? in_.ConsumeIntegralInRange<int32_t>(0, vertex_count - 1) : 0;
          }
          std::memcpy(at + 4 * k, &v, 4);
          b.min_index = std::min(b.min_index, v);
          b.max_index = std::max(b.max_index, v);
        }
      } else {
        const size_t n = element / 4;
        float f[6];
        const bool wild = choice(6) == 0;
        for (size_t k = 0; k < n; ++k) {
          f[k] = wild ? coordinate() : float(in_.ConsumeIntegralInRange<int>(-16, 16)) / 8.0f;
          if (!std::isfinite(f[k])) b.non_finite = true;
        }
        if (fill == Fill::kBoxes) {
          for (int k = 0; k < 3; ++k)
            if (!wild || choice(4) != 0) {  // mostly ordered
              if (f[k] > f[k + 3]) std::swap(f[k], f[k + 3]);
              if (!(f[k] <= f[k + 3])) b.unordered_box = true;  // NaN
            } else if (!(f[k] <= f[k + 3])) {
              b.unordered_box = true;
            }
        }
        std::memcpy(at, f, 4 * n);
      }
    }
    const void* data = null_data ? nullptr : (b.storage.empty() ? (choice(2) ? nullptr : reinterpret_cast<void*>(&b)) : b.storage.data());
    b.desc = shim_buffer(data, declared_stride, b.count, memory);
    return b;
  }

 private:
  FuzzedDataProvider& in_;
};

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
void check_pairs(const char* call, const int32_t* pairs, uint64_t count, size_t queries, size_t prims, bool ee,
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
minkq::cxx::Result own_result() {
  minkq_result* r = nullptr;
  if (minkq_result_create(&r) != MINKQ_SUCCESS) failure("minkq_result_create");
  return minkq::cxx::Result(r);
}

// The digest of a fixed query: a scene's state, compared before and after a failed refit.
uint64_t scene_state(const SceneSlot& s) {
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
uint64_t scene_full_state(const SceneSlot& s) {
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
double scene_growth(const SceneSlot& s) {
  double g = -1.0;
  const minkq_status st = minkq_scene_tree_growth(s.handle, &g);
  if (st != MINKQ_SUCCESS) failure("minkq_scene_tree_growth failed: " + name(st));
  return g;
}

uint64_t bvh_state(const BvhSlot& b) {
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

class Session {
 public:
  Session(FuzzedDataProvider& in) : in_(in), gen_(in) {}

  void run() {
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
        case 9: scene_edges(); break;
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

 private:
  minkq_device* device(int* index) {
    const int d = gen_.choice(3);
    *index = d < 2 ? d : -1;
    return d < 2 ? st_.devices[d] : nullptr;
  }

  void device_create() {
    static const char* specs[] = {"cpu", "auto", "cuda", "cuda:0", "cuda:7", "cuda:99999", "cuda:123456", "cuda:",
                                  "cuda:-1", "cuda:1x", "CPU", "", "gpu", nullptr};
    const int which = gen_.choice(14);
    const char* spec = specs[which];
    const int slot = gen_.choice(2);
    const bool null_out = gen_.rarely();
    if (st_.devices[slot] && !null_out) {  // replace it only when nothing uses it
      if (st_.device_in_use(slot)) return;
      minkq_device_release(st_.devices[slot]);
      st_.devices[slot] = nullptr;
    }
    Misuse m;
    m.add(null_out, MINKQ_ERROR_INVALID_ARGUMENT, "out_device NULL");
    m.add(spec == nullptr, MINKQ_ERROR_INVALID_ARGUMENT, "spec NULL");
    const bool cuda = which >= 2 && which <= 5;  // well-formed CUDA specs: no CUDA in this build
    const bool malformed = spec && !cuda && which > 1;
    m.add(malformed, MINKQ_ERROR_INVALID_ARGUMENT, "unknown spec");
    m.add(cuda && minkq_cuda_device_count() <= (which == 4 ? 7 : which == 5 ? 99999 : 0), MINKQ_ERROR_UNSUPPORTED,
          "no such CUDA device");
    minkq_device* out = reinterpret_cast<minkq_device*>(0x1);
    const minkq_status s = minkq_device_create(spec, null_out ? nullptr : &out);
    expect("minkq_device_create", s, m);
    if (null_out) return;
    if (s == MINKQ_SUCCESS) {
      st_.devices[slot] = out;
      if (minkq_device_backend(out) != MINKQ_BACKEND_CPU && minkq_cuda_device_count() == 0)
        failure("a non-CPU device without CUDA");
      if (std::strlen(minkq_device_name(out)) == 0) failure("empty device name");
    } else if (out != nullptr) {
      failure("minkq_device_create failed but did not set *out_device to NULL");
    }
  }

  void device_release() {
    const int d = gen_.choice(2);
    if (st_.device_in_use(d)) return;  // the contract: scenes and bvhs first
    minkq_device_release(st_.devices[d]);  // NULL is fine too
    st_.devices[d] = nullptr;
    note("minkq_device_release");
  }

  void scene_create() {
    int d;
    minkq_device* dev = device(&d);
    const int slot = gen_.choice(3);
    if (st_.scenes[slot].handle) {
      minkq_scene_release(st_.scenes[slot].handle);
      st_.scenes[slot] = {};
    }
    uint32_t flags = uint32_t(gen_.choice(8));
    // Unknown bits only: 8 is MINKQ_SCENE_FLOAT64 (double vertices, which this model does not
    // make), 16 and 32 MINKQ_SCENE_VV and MINKQ_SCENE_EV (not modelled either).
    if (gen_.rarely()) flags |= gen_.choice(2) ? 64u : 0x80000000u;
    Buffer v = gen_.buffer(12, Fill::kCoordinates, "vertices", SIZE_MAX, 0, 32);
    const int32_t nv = int32_t(std::min<size_t>(v.count, 64));
    Buffer t = gen_.buffer(12, Fill::kIndices, "triangles", SIZE_MAX, nv, 32);
    Buffer e = gen_.choice(3) == 0 ? gen_.buffer(8, Fill::kIndices, "edges", SIZE_MAX, nv, 32)
                                   : gen_.buffer(8, Fill::kIndices, "edges", 0, nv, 0);
    const bool null_desc = gen_.rarely() && gen_.choice(2);
    const bool null_out = gen_.rarely() && gen_.choice(2);
    Misuse m;
    m.add(dev == nullptr, MINKQ_ERROR_INVALID_ARGUMENT, "device NULL");
    m.add(null_desc, MINKQ_ERROR_INVALID_ARGUMENT, "desc NULL");
    m.add(null_out, MINKQ_ERROR_INVALID_ARGUMENT, "out_scene NULL");
    if (!null_desc) {
      m.add(flags & ~63u, MINKQ_ERROR_INVALID_ARGUMENT, "unknown flag bits");
      m.add(!(flags & 3u), MINKQ_ERROR_INVALID_ARGUMENT, "no query kind");
      m.merge(v.misuse);
      m.merge(t.misuse);
      m.merge(e.misuse);
      if (v.honest) m.add(v.non_finite, MINKQ_ERROR_NON_FINITE, "non-finite vertex");
      if (t.honest && t.count > 0)
        m.add(t.min_index < 0 || t.max_index >= int32_t(v.count), MINKQ_ERROR_INDEX_OUT_OF_RANGE, "triangle index");
      if (e.honest && e.count > 0)
        m.add(e.min_index < 0 || e.max_index >= int32_t(v.count), MINKQ_ERROR_INDEX_OUT_OF_RANGE, "edge index");
    }
    minkq_scene_desc desc{};
    desc.flags = flags;
    desc.vertices = v.desc;
    desc.triangles = t.desc;
    desc.edges = e.desc;
    minkq_scene* out = reinterpret_cast<minkq_scene*>(0x1);
    const minkq_status s = minkq_scene_create(dev, null_desc ? nullptr : &desc, null_out ? nullptr : &out);
    expect("minkq_scene_create", s, m);
    if (null_out) return;
    if (s != MINKQ_SUCCESS) {
      if (out != nullptr && dev != nullptr && !null_desc) failure("minkq_scene_create failed but *out_scene is not NULL");
      return;
    }
    SceneSlot& slot_ref = st_.scenes[slot];
    slot_ref = SceneSlot::of(out, d, flags);
    if (slot_ref.vertices != v.count || slot_ref.triangles != t.count) failure("scene counts differ from the desc");
    if (e.count > 0 && slot_ref.edges != e.count) failure("scene edge count differs from the given edges");
    if (e.count == 0 && !(flags & MINKQ_SCENE_EE) && slot_ref.edges != 0) failure("edges derived for a VT-only scene");
    // Often reserve at once (the stream-ordered calls need it), as a simulator would.
    if (gen_.choice(2) == 0) reserve_on(&slot_ref, false, reserve_flags(), reserve_capacity());
  }

  void scene_release() {
    const int slot = gen_.choice(3);
    minkq_scene_release(st_.scenes[slot].handle);
    st_.scenes[slot] = {};
    note("minkq_scene_release");
  }

  SceneSlot* scene(bool* null_scene) {
    SceneSlot& s = st_.scenes[gen_.choice(3)];
    *null_scene = s.handle == nullptr;
    return &s;
  }
  // A slot for the stream-ordered calls: an empty one (a NULL scene) less often than scene();
  // when every slot is empty, mostly a valid scene made for the purpose.
  SceneSlot* live_scene(bool* null_scene) {
    SceneSlot* s = scene(null_scene);
    if (!*null_scene || gen_.choice(4) == 0) return s;
    for (auto& other : st_.scenes)
      if (other.handle) {
        *null_scene = false;
        return &other;
      }
    *null_scene = false;
    return valid_scene();
  }

  // A small valid scene (a CPU device made if there is none) in a random slot, often with a
  // reservation: something for the stream-ordered calls to act on.
  SceneSlot* valid_scene() {
    int d = st_.devices[0] ? 0 : st_.devices[1] ? 1 : -1;
    if (d < 0) {
      expect("minkq_device_create (for a valid scene)", minkq_device_create("cpu", &st_.devices[0]), Misuse{});
      d = 0;
    }
    SceneSlot& slot = st_.scenes[gen_.choice(3)];
    minkq_scene_release(slot.handle);
    slot = SceneSlot{};
    const int nv = 3 + gen_.choice(22), nt = 1 + gen_.choice(24);
    std::vector<float> xyz(3 * size_t(nv));
    for (float& x : xyz) x = float(gen_.choice(33) - 16) / 8.0f;
    std::vector<int32_t> tri(3 * size_t(nt));
    for (int32_t& v : tri) v = gen_.choice(nv);
    const uint32_t flags = uint32_t(1 + gen_.choice(3)) | (gen_.choice(2) ? uint32_t(MINKQ_SCENE_DROP_INCIDENT) : 0u);
    minkq_scene_desc desc{};
    desc.flags = flags;
    desc.vertices = shim_buffer(xyz.data(), 0, size_t(nv), MINKQ_MEMORY_HOST);
    desc.triangles = shim_buffer(tri.data(), 0, size_t(nt), MINKQ_MEMORY_HOST);
    desc.edges = shim_buffer(nullptr, 0, 0, MINKQ_MEMORY_HOST);
    minkq_scene* out = nullptr;
    expect("minkq_scene_create (a valid scene)", minkq_scene_create(st_.devices[d], &desc, &out), Misuse{});
    slot = SceneSlot::of(out, d, flags);
    if (slot.vertices != size_t(nv) || slot.triangles != size_t(nt)) failure("scene counts differ from the desc");
    if (gen_.choice(4) != 0) reserve_on(&slot, false, reserve_flags(), reserve_capacity());
    return &slot;
  }

  void scene_refit() {
    bool null_scene;
    SceneSlot* s = scene(&null_scene);
    Buffer v = gen_.buffer(12, Fill::kCoordinates, "vertices", null_scene ? SIZE_MAX : s->vertices, 0, 32);
    Misuse m;
    m.add(null_scene, MINKQ_ERROR_INVALID_ARGUMENT, "scene NULL");
    m.merge(v.misuse);
    if (!null_scene) m.add(v.count != s->vertices, MINKQ_ERROR_INVALID_ARGUMENT, "vertex count differs");
    if (v.honest) m.add(v.non_finite, MINKQ_ERROR_NON_FINITE, "non-finite vertex");
    const uint64_t before = null_scene ? 0 : scene_state(*s);
    const bool rebuild = gen_.choice(3) == 0;
    minkq_scene* handle = null_scene ? nullptr : s->handle;
    const minkq_status st = rebuild ? minkq_scene_rebuild(handle, v.desc) : minkq_scene_refit(handle, v.desc);
    expect(rebuild ? "minkq_scene_rebuild" : "minkq_scene_refit", st, m);
    if (st != MINKQ_SUCCESS && !null_scene && scene_state(*s) != before)
      failure(std::string("a failed ") + (rebuild ? "rebuild" : "refit") + " changed the scene's positions");
    check_tree_growth("minkq_scene_tree_growth", minkq_scene_tree_growth, handle, rebuild && st == MINKQ_SUCCESS);
  }

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

  // The arguments of a scene query, with the misuses they contain.
  struct QueryArgs {
    minkq_query_desc desc{};
    bool null_desc = false;
    int kind = 0, mode = 0;
    uint32_t flags = 0;
    float r = 0;
    Misuse misuse;
  };
  // `want_kind` >= 0: mostly that kind (the fused calls); `async`: mostly flags an asynchronous
  // query supports (no DIGEST, no STATS), so that most asynchronous queries get past the checks.
  QueryArgs query_args(const SceneSlot* s, bool null_scene, int want_kind = -1, bool async = false) {
    QueryArgs a;
    const int k = gen_.choice(12);
    a.kind = k < 5 ? MINKQ_QUERY_VT : k < 10 ? MINKQ_QUERY_EE : (k == 10 ? 4 : -1);  // (2, 3: VV, EV, not modelled)
    if (want_kind >= 0 && gen_.choice(6) != 0) a.kind = want_kind;
    const int md = gen_.choice(14);
    a.mode = md < 12 ? md % 4 : (md == 12 ? 4 : 99);
    // (MINKQ_QUERY_COUNT, 16, is not modelled: the unknown bits drawn start above it.)
    a.flags = uint32_t(gen_.choice(16)) | (gen_.rarely() ? 32u << gen_.choice(19) : 0u);
    if (async && gen_.choice(4) != 0) a.flags &= ~uint32_t(MINKQ_QUERY_DIGEST | MINKQ_QUERY_STATS);
    a.r = gen_.radius();
    a.null_desc = gen_.rarely() && gen_.choice(2);
    shim_query_desc(&a.desc, a.kind, a.mode, a.flags, a.r);
    Misuse& m = a.misuse;
    m.add(null_scene, MINKQ_ERROR_INVALID_ARGUMENT, "scene NULL");
    m.add(a.null_desc, MINKQ_ERROR_INVALID_ARGUMENT, "query NULL");
    if (!a.null_desc) {
      const bool kind_ok = a.kind == MINKQ_QUERY_VT || a.kind == MINKQ_QUERY_EE;
      m.add(!kind_ok, MINKQ_ERROR_INVALID_ARGUMENT, "kind invalid");
      m.add(a.mode < 0 || a.mode > 3, MINKQ_ERROR_INVALID_ARGUMENT, "mode invalid");
      m.add(a.flags & ~31u, MINKQ_ERROR_INVALID_ARGUMENT, "unknown query flags");
      if (!null_scene && kind_ok)
        m.add(!(s->flags & (a.kind == MINKQ_QUERY_VT ? MINKQ_SCENE_VT : MINKQ_SCENE_EE)), MINKQ_ERROR_INVALID_ARGUMENT,
              "kind not built");
      m.add(a.kind == MINKQ_QUERY_EE && a.mode == MINKQ_MODE_SPHERE, MINKQ_ERROR_INVALID_ARGUMENT, "EE sphere mode");
      m.add(!std::isfinite(a.r), MINKQ_ERROR_NON_FINITE, "radius not finite");
      m.add(a.r < 0, MINKQ_ERROR_INVALID_ARGUMENT, "radius negative");
    }
    return a;
  }
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
  // `own_memory` false: host memory, never misused (the fused call's second buffer shares the first's).
  Output output(uint64_t needed, bool own_memory = true) {
    Output o;
    switch (gen_.choice(8)) {
      case 0: o.capacity = 0; break;
      case 1: o.capacity = needed > 0 ? size_t(needed - 1) : 0; break;  // one short
      case 2: o.capacity = size_t(needed) + size_t(gen_.choice(4)); break;
      case 3: o.capacity = size_t(gen_.choice(4)); break;
      default: o.capacity = size_t(needed); break;
    }
    o.pairs.assign(2 * o.capacity, -5);
    o.data = o.capacity ? o.pairs.data() : (gen_.choice(2) ? nullptr : reinterpret_cast<int32_t*>(&o));
    if (gen_.rarely()) {
      const int c = gen_.choice(3);
      if (c == 0) {
        o.data = nullptr;
        o.capacity = 1 + size_t(gen_.choice(3));
        o.misuse.add(true, MINKQ_ERROR_INVALID_ARGUMENT, "out_pairs NULL with capacity");
      } else {
        o.capacity = c == 1 ? SIZE_MAX : SIZE_MAX / 8 + 1;  // declared, not held: must be rejected
        if (o.data == nullptr) o.data = reinterpret_cast<int32_t*>(&o);
        o.misuse.add(true, MINKQ_ERROR_SIZE_OVERFLOW, "capacity overflows");
      }
    }
    o.memory = own_memory && gen_.choice(6) == 0 ? gen_.memory() : MINKQ_MEMORY_HOST;
    o.misuse.add(o.memory != MINKQ_MEMORY_HOST && o.memory != MINKQ_MEMORY_DEVICE, MINKQ_ERROR_INVALID_ARGUMENT,
                 "out_memory invalid");
    o.misuse.add(o.memory == MINKQ_MEMORY_DEVICE, MINKQ_ERROR_INVALID_ARGUMENT, "out_memory device on CPU");
    o.null_info = gen_.rarely() && gen_.choice(2);
    o.misuse.add(o.null_info, MINKQ_ERROR_INVALID_ARGUMENT, "info NULL");
    return o;
  }

  // The count and digest of a query through the library-owned result (trusted after checks).
  bool reference_count(minkq_scene* scene, const minkq_query_desc& d, uint64_t* count, std::vector<int32_t>* pairs) {
    const minkq::cxx::Result r = own_result();
    const minkq_status st = minkq_scene_query_result(scene, &d, r.get());
    *count = minkq_result_count(r.get());
    if (pairs) pairs->assign(minkq_result_pairs(r.get()), minkq_result_pairs(r.get()) + 2 * *count);
    return st == MINKQ_SUCCESS;
  }

  void scene_query() {
    bool null_scene;
    SceneSlot* s = scene(&null_scene);
    QueryArgs a = query_args(s, null_scene);
    uint64_t needed = 0;
    std::vector<int32_t> expected;
    if (a.misuse.none() && !reference_count(s->handle, a.desc, &needed, &expected))
      failure("a valid query failed through minkq_scene_query_result: " + std::string(minkq_last_error_message()));
    Output o = output(needed);
    Misuse m = a.misuse;
    m.merge(o.misuse);
    minkq_query_info info{12345, 67890, {1, 2, 3, 4}};
    const minkq_status st = shim_scene_query(null_scene ? nullptr : s->handle, a.null_desc ? nullptr : &a.desc, o.data,
                                             o.capacity, o.memory, o.null_info ? nullptr : &info);
    expect("minkq_scene_query", st, m, needed > o.capacity ? MINKQ_ERROR_CAPACITY : MINKQ_SUCCESS);
    if (st == MINKQ_ERROR_CAPACITY && info.count != needed) failure("CAPACITY: info.count is not the exact count needed");
    if ((st == MINKQ_SUCCESS || st == MINKQ_ERROR_CAPACITY) &&
        info.stats.candidates != ((a.flags & MINKQ_QUERY_STATS) ? info.count : 0u))
      failure("info.stats.candidates is not the count with MINKQ_QUERY_STATS, or not 0 without");
    if (st != MINKQ_SUCCESS) return;
    if (info.count != needed) failure("minkq_scene_query and minkq_scene_query_result disagree on the count");
    check_pairs("minkq_scene_query", o.pairs.data(), info.count, queries_of(*s, a.kind), prims_of(*s, a.kind),
                a.kind == MINKQ_QUERY_EE, a.flags, info.digest);
    for (size_t i = 2 * size_t(info.count); i < o.pairs.size(); ++i)
      if (o.pairs[i] != -5) failure("minkq_scene_query wrote past the pairs it reported");
    if (a.flags & (MINKQ_QUERY_CANONICAL | MINKQ_QUERY_DIGEST)) {
      o.pairs.resize(2 * size_t(info.count));
      if (o.pairs != expected) failure("canonical pairs differ between minkq_scene_query and the result path");
    }
  }

  // The fused call: a VT and an EE description (either may be misused, or of the wrong kind),
  // two outputs in one memory; each query that fits must be written as the result path gives it.
  void scene_query_vt_ee() {
    bool null_scene;
    SceneSlot* s = scene(&null_scene);
    const QueryArgs vt = query_args(s, null_scene), ee = query_args(s, null_scene);
    Misuse m = vt.misuse;
    m.merge(ee.misuse);
    m.add(!vt.null_desc && vt.kind != MINKQ_QUERY_VT, MINKQ_ERROR_INVALID_ARGUMENT, "vt_query not VT");
    m.add(!ee.null_desc && ee.kind != MINKQ_QUERY_EE, MINKQ_ERROR_INVALID_ARGUMENT, "ee_query not EE");
    uint64_t needed[2] = {0, 0};
    std::vector<int32_t> expected[2];
    if (m.none() && !(reference_count(s->handle, vt.desc, &needed[0], &expected[0]) &&
                      reference_count(s->handle, ee.desc, &needed[1], &expected[1])))
      failure("a valid query failed through minkq_scene_query_result: " + std::string(minkq_last_error_message()));
    Output o[2] = {output(needed[0]), output(needed[1], false)};
    m.merge(o[0].misuse);
    m.merge(o[1].misuse);
    minkq_query_info info[2] = {{12345, 67890, {1, 2, 3, 4}}, {54321, 9876, {4, 3, 2, 1}}};
    const minkq_status st = shim_scene_query_vt_ee(
        null_scene ? nullptr : s->handle, vt.null_desc ? nullptr : &vt.desc, ee.null_desc ? nullptr : &ee.desc,
        o[0].data, o[0].capacity, o[1].data, o[1].capacity, o[0].memory, o[0].null_info ? nullptr : &info[0],
        o[1].null_info ? nullptr : &info[1]);
    const bool short_buffer = needed[0] > o[0].capacity || needed[1] > o[1].capacity;
    expect("minkq_scene_query_vt_ee", st, m, short_buffer ? MINKQ_ERROR_CAPACITY : MINKQ_SUCCESS);
    if (st != MINKQ_SUCCESS && st != MINKQ_ERROR_CAPACITY) return;
    const QueryArgs* args[2] = {&vt, &ee};
    for (int k = 0; k < 2; ++k) {
      if (info[k].count != needed[k]) failure("minkq_scene_query_vt_ee: a count is not the exact count");
      if (info[k].stats.candidates != ((args[k]->flags & MINKQ_QUERY_STATS) ? info[k].count : 0u))
        failure("minkq_scene_query_vt_ee: stats.candidates is not the count with MINKQ_QUERY_STATS, or not 0 without");
      if (needed[k] > o[k].capacity) {
        for (int32_t x : o[k].pairs)
          if (x != -5) failure("minkq_scene_query_vt_ee wrote into a buffer too small for its query");
        continue;
      }
      check_pairs("minkq_scene_query_vt_ee", o[k].pairs.data(), info[k].count, queries_of(*s, args[k]->kind),
                  prims_of(*s, args[k]->kind), k == 1, args[k]->flags, info[k].digest);
      for (size_t i = 2 * size_t(info[k].count); i < o[k].pairs.size(); ++i)
        if (o[k].pairs[i] != -5) failure("minkq_scene_query_vt_ee wrote past the pairs it reported");
      if (args[k]->flags & (MINKQ_QUERY_CANONICAL | MINKQ_QUERY_DIGEST)) {
        o[k].pairs.resize(2 * size_t(info[k].count));
        if (o[k].pairs != expected[k]) failure("minkq_scene_query_vt_ee: canonical pairs differ from the result path");
      }
    }
  }

  void scene_query_result() {
    bool null_scene;
    SceneSlot* s = scene(&null_scene);
    QueryArgs a = query_args(s, null_scene);
    const int which = gen_.choice(3);
    minkq_result* r = which < 2 ? st_.results[which] : nullptr;
    if (which < 2 && r == nullptr) {
      if (minkq_result_create(&st_.results[which]) != MINKQ_SUCCESS) failure("minkq_result_create");
      r = st_.results[which];
    }
    Misuse m = a.misuse;
    m.add(r == nullptr, MINKQ_ERROR_INVALID_ARGUMENT, "result NULL");
    const minkq_status st = minkq_scene_query_result(null_scene ? nullptr : s->handle, a.null_desc ? nullptr : &a.desc, r);
    expect("minkq_scene_query_result", st, m);
    if (st != MINKQ_SUCCESS) {
      if (r && minkq_result_count(r) != 0) failure("a failed query left a count in the result");
      return;
    }
    check_pairs("minkq_scene_query_result", minkq_result_pairs(r), minkq_result_count(r), queries_of(*s, a.kind),
                prims_of(*s, a.kind), a.kind == MINKQ_QUERY_EE, a.flags, minkq_result_digest(r));
  }

  void scene_edges() {
    bool null_scene;
    SceneSlot* s = scene(&null_scene);
    const size_t ne = null_scene ? 0 : s->edges;
    size_t capacity = gen_.choice(3) == 0 ? size_t(gen_.choice(4)) : ne + size_t(gen_.choice(2));
    std::vector<int32_t> out(2 * capacity, -3);
    int32_t* data = capacity ? out.data() : nullptr;
    Misuse m;
    m.add(null_scene, MINKQ_ERROR_INVALID_ARGUMENT, "scene NULL");
    if (gen_.rarely()) {
      data = nullptr;
      capacity = 1 + capacity;
      m.add(true, MINKQ_ERROR_INVALID_ARGUMENT, "out_edges NULL with capacity");
    }
    const minkq_status st = minkq_scene_edges(null_scene ? nullptr : s->handle, data, capacity);
    expect("minkq_scene_edges", st, m, ne > capacity ? MINKQ_ERROR_CAPACITY : MINKQ_SUCCESS);
    if (st == MINKQ_SUCCESS)
      for (size_t i = 2 * ne; i < out.size(); ++i)
        if (out[i] != -3) failure("minkq_scene_edges wrote past the edges");
  }

  void bvh_create() {
    int d;
    minkq_device* dev = device(&d);
    const int slot = gen_.choice(2);
    if (st_.bvhs[slot].handle) {
      minkq_bvh_release(st_.bvhs[slot].handle);
      st_.bvhs[slot] = {};
    }
    Buffer b = gen_.buffer(24, Fill::kBoxes, "boxes", SIZE_MAX, 0, 32);
    const bool null_out = gen_.rarely() && gen_.choice(2);
    Misuse m;
    m.add(null_out, MINKQ_ERROR_INVALID_ARGUMENT, "out_bvh NULL");
    m.add(dev == nullptr, MINKQ_ERROR_INVALID_ARGUMENT, "device NULL");
    m.merge(b.misuse);
    if (b.honest) {
      m.add(b.non_finite, MINKQ_ERROR_NON_FINITE, "non-finite box");
      m.add(b.unordered_box, MINKQ_ERROR_INVALID_ARGUMENT, "box lo > hi");
    }
    minkq_bvh* out = reinterpret_cast<minkq_bvh*>(0x1);
    const minkq_status st = minkq_bvh_create(dev, b.desc, null_out ? nullptr : &out);
    expect("minkq_bvh_create", st, m);
    if (null_out) return;
    if (st != MINKQ_SUCCESS) {
      if (out != nullptr && dev != nullptr) failure("minkq_bvh_create failed but *out_bvh is not NULL");
      return;
    }
    st_.bvhs[slot] = {out, d, b.count};
  }

  void bvh_refit() {
    BvhSlot& b = st_.bvhs[gen_.choice(2)];
    const bool null_bvh = b.handle == nullptr;
    Buffer v = gen_.buffer(24, Fill::kBoxes, "boxes", null_bvh ? SIZE_MAX : b.boxes, 0, 32);
    Misuse m;
    m.add(null_bvh, MINKQ_ERROR_INVALID_ARGUMENT, "bvh NULL");
    m.merge(v.misuse);
    if (!null_bvh) m.add(v.count != b.boxes, MINKQ_ERROR_INVALID_ARGUMENT, "box count differs");
    if (v.honest) {
      m.add(v.non_finite, MINKQ_ERROR_NON_FINITE, "non-finite box");
      m.add(v.unordered_box, MINKQ_ERROR_INVALID_ARGUMENT, "box lo > hi");
    }
    const uint64_t before = null_bvh ? 0 : bvh_state(b);
    const bool rebuild = gen_.choice(3) == 0;
    minkq_bvh* handle = null_bvh ? nullptr : b.handle;
    const minkq_status st = rebuild ? minkq_bvh_rebuild(handle, v.desc) : minkq_bvh_refit(handle, v.desc);
    expect(rebuild ? "minkq_bvh_rebuild" : "minkq_bvh_refit", st, m);
    if (st != MINKQ_SUCCESS && !null_bvh && bvh_state(b) != before)
      failure(std::string("a failed bvh ") + (rebuild ? "rebuild" : "refit") + " changed its boxes");
    check_tree_growth("minkq_bvh_tree_growth", minkq_bvh_tree_growth, handle, rebuild && st == MINKQ_SUCCESS);
  }

  void bvh_query() {
    BvhSlot& b = st_.bvhs[gen_.choice(2)];
    const bool null_bvh = b.handle == nullptr;
    const int sh = gen_.choice(13);
    const int shape = sh < 12 ? sh % 3 : (sh == 12 ? 3 : -2);
    const int md = gen_.choice(14);
    const int mode = md < 12 ? md % 4 : (md == 12 ? -1 : 17);
    const uint32_t flags = uint32_t(gen_.choice(16)) | (gen_.rarely() ? 32u : 0u);
    const float r = gen_.choice(3) == 0 ? 0.0f : gen_.radius();
    Buffer first = gen_.buffer(12, Fill::kCoordinates, "first", SIZE_MAX, 0, 16);
    Buffer second = shape == MINKQ_SHAPE_SPHERE && gen_.choice(4) != 0
                        ? gen_.buffer(12, Fill::kCoordinates, "second", 0, 0, 0)
                        : gen_.buffer(12, Fill::kCoordinates, "second", first.count, 0, 16);
    const bool null_desc = gen_.rarely() && gen_.choice(2);
    minkq_bvh_query_desc d;
    shim_bvh_query_desc(&d, shape, mode, flags, r, first.desc, second.desc);
    Misuse m;
    m.add(null_bvh, MINKQ_ERROR_INVALID_ARGUMENT, "bvh NULL");
    m.add(null_desc, MINKQ_ERROR_INVALID_ARGUMENT, "query NULL");
    if (!null_desc) {
      m.add(shape < 0 || shape > 2, MINKQ_ERROR_INVALID_ARGUMENT, "shape invalid");
      m.add(mode < 0 || mode > 3, MINKQ_ERROR_INVALID_ARGUMENT, "mode invalid");
      m.add(flags & ~31u, MINKQ_ERROR_INVALID_ARGUMENT, "unknown flags");
      m.add(flags & MINKQ_QUERY_LEAF_EXACT, MINKQ_ERROR_INVALID_ARGUMENT, "LEAF_EXACT on a bvh");
      m.add(shape == MINKQ_SHAPE_CAPSULE && mode == MINKQ_MODE_SPHERE, MINKQ_ERROR_INVALID_ARGUMENT, "capsule sphere mode");
      m.add(shape == MINKQ_SHAPE_BOX && mode != MINKQ_MODE_BOX, MINKQ_ERROR_INVALID_ARGUMENT, "box query non-box mode");
      m.add(!std::isfinite(r), MINKQ_ERROR_NON_FINITE, "radius not finite");
      m.add(r < 0, MINKQ_ERROR_INVALID_ARGUMENT, "radius negative");
      // minkq.h: "MINKQ_SHAPE_BOX ... radius must be 0".
      m.add(shape == MINKQ_SHAPE_BOX && std::isfinite(r) && r != 0, MINKQ_ERROR_INVALID_ARGUMENT, "box query radius not 0");
      m.merge(first.misuse);
      m.merge(second.misuse);
      if (shape == MINKQ_SHAPE_SPHERE) m.add(second.count != 0, MINKQ_ERROR_INVALID_ARGUMENT, "second not empty");
      else m.add(second.count != first.count, MINKQ_ERROR_INVALID_ARGUMENT, "second.count differs");
      if (first.honest) m.add(first.non_finite, MINKQ_ERROR_NON_FINITE, "non-finite query point");
      if (second.honest) m.add(second.non_finite, MINKQ_ERROR_NON_FINITE, "non-finite query point");
    }
    // The count a valid query needs, from a capacity-0 call of the same arguments.
    uint64_t needed = 0;
    if (m.none()) {
      minkq_query_info probe{};
      const minkq_status ps = shim_bvh_query(b.handle, &d, nullptr, 0, MINKQ_MEMORY_HOST, &probe);
      if (ps != MINKQ_SUCCESS && ps != MINKQ_ERROR_CAPACITY) failure("a valid bvh query failed: " + name(ps));
      needed = probe.count;
    }
    Output o = output(needed);
    m.merge(o.misuse);
    minkq_query_info info{};
    const minkq_status st = shim_bvh_query(null_bvh ? nullptr : b.handle, null_desc ? nullptr : &d, o.data, o.capacity,
                                           o.memory, o.null_info ? nullptr : &info);
    expect("minkq_bvh_query", st, m, needed > o.capacity ? MINKQ_ERROR_CAPACITY : MINKQ_SUCCESS);
    if (st == MINKQ_ERROR_CAPACITY && info.count != needed) failure("bvh CAPACITY: info.count is not the count needed");
    if (st != MINKQ_SUCCESS) return;
    check_pairs("minkq_bvh_query", o.pairs.data(), info.count, first.count, b.boxes, false, flags, info.digest);
  }

  // ---- Stream-ordered calls (minkq.h, "Stream-ordered calls"): on the CPU they run at once,
  // on host memory, the stream ignored; non-finite vertices become the scene's pending error.

  // A stream argument: ignored on the CPU, so any value (never dereferenced) must do.
  minkq_stream stream() {
    switch (gen_.choice(4)) {
      case 0: return reinterpret_cast<minkq_stream>(uintptr_t(0x5eed));
      case 1: return reinterpret_cast<minkq_stream>(&st_);
      default: return nullptr;
    }
  }

  // Reservation flags and capacities: mostly valid, sometimes unknown bits or overflowing sizes.
  uint32_t reserve_flags() {
    switch (gen_.choice(8)) {
      case 0: return 0u;
      case 1: case 2: return MINKQ_RESERVE_REFIT;
      case 3: return MINKQ_RESERVE_REFIT | MINKQ_RESERVE_REBUILD;
      case 4: return uint32_t(gen_.choice(8)) | (8u << gen_.choice(28));  // unknown bits (above SWEPT)
      default: return MINKQ_RESERVE_REBUILD;
    }
  }
  size_t reserve_capacity() {
    switch (gen_.choice(12)) {
      case 0: return 0;
      case 1: return size_t(gen_.choice(8));
      case 2: case 3: return size_t(gen_.choice(1024));
      case 4: return size_t(1) << 20;
      case 5: return kMaxElements + 1;
      case 6: return SIZE_MAX / 16;      // the largest capi/scene.cpp accepts (2 uint64_t per pair)
      case 7: return SIZE_MAX / 16 + 1;  // its byte size overflows: SIZE_OVERFLOW
      case 8: return SIZE_MAX;
      default: return size_t(gen_.choice(256));
    }
  }

  // One minkq_scene_reserve call on `s` (NULL scene when null_scene), checked and modelled.
  void reserve_on(SceneSlot* s, bool null_scene, uint32_t flags, size_t capacity) {
    Misuse m;
    m.add(null_scene, MINKQ_ERROR_INVALID_ARGUMENT, "scene NULL");
    m.add(flags & ~uint32_t(MINKQ_RESERVE_REFIT | MINKQ_RESERVE_REBUILD | MINKQ_RESERVE_SWEPT),
          MINKQ_ERROR_INVALID_ARGUMENT, "unknown reserve flags");
    m.add(capacity > SIZE_MAX / (2 * sizeof(uint64_t)), MINKQ_ERROR_SIZE_OVERFLOW, "canonical_capacity overflows");
    const uint64_t before = null_scene ? 0 : scene_full_state(*s);
    const minkq_status st = minkq_scene_reserve(null_scene ? nullptr : s->handle, flags, capacity);
    // A valid reservation beyond 2^31 pairs may be refused for memory (not on the CPU, which
    // reserves nothing, but minkq.h allows it).
    if (m.none() && capacity > kMaxElements && st == MINKQ_ERROR_OUT_OF_MEMORY) {
      Misuse oom;
      oom.add(true, MINKQ_ERROR_OUT_OF_MEMORY, "a huge valid reservation");
      expect("minkq_scene_reserve", st, oom);
    } else {
      expect("minkq_scene_reserve", st, m);
    }
    if (null_scene) return;
    if (scene_full_state(*s) != before) failure("minkq_scene_reserve changed the scene's pairs");
    if (st != MINKQ_SUCCESS) return;
    s->reserved_refit |= (flags & (MINKQ_RESERVE_REFIT | MINKQ_RESERVE_REBUILD)) != 0;
    s->reserved_rebuild |= (flags & MINKQ_RESERVE_REBUILD) != 0;
    s->reserved_canonical = std::max(s->reserved_canonical, capacity);
  }

  void scene_reserve() {
    bool null_scene;
    SceneSlot* s = live_scene(&null_scene);
    const uint32_t flags = reserve_flags();
    const size_t capacity = reserve_capacity();
    reserve_on(s, null_scene, flags, capacity);
  }

  // minkq_scene_refit_async / minkq_scene_rebuild_async: the blocking calls' buffer misuses
  // (minus NON_FINITE), the reservation, the vertex count. Non-finite coordinates succeed, keep
  // the positions and become the pending error (the first one only); finite ones give the state
  // the blocking call gives for the same vertices.
  void scene_refit_async() {
    bool null_scene;
    SceneSlot* s = live_scene(&null_scene);
    const bool rebuild = gen_.choice(3) == 0;
    const char* call = rebuild ? "minkq_scene_rebuild_async" : "minkq_scene_refit_async";
    // Half the scenes without the reservation get it now (a simulator reserves before its loop).
    if (!null_scene && !(rebuild ? s->reserved_rebuild : s->reserved_refit) && gen_.choice(2))
      reserve_on(s, false, rebuild || gen_.choice(2) ? MINKQ_RESERVE_REBUILD : MINKQ_RESERVE_REFIT, reserve_capacity());
    Buffer v = gen_.buffer(12, Fill::kCoordinates, "vertices", null_scene ? SIZE_MAX : s->vertices, 0, 32);
    switch (gen_.choice(4)) {
      case 0: case 1: v.make_finite3(); break;
      case 2:  // one NaN or infinity at a chosen record and axis (maybe after others)
        if (v.honest && v.stride >= 12 && v.count > 0) {
          const size_t i = size_t(gen_.choice(int(std::min<size_t>(v.count, 64))));
          const float bad_value = gen_.choice(2) ? std::numeric_limits<float>::quiet_NaN() : (gen_.choice(2) ? INFINITY : -INFINITY);
          std::memcpy(v.storage.data() + i * v.stride + 4 * size_t(gen_.choice(3)), &bad_value, 4);
          v.non_finite = true;
        }
        break;
      default: break;  // as generated
    }
    Misuse m;
    m.add(null_scene, MINKQ_ERROR_INVALID_ARGUMENT, "scene NULL");
    if (!null_scene) {
      m.add(rebuild ? !s->reserved_rebuild : !s->reserved_refit, MINKQ_ERROR_INVALID_ARGUMENT,
            rebuild ? "no MINKQ_RESERVE_REBUILD" : "no MINKQ_RESERVE_REFIT");
      m.add(v.count != s->vertices, MINKQ_ERROR_INVALID_ARGUMENT, "vertex count differs");
    }
    m.merge(v.misuse);
    const int64_t bad = m.none() ? v.first_non_finite3() : -1;
    if (m.none() && (bad >= 0) != v.non_finite) failure("harness: first_non_finite3 disagrees with the generator");
    const uint64_t before = null_scene ? 0 : scene_full_state(*s);
    const double growth_before = null_scene ? 0.0 : scene_growth(*s);
    const minkq_stream strm = stream();
    minkq_scene* handle = null_scene ? nullptr : s->handle;
    const minkq_status st = rebuild ? minkq_scene_rebuild_async(handle, v.desc, strm)
                                    : minkq_scene_refit_async(handle, v.desc, strm);
    expect(call, st, m);
    if (null_scene) return;
    const uint64_t after = scene_full_state(*s);
    const double growth = scene_growth(*s);
    if (st != MINKQ_SUCCESS) {
      if (after != before) failure(std::string("a failed ") + call + " changed the scene's positions");
      if (growth != growth_before) failure(std::string("a failed ") + call + " changed the tree growth");
      return;
    }
    if (rebuild && growth != 1.0)
      failure(std::string(call) + ": tree growth " + std::to_string(growth) + " after the rebuild, not 1");
    if (bad >= 0) {
      note("  (non-finite vertex " + std::to_string(bad) + ": pending " +
           (s->pending.call ? "already set" : "recorded") + ")");
      if (after != before) failure(std::string(call) + " with a non-finite vertex changed the scene's positions");
      // A refit to the kept positions leaves every box, so the growth, as it was.
      if (!rebuild && growth != growth_before)
        failure(std::string(call) + " with a non-finite vertex changed the tree growth from " +
                std::to_string(growth_before) + " to " + std::to_string(growth));
      if (s->pending.call == 0) s->pending = {rebuild ? 2 : 1, bad + (g_inject ? 1 : 0)};
      ++g_async_non_finite;
      if (gen_.choice(3) == 0) scene_query_async_on(s, false);
      if (gen_.choice(2) == 0) async_status_on(s, false);
      return;
    }
    // The reference: the blocking call with the same vertices must leave the same state (a
    // refit to the positions the scene already holds changes no pair and no box).
    const minkq_status bs = rebuild ? minkq_scene_rebuild(s->handle, v.desc) : minkq_scene_refit(s->handle, v.desc);
    expect(rebuild ? "minkq_scene_rebuild (reference)" : "minkq_scene_refit (reference)", bs, Misuse{});
    if (scene_full_state(*s) != after)
      failure(std::string(call) + ": the scene's pairs differ from those of the blocking call with the same vertices");
    ++g_async_moves;
    const double blocking_growth = scene_growth(*s);
    if (blocking_growth != growth)
      failure(std::string(call) + ": tree growth " + std::to_string(growth) + " but the blocking call then gives " +
              std::to_string(blocking_growth));
    if (gen_.choice(3) == 0) scene_query_async_on(s, false);
    if (gen_.choice(4) == 0) async_status_on(s, false);
  }

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
  AsyncOutput async_output(uint64_t needed) {
    AsyncOutput o;
    switch (gen_.choice(8)) {
      case 0: o.capacity = 0; break;
      case 1: o.capacity = needed > 0 ? size_t(needed - 1) : 0; break;
      case 2: o.capacity = size_t(needed) + size_t(gen_.choice(4)); break;
      case 3: o.capacity = size_t(gen_.choice(4)); break;
      default: o.capacity = size_t(needed); break;
    }
    o.raw.assign(2 * o.capacity + kGuardWords, kGuard);
    o.data = o.capacity || gen_.choice(2) ? o.raw.data() : nullptr;
    if (gen_.rarely()) {
      const int c = gen_.choice(3);
      o.declared_only = true;
      o.raw.assign(kGuardWords, kGuard);
      if (c == 0) {
        o.data = nullptr;
        o.capacity = 1 + size_t(gen_.choice(3));
        o.misuse.add(true, MINKQ_ERROR_INVALID_ARGUMENT, "out_pairs NULL with capacity");
      } else {
        o.data = o.raw.data();
        o.capacity = c == 1 ? SIZE_MAX : SIZE_MAX / 8 + 1;
        o.misuse.add(true, MINKQ_ERROR_SIZE_OVERFLOW, "capacity overflows");
      }
    }
    return o;
  }

  // Checks an asynchronous query's outputs after the call: `ok` whether it succeeded; `needed`
  // and `expected` the blocking query's count and canonical pairs.
  void check_async_output(const char* call, bool ok, const AsyncOutput& o, const uint64_t* count_word,
                          uint64_t count_value, const SceneSlot& s, const QueryArgs& a, uint64_t needed,
                          const std::vector<int32_t>& expected) {
    const size_t held = o.declared_only ? 0 : 2 * o.capacity;
    for (size_t i = held; i < o.raw.size(); ++i)
      if (o.raw[i] != kGuard) failure(std::string(call) + " wrote past the capacity (guard word " + std::to_string(i - held) + ")");
    if (!ok) {
      if (count_word && count_value != kCountSentinel) failure(std::string(call) + " failed but wrote the count");
      for (size_t i = 0; i < held; ++i)
        if (o.raw[i] != kGuard) failure(std::string(call) + " failed but wrote pairs");
      return;
    }
    if (count_value != needed)
      failure(std::string(call) + ": count " + std::to_string(count_value) + " but the blocking query finds " +
              std::to_string(needed));
    ++(needed > o.capacity ? g_async_short : g_async_fit);
    auto as_set = [](const std::vector<int32_t>& flat) {
      std::vector<std::pair<int32_t, int32_t>> p(flat.size() / 2);
      for (size_t i = 0; i < p.size(); ++i) p[i] = {flat[2 * i], flat[2 * i + 1]};
      std::sort(p.begin(), p.end());
      return p;
    };
    if (needed > o.capacity) {  // min(count, capacity) of the pairs, distinct, in any order (minkq.h)
      if (held == 0) return;
      const auto some = as_set(std::vector<int32_t>(o.raw.begin(), o.raw.begin() + std::ptrdiff_t(held)));
      const auto all = as_set(expected);
      if (std::adjacent_find(some.begin(), some.end()) != some.end())
        failure(std::string(call) + ": the pairs do not fit and one was written twice");
      if (!std::includes(all.begin(), all.end(), some.begin(), some.end()))
        failure(std::string(call) + ": the pairs do not fit and one written is not a pair of the blocking query");
      return;
    }
    for (size_t i = 2 * size_t(needed); i < held; ++i)
      if (o.raw[i] != kGuard) failure(std::string(call) + " wrote past the pairs it counted");
    const uint32_t flags = a.flags & uint32_t(MINKQ_QUERY_CANONICAL);  // no digest here
    check_pairs(call, o.raw.data(), needed, queries_of(s, a.kind), prims_of(s, a.kind), a.kind == MINKQ_QUERY_EE,
                flags, 0);
    std::vector<int32_t> got(o.raw.begin(), o.raw.begin() + 2 * std::ptrdiff_t(needed));
    if (a.flags & MINKQ_QUERY_CANONICAL) {
      if (got != expected) failure(std::string(call) + ": canonical pairs differ from the blocking query's (in order)");
      return;
    }
    if (as_set(got) != as_set(expected)) failure(std::string(call) + ": pairs differ from the blocking query's set");
  }

  // The asynchronous checks of one description beyond the blocking query's: DIGEST and STATS
  // are unsupported, canonical order needs the capacity reserved.
  void async_desc_misuse(Misuse& m, const QueryArgs& a, const SceneSlot* s, bool null_scene, size_t capacity,
                         const char* which) {
    if (a.null_desc) return;
    m.add(a.flags & uint32_t(MINKQ_QUERY_DIGEST | MINKQ_QUERY_STATS), MINKQ_ERROR_UNSUPPORTED,
          std::string(which) + " DIGEST or STATS");
    if (!null_scene)
      m.add((a.flags & MINKQ_QUERY_CANONICAL) && capacity > s->reserved_canonical, MINKQ_ERROR_INVALID_ARGUMENT,
            std::string(which) + " canonical capacity " + std::to_string(capacity) + " over the reservation " +
                std::to_string(s->reserved_canonical));
  }

  void scene_query_async() {
    bool null_scene;
    SceneSlot* s = live_scene(&null_scene);
    scene_query_async_on(s, null_scene);
  }
  void scene_query_async_on(SceneSlot* s, bool null_scene) {
    QueryArgs a = query_args(s, null_scene, -1, true);
    Misuse m = a.misuse;
    uint64_t needed = 0;
    std::vector<int32_t> expected;
    const bool desc_ok = m.none() && !(a.flags & (MINKQ_QUERY_DIGEST | MINKQ_QUERY_STATS));
    if (desc_ok && !reference_count(s->handle, a.desc, &needed, &expected))
      failure("a valid query failed through minkq_scene_query_result: " + std::string(minkq_last_error_message()));
    AsyncOutput o = async_output(needed);
    m.merge(o.misuse);
    async_desc_misuse(m, a, s, null_scene, o.capacity, "query");
    const bool null_count = gen_.rarely() && gen_.choice(2);
    m.add(null_count, MINKQ_ERROR_INVALID_ARGUMENT, "out_count NULL");
    uint64_t count = kCountSentinel;
    const uint64_t before = null_scene ? 0 : scene_full_state(*s);
    const minkq_status st = minkq_scene_query_async(null_scene ? nullptr : s->handle, a.null_desc ? nullptr : &a.desc,
                                                    o.data, o.capacity, null_count ? nullptr : &count, stream());
    expect("minkq_scene_query_async", st, m);
    if (null_scene) return;
    check_async_output("minkq_scene_query_async", st == MINKQ_SUCCESS, o, null_count ? nullptr : &count, count, *s, a,
                       needed, expected);
    if (scene_full_state(*s) != before) failure("minkq_scene_query_async changed the scene");
  }

  void scene_query_vt_ee_async() {
    bool null_scene;
    SceneSlot* s = live_scene(&null_scene);
    const QueryArgs vt = query_args(s, null_scene, MINKQ_QUERY_VT, true);
    const QueryArgs ee = query_args(s, null_scene, MINKQ_QUERY_EE, true);
    Misuse m = vt.misuse;
    m.merge(ee.misuse);
    m.add(!vt.null_desc && vt.kind != MINKQ_QUERY_VT, MINKQ_ERROR_INVALID_ARGUMENT, "vt_query not VT");
    m.add(!ee.null_desc && ee.kind != MINKQ_QUERY_EE, MINKQ_ERROR_INVALID_ARGUMENT, "ee_query not EE");
    const uint32_t unsupported = MINKQ_QUERY_DIGEST | MINKQ_QUERY_STATS;
    uint64_t needed[2] = {0, 0};
    std::vector<int32_t> expected[2];
    if (m.none() && !(vt.flags & unsupported) && !(ee.flags & unsupported) &&
        !(reference_count(s->handle, vt.desc, &needed[0], &expected[0]) &&
          reference_count(s->handle, ee.desc, &needed[1], &expected[1])))
      failure("a valid query failed through minkq_scene_query_result: " + std::string(minkq_last_error_message()));
    AsyncOutput o[2] = {async_output(needed[0]), async_output(needed[1])};
    m.merge(o[0].misuse);
    m.merge(o[1].misuse);
    async_desc_misuse(m, vt, s, null_scene, o[0].capacity, "vt_query");
    async_desc_misuse(m, ee, s, null_scene, o[1].capacity, "ee_query");
    uint64_t counts[2] = {kCountSentinel, kCountSentinel};
    uint64_t* vt_count = &counts[0];
    uint64_t* ee_count = &counts[1];
    switch (gen_.choice(16)) {
      case 0: vt_count = nullptr; m.add(true, MINKQ_ERROR_INVALID_ARGUMENT, "vt_count NULL"); break;
      case 1: ee_count = nullptr; m.add(true, MINKQ_ERROR_INVALID_ARGUMENT, "ee_count NULL"); break;
      case 2: ee_count = vt_count; m.add(true, MINKQ_ERROR_INVALID_ARGUMENT, "vt_count == ee_count"); break;
      default: break;
    }
    const uint64_t before = null_scene ? 0 : scene_full_state(*s);
    const minkq_status st = minkq_scene_query_vt_ee_async(
        null_scene ? nullptr : s->handle, vt.null_desc ? nullptr : &vt.desc, ee.null_desc ? nullptr : &ee.desc,
        o[0].data, o[0].capacity, vt_count, o[1].data, o[1].capacity, ee_count, stream());
    expect("minkq_scene_query_vt_ee_async", st, m);
    if (null_scene) return;
    const bool ok = st == MINKQ_SUCCESS;
    if (ok && ee_count == vt_count) failure("minkq_scene_query_vt_ee_async succeeded with vt_count == ee_count");
    check_async_output("minkq_scene_query_vt_ee_async (VT)", ok, o[0], vt_count, counts[0], *s, vt, needed[0],
                       expected[0]);
    check_async_output("minkq_scene_query_vt_ee_async (EE)", ok, o[1], ee_count, ee_count ? *ee_count : kCountSentinel,
                       *s, ee, needed[1], expected[1]);
    if (scene_full_state(*s) != before) failure("minkq_scene_query_vt_ee_async changed the scene");
  }

  // minkq_scene_async_status: the pending error of the model, once, with a message naming the
  // call and the vertex; then SUCCESS.
  void scene_async_status() {
    bool null_scene;
    SceneSlot* s = live_scene(&null_scene);
    async_status_on(s, null_scene);
  }
  void async_status_on(SceneSlot* s, bool null_scene) {
    const int times = gen_.choice(3) == 0 ? 2 : 1;
    for (int k = 0; k < times; ++k) {
      Misuse m;
      m.add(null_scene, MINKQ_ERROR_INVALID_ARGUMENT, "scene NULL");
      const PendingModel pending = null_scene ? PendingModel{} : s->pending;
      const uint64_t before = null_scene ? 0 : scene_full_state(*s);
      const minkq_status st = minkq_scene_async_status(null_scene ? nullptr : s->handle, stream());
      const std::string message = minkq_last_error_message();
      expect("minkq_scene_async_status", st, m, pending.call ? MINKQ_ERROR_NON_FINITE : MINKQ_SUCCESS);
      if (null_scene) return;
      if (st == MINKQ_ERROR_NON_FINITE) {
        ++g_async_pending;
        const std::string want = std::string(pending.call == 2 ? "minkq_scene_rebuild_async" : "minkq_scene_refit_async") +
                                 ": vertex " + std::to_string(pending.vertex) + " ";
        if (message.compare(0, want.size(), want) != 0 || message.find("non-finite") == std::string::npos)
          failure("minkq_scene_async_status: message \"" + message + "\" does not name the call and vertex (\"" + want +
                  "...\")");
      }
      s->pending = {};
      if (scene_full_state(*s) != before) failure("minkq_scene_async_status changed the scene");
    }
  }

  void misc() {
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

  FuzzedDataProvider& in_;
  Generator gen_;
  State st_;
};

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
