// The host's SIMD helpers: simd4, for the shapes' leaf tests on four boxes at once (shapes.h)
// and the incidence test on four elements (leaf_groups.h), and Lanes<W>, the box test on the W
// boxes of W / 4 consecutive leaf groups (traversal.h's scan at the wider CPU levels,
// core/src/cpu/isa.h). Host code only: CUDA code tests lane by lane.
#pragma once

#include "minkq/hd.h"

#if !defined(__CUDACC__)
namespace minkq {

// Four floats in 4-float vector lanes (GCC vector extensions, SSE2 here): the host's leaf tests
// on a group's four boxes at once. Each lane runs the scalar test's float operations in the
// scalar test's order, with its selects for min_num / max_num / next_down, so every verdict is
// the scalar one bit for bit (tests/test_bvh.cpp checks each shape against it).
namespace simd4 {
typedef float F4 __attribute__((vector_size(16)));
typedef int32_t M4 __attribute__((vector_size(16)));  // a comparison: -1 (true) or 0 per lane
inline F4 load(const float* p) {
  F4 v;
  memcpy(&v, p, 16);
  return v;
}
inline F4 splat(float x) { return F4{x, x, x, x}; }
inline M4 load(const int32_t* p) {
  M4 v;
  memcpy(&v, p, 16);
  return v;
}
inline unsigned mask_bits(M4 m) {
#if defined(__SSE__)
  return unsigned(__builtin_ia32_movmskps((F4)m));  // one instruction: each lane's sign bit
#else
  return unsigned(m[0] & 1) | unsigned(m[1] & 1) << 1 | unsigned(m[2] & 1) << 2 | unsigned(m[3] & 1) << 3;
#endif
}
inline F4 min_num(F4 a, F4 b) { return ((a < b) | (b != b)) ? a : b; }
inline F4 max_num(F4 a, F4 b) { return ((a > b) | (b != b)) ? a : b; }
inline F4 abs(F4 x) {
  M4 bits;
  memcpy(&bits, &x, 16);
  bits &= 0x7fffffff;
  memcpy(&x, &bits, 16);
  return x;
}
inline F4 next_down(F4 x) {  // minkq::next_down per lane
  M4 bits;
  memcpy(&bits, &x, 16);
  bits = (x > 0.0f) ? bits - 1 : bits + 1;
  F4 stepped;
  memcpy(&stepped, &bits, 16);
  stepped = (x == 0.0f) ? splat(-1.40129846e-45f) : stepped;
  return ((x != x) | (x == -INFINITY)) ? x : stepped;
}
inline F4 next_up(F4 x) { return -next_down(-x); }
}  // namespace simd4

// W lanes of floats (W = 4 or 8) in GCC vector extensions: written once, compiled for the
// level of the function they are inlined into (SSE2: two 4-float halves; AVX2 and AVX-512: one
// 8-float register). Wider vectors are left out: g++ 12 tests 16-float comparisons lane by lane.
template <int W>
struct Lanes;
template <>
struct Lanes<4> {
  typedef float F __attribute__((vector_size(16)));
  typedef int32_t M __attribute__((vector_size(16)));
};
template <>
struct Lanes<8> {
  typedef float F __attribute__((vector_size(32)));
  typedef int32_t M __attribute__((vector_size(32)));
};

// Lanes 0..W-1: the 4-float rows at p, p + stride, ... (a field of consecutive groups). Always
// inlined: a wide vector never crosses a call, whose convention would depend on the level (so
// g++'s note that it does, -Wpsabi, does not apply).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wpsabi"
template <int W>
__attribute__((always_inline)) inline typename Lanes<W>::F load_rows(const float* p, size_t stride) {
  if constexpr (W == 4) {
    return simd4::load(p);
  } else {
    static_assert(W == 8, "4 or 8 lanes");
    return __builtin_shufflevector(simd4::load(p), simd4::load(p + stride), 0, 1, 2, 3, 4, 5, 6, 7);
  }
}
// Bit k set where lane k of the comparison m is true.
template <int W>
__attribute__((always_inline)) inline unsigned mask_bits(typename Lanes<W>::M m) {
  if constexpr (W == 4) {
    return simd4::mask_bits(m);
  } else {
    return simd4::mask_bits(__builtin_shufflevector(m, m, 0, 1, 2, 3)) |
           simd4::mask_bits(__builtin_shufflevector(m, m, 4, 5, 6, 7)) << 4;
  }
}
#pragma GCC diagnostic pop

}  // namespace minkq
#endif
