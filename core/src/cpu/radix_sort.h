// The CPU build's key sort: a parallel radix sort of (key, value) pairs (one pass on the top
// digit, then each bucket by its next digits and its runs of shared top bits by the rest; fewer
// pairs on one thread the same way), the host counterpart of the CUDA build's
// cub::DeviceRadixSort::SortPairs. Stable, so values that start
// as 0..n-1 break ties by index exactly as CUB's sort does, and the result does not depend on
// the thread count. Hand-written because no Debian or PyPI library offers a parallel host radix
// sort of pairs (TBB's and oneDPL's host sorts compare; Boost's spreadsort runs on one thread).
#pragma once

#include <cstddef>
#include <cstdint>

#include "cpu/runtime.h"

namespace minkq {

// The sort's second buffers and per-block digit counts, kept by a caller that sorts again.
struct RadixScratch {
  HostVector<uint64_t> keys;
  HostVector<int32_t> values;
  HostVector<uint32_t> offsets;
  size_t bytes() const {
    return keys.capacity() * sizeof(uint64_t) + values.capacity() * sizeof(int32_t) +
           offsets.capacity() * sizeof(uint32_t);
  }
};

// Sorts keys ascending by their low `bits` bits (1 to 64; higher bits must be zero), moving
// values along; equal keys keep their order. Digits that every key shares are skipped. The
// vectors may come back swapped with the scratch's (same sizes).
void radix_sort_pairs(HostVector<uint64_t>& keys, HostVector<int32_t>& values, int bits, RadixScratch& scratch);
inline void radix_sort_pairs(HostVector<uint64_t>& keys, HostVector<int32_t>& values, int bits) {
  RadixScratch scratch;
  radix_sort_pairs(keys, values, bits, scratch);
}

}  // namespace minkq
