#include "cpu/radix_sort.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <utility>
#include <vector>

namespace minkq {
namespace {

constexpr int kDigitBits = 8;
constexpr uint32_t kBuckets = 1u << kDigitBits;
// Blocks of at least this many pairs: each block is one task's histogram and scatter of the
// top digit; fewer pairs are sorted on one thread.
constexpr int64_t kMinBlock = 16384;

// The digit of `key` at bits [shift, shift + kDigitBits).
uint32_t digit_at(uint64_t key, int shift) { return uint32_t(key >> shift) & (kBuckets - 1); }

// The LSD passes over bits [lo, hi) of one range, on one thread: ping-pong between the two
// buffers; returns whether the sorted range ended in the second (b) buffer. Every digit's
// histogram comes from one read of the keys (a permutation keeps each digit's counts), so a
// pass costs one scatter; a digit that all keys share is skipped.
bool sort_range(uint64_t* a_k, int32_t* a_v, uint64_t* b_k, int32_t* b_v, int64_t n, int lo, int hi) {
  constexpr int kMaxDigits = (64 + kDigitBits - 1) / kDigitBits;
  const int digits = (hi - lo + kDigitBits - 1) / kDigitBits;
  uint32_t count[kMaxDigits][kBuckets];
  std::fill(&count[0][0], &count[0][0] + digits * kBuckets, 0u);  // only the digits sorted
  const uint64_t below_hi = hi >= 64 ? ~uint64_t(0) : (uint64_t(1) << hi) - 1;
  // Digit d of bits [lo, hi).
  auto digit = [&](uint64_t key, int d) { return digit_at(key & below_hi, lo + d * kDigitBits); };
  for (int64_t i = 0; i < n; ++i)
    for (int d = 0; d < digits; ++d) ++count[d][digit(a_k[i], d)];
  bool in_b = false;
  for (int d = 0; d < digits; ++d) {
    uint64_t *src_k = in_b ? b_k : a_k, *dst_k = in_b ? a_k : b_k;
    int32_t *src_v = in_b ? b_v : a_v, *dst_v = in_b ? a_v : b_v;
    uint32_t* next = count[d];
    uint32_t running = 0;
    bool shared = false;
    for (uint32_t b = 0; b < kBuckets; ++b) {
      shared = shared || next[b] == uint32_t(n);
      const uint32_t c = next[b];
      next[b] = running;
      running += c;
    }
    if (shared) continue;
    for (int64_t i = 0; i < n; ++i) {
      const uint32_t p = next[digit(src_k[i], d)]++;
      dst_k[p] = src_k[i];
      dst_v[p] = src_v[i];
    }
    in_b = !in_b;
  }
  return in_b;
}

// Runs of keys sharing their top bits no longer than this are finished by insertion sort,
// longer ones by sort_range_msd over their low bits.
constexpr int64_t kInsertionRun = 32;
// The one-thread sort's top digits tell apart at least this many cells per key.
constexpr int64_t kCellsPerKey = 16;

// The stable insertion sort of one range by key (few elements, nearly in order).
void insertion_sort(uint64_t* k, int32_t* v, int64_t n) {
  for (int64_t i = 1; i < n; ++i) {
    const uint64_t key = k[i];
    const int32_t value = v[i];
    int64_t j = i;
    for (; j > 0 && k[j - 1] > key; --j) k[j] = k[j - 1], v[j] = v[j - 1];
    k[j] = key, v[j] = value;
  }
}

// Bits [0, hi) of one range sorted on one thread, like sort_range, but most significant digits
// first: LSD passes over the top digits alone, as many as make at least kCellsPerKey cells per
// key, then each run of keys that share those top bits by its low bits: insertion sort for a
// short run, the same way again for a long one (its top digits then sized by its own length,
// so clustered keys cost a few passes per level, not one per digit). Morton codes of points on
// a surface or a curve leave short runs, so a few scatters and one nearly free pass replace a
// scatter per digit (the build study's real meshes: one top digit fewer leaves long runs, one
// more costs a scatter). Each level sorts at least one more digit, so it nests at most eight
// deep. Returns whether the range ended in b.
bool sort_range_msd(uint64_t* a_k, int32_t* a_v, uint64_t* b_k, int32_t* b_v, int64_t n, int hi) {
  int top_bits = kDigitBits;
  while (top_bits < hi && (int64_t(1) << top_bits) < kCellsPerKey * n) top_bits += kDigitBits;
  const int lo = hi - top_bits;
  if (lo <= 0) return sort_range(a_k, a_v, b_k, b_v, n, 0, hi);
  const bool in_b = sort_range(a_k, a_v, b_k, b_v, n, lo, hi);
  uint64_t* k = in_b ? b_k : a_k;
  int32_t* v = in_b ? b_v : a_v;
  uint64_t* other_k = in_b ? a_k : b_k;
  int32_t* other_v = in_b ? a_v : b_v;
  // Every key of the range has the same bits at and above hi (zero at the top call, the
  // bucket's digit or the enclosing run's top bits in nested ones), so a run is the keys equal
  // above lo; the insertion sort relies on the same.
  for (int64_t first = 0; first < n;) {
    const uint64_t cell = k[first] >> lo;
    int64_t last = first + 1;
    while (last < n && (k[last] >> lo) == cell) ++last;
    const int64_t count = last - first;
    if (count <= kInsertionRun) {
      insertion_sort(k + first, v + first, count);
    } else if (sort_range_msd(k + first, v + first, other_k + first, other_v + first, count, lo)) {
      std::copy(other_k + first, other_k + last, k + first);
      std::copy(other_v + first, other_v + last, v + first);
    }
    first = last;
  }
  return in_b;
}

}  // namespace

// One parallel pass on the top digit splits the pairs into buckets that fit a core's cache,
// then each bucket is sorted by its lower bits alone (sort_range_msd): one pass over memory
// instead of one per digit. Stable throughout, so the order is a stable sort's.
void radix_sort_pairs(HostVector<uint64_t>& keys, HostVector<int32_t>& values, int bits, RadixScratch& scratch) {
  const int64_t n = int64_t(keys.size());
  if (n < 2) return;
  HostVector<uint64_t>& other_keys = scratch.keys;
  HostVector<int32_t>& other_values = scratch.values;
  other_keys.resize(size_t(n));
  other_values.resize(size_t(n));
  const int top = std::max(0, bits - kDigitBits);  // the top digit: bits [top, bits)
  if (n < kMinBlock || top == 0) {
    if (sort_range_msd(keys.data(), values.data(), other_keys.data(), other_values.data(), n, bits)) {
      keys.swap(other_keys);
      values.swap(other_values);
    }
    return;
  }
  // The top digit, in parallel over blocks: a few per thread balance the load.
  const int64_t threads = std::max(1, tbb::this_task_arena::max_concurrency());
  const int64_t blocks = std::clamp<int64_t>(n / kMinBlock, 1, 4 * threads);
  const int64_t block = (n + blocks - 1) / blocks;
  HostVector<uint32_t>& offsets = scratch.offsets;
  offsets.resize(size_t(blocks * kBuckets));
  tbb::parallel_for(int64_t(0), blocks, [&](int64_t b) {
    uint32_t* count = offsets.data() + b * kBuckets;
    std::fill(count, count + kBuckets, 0u);
    for (int64_t i = b * block, end = std::min(n, i + block); i < end; ++i) ++count[digit_at(keys[size_t(i)], top)];
  });
  // Where each block's keys of each digit go: digits in order, blocks in order within one.
  std::vector<uint32_t> bucket_start(kBuckets + 1);
  uint32_t running = 0;
  for (uint32_t d = 0; d < kBuckets; ++d) {
    bucket_start[d] = running;
    for (int64_t b = 0; b < blocks; ++b) {
      const uint32_t c = offsets[size_t(b * kBuckets + d)];
      offsets[size_t(b * kBuckets + d)] = running;
      running += c;
    }
  }
  bucket_start[kBuckets] = running;
  tbb::parallel_for(int64_t(0), blocks, [&](int64_t b) {
    uint32_t* next = offsets.data() + b * kBuckets;
    for (int64_t i = b * block, end = std::min(n, i + block); i < end; ++i) {
      const uint32_t p = next[digit_at(keys[size_t(i)], top)]++;
      other_keys[p] = keys[size_t(i)];
      other_values[p] = values[size_t(i)];
    }
  });
  // Each bucket on its own, from other_* back into keys / values.
  tbb::parallel_for(uint32_t(0), kBuckets, [&](uint32_t d) {
    const uint32_t first = bucket_start[d], count = bucket_start[d + 1] - first;
    if (count == 0) return;
    uint64_t* a_k = other_keys.data() + first;
    int32_t* a_v = other_values.data() + first;
    uint64_t* b_k = keys.data() + first;
    int32_t* b_v = values.data() + first;
    if (!sort_range_msd(a_k, a_v, b_k, b_v, count, top)) {
      std::copy(a_k, a_k + count, b_k);
      std::copy(a_v, a_v + count, b_v);
    }
  });
}

}  // namespace minkq
