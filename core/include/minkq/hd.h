// Portable building blocks shared by the CPU (g++) and CUDA (nvcc) backends: the MINKQ_HD
// macro, a float3 type, boxes, and outward rounding. Everything here is plain arithmetic on
// PODs so both compilers produce bit-identical results (no FMA contraction: see CMakeLists).
#pragma once

#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>

// Forced inline on both sides: the node tests run tens of times per query, and g++ left the
// small ones (vmin, the shapes' overlaps) as out-of-line calls in the shared library.
#if defined(__CUDACC__)
#define MINKQ_HD __host__ __device__ __forceinline__
#else
#define MINKQ_HD inline __attribute__((always_inline))
#endif

namespace minkq {

// Unit roundoff of float32 (2^-24): every basic float operation on normal numbers has a
// relative error of at most this.
constexpr float kFloatUnitRoundoff = 5.9604644775390625e-08f;

struct Vec3 {
  float x, y, z;
};

MINKQ_HD Vec3 make_vec3(float x, float y, float z) { return Vec3{x, y, z}; }
MINKQ_HD Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
MINKQ_HD Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
MINKQ_HD Vec3 operator*(float s, Vec3 a) { return {s * a.x, s * a.y, s * a.z}; }
MINKQ_HD float component(Vec3 v, int axis) { return axis == 0 ? v.x : (axis == 1 ? v.y : v.z); }

// fmin/fmax semantics (a NaN operand yields the other one; the predicates rely on it to stay
// conservative when an intermediate overflows). The device has them as instructions; on the
// host g++ calls libm for each unless -ffinite-math-only, so there they are plain selects.
#if defined(__CUDA_ARCH__)
MINKQ_HD float min_num(float a, float b) { return fminf(a, b); }
MINKQ_HD float max_num(float a, float b) { return fmaxf(a, b); }
MINKQ_HD double min_num(double a, double b) { return fmin(a, b); }
MINKQ_HD double max_num(double a, double b) { return fmax(a, b); }
#else
// Written as two selects, not as (a < b || b != b) ? a : b: g++ compiles that `||` into a
// branch on the data, which a real mesh's coordinates leave unpredictable; these two become
// minss/maxss and a conditional move (the same results, bit for bit).
template <class T>
MINKQ_HD T min_num(T a, T b) {
  const T m = a < b ? a : b;
  return b != b ? a : m;
}
template <class T>
MINKQ_HD T max_num(T a, T b) {
  const T m = a > b ? a : b;
  return b != b ? a : m;
}
#endif

MINKQ_HD Vec3 vmin(Vec3 a, Vec3 b) { return {min_num(a.x, b.x), min_num(a.y, b.y), min_num(a.z, b.z)}; }
MINKQ_HD Vec3 vmax(Vec3 a, Vec3 b) { return {max_num(a.x, b.x), max_num(a.y, b.y), max_num(a.z, b.z)}; }

// Axis-aligned box; an empty box has lo > hi (see Box::empty()).
struct Box {
  Vec3 lo, hi;
  MINKQ_HD static Box empty() { return {{FLT_MAX, FLT_MAX, FLT_MAX}, {-FLT_MAX, -FLT_MAX, -FLT_MAX}}; }
  MINKQ_HD static Box of_point(Vec3 p) { return {p, p}; }
};

// Four boxes by axis, 96 B (the bytes of four Box): leaf scans test a group's four boxes at once
// (shapes.h). Lane k holds lo[axis][k], hi[axis][k].
struct BoxGroup {
  float lo[3][4];
  float hi[3][4];
};
static_assert(sizeof(BoxGroup) == 96, "a group holds four boxes and nothing else");
MINKQ_HD int64_t box_group_count(int64_t boxes) { return (boxes + 3) / 4; }
MINKQ_HD Box group_box(const BoxGroup& g, int k) {
  return {{g.lo[0][k], g.lo[1][k], g.lo[2][k]}, {g.hi[0][k], g.hi[1][k], g.hi[2][k]}};
}
MINKQ_HD void set_group_box(BoxGroup& g, int k, const Box& b) {
  g.lo[0][k] = b.lo.x, g.lo[1][k] = b.lo.y, g.lo[2][k] = b.lo.z;
  g.hi[0][k] = b.hi.x, g.hi[1][k] = b.hi.y, g.hi[2][k] = b.hi.z;
}
// Index of the lowest set bit of a non-zero mask.
MINKQ_HD int lowest_bit(unsigned mask) {
#if defined(__CUDA_ARCH__)
  return __ffs(int(mask)) - 1;
#else
  return __builtin_ctz(mask);
#endif
}

// Number of set bits of a lane mask. On the host a mask of four lanes reads a table of 16
// nibbles (generic x86-64 has no popcount instruction: __builtin_popcount is a library call).
MINKQ_HD int popcount(unsigned mask) {
#if defined(__CUDA_ARCH__)
  return __popc(mask);
#else
  if (mask < 16u) return int((0x4332322132212110ull >> (4u * mask)) & 15u);
  return __builtin_popcount(mask);
#endif
}
// The lanes of `lanes` for which pred(k) holds, tested lane by lane (the scalar form of a
// lane-mask test: CUDA code, and the host where a test has no four-lane form).
template <class Pred>
MINKQ_HD unsigned lanes_where(unsigned lanes, Pred pred) {
  unsigned bits = 0;
  for (unsigned rest = lanes; rest != 0; rest &= rest - 1u) {
    const int k = lowest_bit(rest);
    bits |= unsigned(bool(pred(k))) << k;
  }
  return bits;
}

// Union and overlap are exact in float (min, max and comparisons do not round), so node
// bounds built from exact primitive boxes need no outward rounding.
MINKQ_HD Box box_union(Box a, Box b) { return {vmin(a.lo, b.lo), vmax(a.hi, b.hi)}; }
MINKQ_HD Box box_expand(Box a, Vec3 p) { return {vmin(a.lo, p), vmax(a.hi, p)}; }
MINKQ_HD bool boxes_overlap(const Box& a, const Box& b) {
  return a.lo.x <= b.hi.x && b.lo.x <= a.hi.x && a.lo.y <= b.hi.y && b.lo.y <= a.hi.y &&
         a.lo.z <= b.hi.z && b.lo.z <= a.hi.z;
}

// Next float toward -inf / +inf. Written with bit operations (not nextafterf) so the device
// needs no libm and the result is identical on both backends. Finite inputs only; -0/+0 step
// to the smallest subnormal of the right sign.
MINKQ_HD float next_down(float x) {
  if (x != x || x == -INFINITY) return x;
  if (x == 0.0f) return -1.40129846e-45f;
  uint32_t bits;
  memcpy(&bits, &x, 4);
  bits = (x > 0.0f) ? bits - 1u : bits + 1u;
  memcpy(&x, &bits, 4);
  return x;
}
MINKQ_HD float next_up(float x) { return -next_down(-x); }

// Upper bound of r*r that also covers the relative error a few float operations add to a
// squared distance computed from exact float inputs (see predicates.h for the budgets).
// scale = 1 + 2^-18 covers 64 roundings of relative size 2^-24; the additive term covers
// underflow (each subnormal result may be off by 2^-150 absolutely).
MINKQ_HD float square_upper_bound(float r) {
  const float r2 = r * r;
  const float padded = next_up(r2 * 1.000003814697265625f);  // 1 + 2^-18
  return padded + 16.0f * 1.40129846e-45f;
}

}  // namespace minkq
