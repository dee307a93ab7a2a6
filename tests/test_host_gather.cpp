// The gathers of host memory that both backends use (backend.h: gather_host and
// gather_float64_host, parallel over blocks of records): the same records, the same rounding
// and the same rho, bit for bit, as one thread reading the records in order, at any stride and
// alignment; and non-finite input named by the index of its first record, wherever the blocks
// split.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "backend.h"
#include "minkq.h"
#include "minkq/float64.h"
#include "test_util.h"

namespace minkq {
namespace {

// Enough records for many of the parallel loops' blocks (1024 records each at the least).
constexpr int64_t kCount = 100003;

// `count` records of `stride` bytes from byte `offset` of a fresh buffer, each holding the
// `floats` scalars of type S that `value(i, k)` gives; the padding is filled with garbage.
template <class S, class Value>
std::vector<char> strided_records(int64_t count, size_t stride, size_t offset, int floats, const Value& value) {
  std::vector<char> bytes(offset + size_t(count) * stride, char(0x5a));
  for (int64_t i = 0; i < count; ++i)
    for (int k = 0; k < floats; ++k) {
      const S v = value(i, k);
      std::memcpy(bytes.data() + offset + size_t(i) * stride + sizeof(S) * size_t(k), &v, sizeof v);
    }
  return bytes;
}

Strided view(const std::vector<char>& bytes, size_t offset, size_t stride, int64_t count, Scalar scalar) {
  Strided values{bytes.data() + offset, stride, count, Memory::kHost};
  values.scalar = scalar;
  return values;
}

template <class T>
bool same_bits(const std::vector<T>& a, const std::vector<T>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(T)) == 0;
}

TEST(HostGather, float_records_match_one_thread_at_any_stride) {
  test::Random rng(test::fresh_seed());
  for (size_t stride : {size_t(12), size_t(16), size_t(13), size_t(28)})
    for (size_t offset : {size_t(0), size_t(1)}) {
      const std::vector<char> bytes =
          strided_records<float>(kCount, stride, offset, 3, [&](int64_t, int) { return rng.uniform(-1e6f, 1e6f); });
      const Strided values = view(bytes, offset, stride, kCount, Scalar::kFloat32);
      std::vector<Vec3> serial(kCount), parallel(kCount);
      for (int64_t i = 0; i < kCount; ++i) std::memcpy(&serial[size_t(i)], bytes.data() + offset + size_t(i) * stride, 12);
      gather_host(values, parallel.data());
      EXPECT_TRUE(same_bits(serial, parallel)) << "stride " << stride << " offset " << offset;
    }
  const size_t stride = 30;  // boxes: 6 floats
  const std::vector<char> bytes =
      strided_records<float>(kCount, stride, 2, 6, [&](int64_t, int) { return rng.uniform(-10.0f, 10.0f); });
  std::vector<Box> serial(kCount), parallel(kCount);
  for (int64_t i = 0; i < kCount; ++i) std::memcpy(&serial[size_t(i)], bytes.data() + 2 + size_t(i) * stride, 24);
  gather_host(view(bytes, 2, stride, kCount, Scalar::kFloat32), parallel.data());
  EXPECT_TRUE(same_bits(serial, parallel));
}

// Rounded to nearest by float(), rho the largest rounding_distance: the one-thread reference.
// The farthest move is planted at the first, a middle and the last record in turn, so a
// reduction that lost a block's maximum, or the first or the last block, would show.
TEST(HostGather, float64_records_round_and_reduce_rho_as_one_thread) {
  test::Random rng(test::fresh_seed());
  for (size_t stride : {size_t(24), size_t(32), size_t(27)})
    for (int64_t planted : {int64_t(0), kCount / 2 + 7, kCount - 1}) {
      const std::vector<char> bytes = strided_records<double>(kCount, stride, 3, 3, [&](int64_t i, int k) {
        const double scale = i == planted ? 1e7 : 1e3;  // a far coordinate moves farther
        return scale * double(rng.uniform(-1.0f, 1.0f)) + 1e-9 * double(k + 1);
      });
      std::vector<Vec3> serial(kCount), parallel(kCount);
      float serial_rho = 0.0f;
      int64_t farthest = -1;
      for (int64_t i = 0; i < kCount; ++i) {
        double p[3];
        std::memcpy(p, bytes.data() + 3 + size_t(i) * stride, sizeof p);
        serial[size_t(i)] = Vec3{float(p[0]), float(p[1]), float(p[2])};
        const float moved = rounding_distance(p, serial[size_t(i)]);
        if (moved > serial_rho) serial_rho = moved, farthest = i;
      }
      ASSERT_EQ(farthest, planted) << "the planted record must move farthest";
      const Strided values = view(bytes, 3, stride, kCount, Scalar::kFloat64);
      for (int run = 0; run < 3; ++run) {  // the same whichever way the blocks were scheduled
        const float rho = gather_float64_host(values, parallel.data());
        EXPECT_TRUE(same_bits(serial, parallel)) << "stride " << stride;
        EXPECT_EQ(std::memcmp(&rho, &serial_rho, sizeof rho), 0)
            << "stride " << stride << ": rho " << rho << ", one thread " << serial_rho;
      }
    }
}

// The first bad record wins however the records were split: a NaN, an infinity or (float64) a
// double beyond the float range, with later bad records in other blocks. Through the C API:
// the message names that vertex.
TEST(HostGather, first_non_finite_record_is_named_by_index) {
  const std::unique_ptr<Backend> cpu = make_cpu_backend();
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  for (const int64_t first : {int64_t(0), int64_t(4095), int64_t(4096), int64_t(70001), kCount - 1}) {
    const auto bad_at = [&](int64_t i, int k, double bad) {
      if (i == first && k == 2) return bad;
      if (i > first && (i - first) % 9973 == 0 && k == 0) return double(nan);  // later ones, other blocks
      return double(i % 100) * 0.01;
    };
    const std::vector<char> floats = strided_records<float>(
        kCount, 16, 0, 3, [&](int64_t i, int k) { return float(bad_at(i, k, double(first % 2 ? inf : nan))); });
    EXPECT_EQ(cpu->first_non_finite(view(floats, 0, 16, kCount, Scalar::kFloat32), 3), first);
    const std::vector<char> doubles =
        strided_records<double>(kCount, 28, 1, 3, [&](int64_t i, int k) { return bad_at(i, k, -1e300); });
    EXPECT_EQ(cpu->first_non_finite(view(doubles, 1, 28, kCount, Scalar::kFloat64), 3), first);
  }
  // The C API names it: float64 vertices at stride 28 with the first bad one at 70001.
  const int64_t first = 70001;
  const std::vector<char> doubles = strided_records<double>(kCount, 28, 0, 3, [&](int64_t i, int k) {
    return i == first && k == 1 ? 1e39 : i == first + 5000 ? double(nan) : double(i % 7);
  });
  minkq_device* device = nullptr;
  ASSERT_EQ(minkq_device_create("cpu", &device), MINKQ_SUCCESS);
  const std::vector<int32_t> tris = {0, 1, 2};
  minkq_scene_desc desc{};
  desc.flags = MINKQ_SCENE_VT | MINKQ_SCENE_FLOAT64;
  desc.vertices = minkq_buffer{doubles.data(), 28, size_t(kCount), MINKQ_MEMORY_HOST};
  desc.triangles = minkq_buffer{tris.data(), 0, 1, MINKQ_MEMORY_HOST};
  minkq_scene* scene = nullptr;
  EXPECT_EQ(minkq_scene_create(device, &desc, &scene), MINKQ_ERROR_NON_FINITE);
  const std::string message = minkq_last_error_message();
  EXPECT_NE(message.find("vertex 70001 has a coordinate that is not finite or beyond the float range"),
            std::string::npos) << message;
  minkq_scene_release(scene);
  minkq_device_release(device);
}

}  // namespace
}  // namespace minkq
