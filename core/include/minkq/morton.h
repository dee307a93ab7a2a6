// Morton codes: the key a build sorts primitives by, the centre of each box on a 63-bit
// Z-order curve over cubic cells of the frame of all centres.
#pragma once

#include "minkq/hd.h"

namespace minkq {

MINKQ_HD uint64_t spread_bits_21(uint32_t v) {  // 21 bits -> every third bit of 63
  uint64_t x = v & 0x1fffffu;
  x = (x | x << 32) & 0x1f00000000ffffull;
  x = (x | x << 16) & 0x1f0000ff0000ffull;
  x = (x | x << 8) & 0x100f00f00f00f00full;
  x = (x | x << 4) & 0x10c30c30c30c30c3ull;
  x = (x | x << 2) & 0x1249249249249249ull;
  return x;
}

MINKQ_HD uint32_t quantize_21(float value, float lo, float scale) {
  const float q = (value - lo) * scale;  // scale = 2^21 / extent (see morton_frame)
  if (!(q > 0.0f)) return 0u;
  if (q >= 2097151.0f) return 2097151u;
  return uint32_t(q);
}

// 63-bit Morton code of a box's centre within the bounds of all centres, over cubic cells: a
// query's radius is the same in every axis, so each axis is split as often as its extent
// warrants (the usual per-axis frame would split a thin axis as often as the longest one).
struct MortonFrame {
  Vec3 lo;
  Vec3 scale;  // 2^21 / extent per axis, 0 for a flat axis
};
MINKQ_HD float morton_scale(float extent) { return extent > 0.0f ? 2097152.0f / extent : 0.0f; }
MINKQ_HD MortonFrame morton_frame(const Box& centre_bounds) {
  const Vec3 extent = centre_bounds.hi - centre_bounds.lo;
  const float scale = morton_scale(max_num(max_num(extent.x, extent.y), extent.z));
  return {centre_bounds.lo, {scale, scale, scale}};
}
MINKQ_HD Vec3 box_centre(const Box& b) { return 0.5f * (b.lo + b.hi); }
MINKQ_HD uint64_t morton_code(const MortonFrame& f, Vec3 c) {
  return spread_bits_21(quantize_21(c.x, f.lo.x, f.scale.x)) << 2 |
         spread_bits_21(quantize_21(c.y, f.lo.y, f.scale.y)) << 1 |
         spread_bits_21(quantize_21(c.z, f.lo.z, f.scale.z));
}

}  // namespace minkq
