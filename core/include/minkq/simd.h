// The host's SIMD helpers (simd4), for the shapes' leaf tests on four boxes at once (shapes.h)
// and the incidence test on four elements (leaf_groups.h). Host code only: CUDA code tests
// lane by lane.
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

}  // namespace minkq
#endif
