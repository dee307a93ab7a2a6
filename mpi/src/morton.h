// The MPI layer's Morton code, for a locality order of elements: the ranks' reach boxes
// (ghosts.cpp) and the Morton partition of minkq-mpi and the tests (tools/partition.h).
//
// libminkq_mpi is built on the C API alone, which offers no Morton code, and these orders only
// group nearby elements (any order gives the same pairs, only tighter or looser ghost sets),
// so the layer keeps its own few lines rather than reaching into the core's headers.
#pragma once

#include <algorithm>
#include <cstdint>

namespace minkq::mpi {

// The 63-bit Morton code of a point given by its coordinates in [0, 1] relative to a bounding
// box (clamped there): each quantized to 21 bits, bit b of axis k at bit 3 b + k.
inline uint64_t morton_code_unit(const double unit[3]) {
  uint32_t q[3];
  for (int k = 0; k < 3; ++k) q[k] = uint32_t(std::min(std::max(unit[k], 0.0), 1.0) * 2097151.0);
  uint64_t code = 0;
  for (int bit = 20; bit >= 0; --bit)
    for (int k = 2; k >= 0; --k) code = code << 1 | (q[k] >> bit & 1u);
  return code;
}

}  // namespace minkq::mpi
