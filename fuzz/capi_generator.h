// The C API fuzzer's buffers: a Buffer holds exactly the bytes it declares (fewer only when the
// declaration must be rejected), with the misuses of its declaration and what the model needs
// to know of its contents; the Generator draws every argument (choices, coordinates, radii,
// memory kinds, buffers) from the fuzzer's input.
#pragma once

#include <fuzzer/FuzzedDataProvider.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "capi_model.h"

namespace minkq::capi_fuzz {

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

}  // namespace minkq::capi_fuzz
