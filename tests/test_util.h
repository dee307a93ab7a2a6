// Shared helpers for the test suites: fresh random seeds (printed, and fixed with
// MINKQ_TEST_SEED to reproduce a failure) and random geometry.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <random>

#include "minkq/hd.h"

namespace minkq::test {

inline uint64_t fresh_seed() {
  if (const char* fixed = std::getenv("MINKQ_TEST_SEED")) return std::strtoull(fixed, nullptr, 10);
  const uint64_t seed = std::random_device{}() ^ (uint64_t(std::random_device{}()) << 32);
  std::printf("[ seed     ] MINKQ_TEST_SEED=%llu\n", static_cast<unsigned long long>(seed));
  return seed;
}

struct Random {
  std::mt19937_64 engine;
  explicit Random(uint64_t seed) : engine(seed) {}
  float uniform(float lo, float hi) { return std::uniform_real_distribution<float>(lo, hi)(engine); }
  int integer(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(engine); }
  float log_uniform(float lo, float hi) {
    return float(std::exp(std::uniform_real_distribution<double>(std::log(lo), std::log(hi))(engine)));
  }
  Vec3 vec3(float lo, float hi) { return {uniform(lo, hi), uniform(lo, hi), uniform(lo, hi)}; }
  // A box near `origin` with extents up to `scale` (sometimes flat or a point).
  Box box(Vec3 origin, float scale) {
    Vec3 a = origin + vec3(-scale, scale), b = origin + vec3(-scale, scale);
    if (integer(0, 5) == 0) b.x = a.x;
    if (integer(0, 9) == 0) b = a;
    return {vmin(a, b), vmax(a, b)};
  }
};

}  // namespace minkq::test
