// The CPU backend's pass runner: the queries of one call's passes in one TBB loop over fixed
// blocks, the counterpart of cuda/passes.cuh's single kernel launch.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <type_traits>
#include <utility>
#include <vector>

#include "backend.h"
#include "cpu/radix_sort.h"
#include "cpu/runtime.h"
#include "minkq/leaf_filter.h"
#include "minkq/packet.h"

namespace minkq::cpu {

// Queries per block: each block runs its queries in order into its own buffer.
constexpr int32_t kBlock = 256;

// One block's output: its pairs in the order its queries found them (the first `words` int32 of
// `pairs`), or only their number where the output has no room for any (capacity 0: a count-only
// query, or a count to size the caller's buffer).
struct BlockOut {
  HostVector<int32_t> pairs;
  size_t words = 0;
  uint64_t counted = 0;
};

// The emitter of a block's pairs: a cursor into its buffer, whose room doubles when full (the
// room is always a whole number of pairs).
class BlockWriter {
 public:
  explicit BlockWriter(BlockOut& part)
      : part_(part), cursor_(part.pairs.data() + part.words), end_(part.pairs.data() + part.pairs.size()) {}
  ~BlockWriter() { part_.words = size_t(cursor_ - part_.pairs.data()); }
  BlockWriter(const BlockWriter&) = delete;
  BlockWriter& operator=(const BlockWriter&) = delete;
  void operator()(int32_t first, int32_t second) {
    if (cursor_ == end_) grow();
    cursor_[0] = first;
    cursor_[1] = second;
    cursor_ += 2;
  }

 private:
  void grow() {
    const size_t words = size_t(cursor_ - part_.pairs.data());
    part_.pairs.resize(std::max<size_t>(512, 2 * part_.pairs.size()));
    cursor_ = part_.pairs.data() + words;
    end_ = part_.pairs.data() + part_.pairs.size();
  }
  BlockOut& part_;
  int32_t* cursor_;
  int32_t* end_;
};

// Whether a pass walks its queries in packets (packet.h): QueryPass and JobPass (one packet per
// job a packet's queries fall in) do.
template <class Pass>
using RunPacket = decltype(std::declval<const Pass&>().run_packet(int32_t(), 1, std::declval<PairCounter&>()));

// Queries [begin, end) of a pass in order: in packets of kPacket without work counts where the
// pass has them (the same pairs; work is counted query by query, as the CUDA backend walks).
template <class Work, class Pass, class Emit>
void run_queries(const Pass& pass, int32_t begin, int32_t end, Emit& emit, Work& work) {
  if constexpr (std::is_same<Work, NoWork>::value && is_detected<RunPacket, Pass>) {
    for (int32_t i = begin; i < end; i += kPacket) pass.run_packet(i, int(std::min<int32_t>(kPacket, end - i)), emit);
  } else {
    for (int32_t i = begin; i < end; ++i) pass.run(i, emit, work);
  }
}

template <class Work, class Pass>
void run_block(const Pass& pass, int32_t block, BlockOut& part, Work& work) {
  const int32_t begin = block * kBlock, end = std::min(pass.num_queries, (block + 1) * kBlock);
  if (pass.out.capacity == 0) {
    PairCounter count;  // leaf_filter.h: the count-only emitter the CUDA backend uses too
    run_queries(pass, begin, end, count, work);
    part.counted += count.counted;
    return;
  }
  BlockWriter emit(part);
  run_queries(pass, begin, end, emit, work);
}

// Sorts n pairs (ids >= 0) lexicographically: each a key of first above second, as few bits as
// the largest ids need, radix sorted (the values go along unused: every pair is a different
// key); a few thousand on one thread, by comparison, which costs less than setting that up.
inline void sort_pairs(int32_t* pairs, int64_t n) {
  if (n < 4096) {
    std::vector<uint64_t> keys(static_cast<size_t>(n));
    for (int64_t i = 0; i < n; ++i) keys[size_t(i)] = pack_pair(pairs[2 * i], pairs[2 * i + 1]);
    std::sort(keys.begin(), keys.end());
    for (int64_t i = 0; i < n; ++i) {
      const Pair pair = unpack_pair(keys[size_t(i)]);
      pairs[2 * i] = pair.first;
      pairs[2 * i + 1] = pair.second;
    }
    return;
  }
  using Range = tbb::blocked_range<int64_t>;
  const auto widest = tbb::parallel_reduce(
      Range(0, n, 4096), std::pair<uint32_t, uint32_t>{0, 0},
      [&](const Range& range, std::pair<uint32_t, uint32_t> m) {
        for (int64_t i = range.begin(); i != range.end(); ++i)
          m = {m.first | uint32_t(pairs[2 * i]), m.second | uint32_t(pairs[2 * i + 1])};
        return m;
      },
      [](std::pair<uint32_t, uint32_t> a, std::pair<uint32_t, uint32_t> b) {
        return std::pair<uint32_t, uint32_t>{a.first | b.first, a.second | b.second};
      });
  const auto width = [](uint32_t bits) { return bits == 0 ? 0 : 32 - __builtin_clz(bits); };
  const int second_bits = width(widest.second), bits = std::max(1, width(widest.first) + second_bits);
  HostVector<uint64_t> keys(static_cast<size_t>(n));
  HostVector<int32_t> unused(static_cast<size_t>(n));
  parallel_for_each(n, [&](int64_t i) {
    keys[i] = uint64_t(uint32_t(pairs[2 * i])) << second_bits | uint32_t(pairs[2 * i + 1]);
    unused[i] = 0;
  });
  radix_sort_pairs(keys, unused, bits);
  const uint64_t second_mask = (uint64_t(1) << second_bits) - 1;
  parallel_for_each(n, [&](int64_t i) {
    pairs[2 * i] = int32_t(keys[i] >> second_bits);
    pairs[2 * i + 1] = int32_t(keys[i] & second_mask);
  });
}

// Writes a pass's blocks, concatenated in block order, and sorts them if asked; returns the
// total. If it exceeds the capacity, a blocking query's output gets nothing and an asynchronous
// one's (out.count set) the first `capacity` pairs, unsorted.
// The blocks are copied in parallel where there is much to copy (a serial copy of a million-vertex
// mesh's pairs is memory bound on one thread).
inline uint64_t write_pass(const BlockOut* parts, int32_t blocks, const PairOutput& out) {
  uint64_t total = 0;
  for (int32_t b = 0; b < blocks; ++b) total += parts[b].words / 2 + parts[b].counted;
  if (total > out.capacity && !out.count) return total;
  const size_t room = 2 * size_t(std::min<uint64_t>(total, out.capacity));  // int32 words
  std::vector<size_t> at(static_cast<size_t>(blocks) + 1, 0);  // block b's words: [at[b], at[b + 1])
  for (int32_t b = 0; b < blocks; ++b) at[b + 1] = std::min(at[b] + parts[b].words, room);
  const auto copy = [&](int32_t b) {
    if (at[b + 1] > at[b]) std::memcpy(out.pairs + at[b], parts[b].pairs.data(), (at[b + 1] - at[b]) * sizeof(int32_t));
  };
  constexpr size_t kParallelCopyWords = size_t(1) << 16;
  if (room >= kParallelCopyWords) {
    tbb::parallel_for(int32_t(0), blocks, copy);
  } else {
    for (int32_t b = 0; b < blocks; ++b) copy(b);
  }
  if (total > out.capacity) return total;
  if (out.canonical) sort_pairs(out.pairs, int64_t(total));
  return total;
}

// Runs the passes' queries in one parallel loop over fixed blocks (each block within one pass),
// each block into its own buffer, then concatenates each pass's blocks in order: the output
// order is deterministic whatever the thread count. Returns each pass's total.
template <class Work, class... Pass>
std::array<uint64_t, sizeof...(Pass)> run_passes(const std::array<WorkCounts*, sizeof...(Pass)>& works,
                                                 const Pass&... passes) {
  constexpr size_t kPasses = sizeof...(Pass);
  const std::array<int32_t, kPasses> num_queries{passes.num_queries...};
  std::array<int32_t, kPasses + 1> first_block{};
  for (size_t k = 0; k < kPasses; ++k) first_block[k + 1] = first_block[k] + (num_queries[k] + kBlock - 1) / kBlock;
  const int32_t blocks = first_block[kPasses];
  std::vector<BlockOut> parts(static_cast<size_t>(blocks));
  std::vector<Work> block_work(static_cast<size_t>(blocks));
  tbb::parallel_for(int32_t(0), blocks, [&](int32_t b) {
    size_t k = 0;
    auto run_if_owner = [&](const auto& pass) {
      if (b >= first_block[k] && b < first_block[k + 1]) run_block(pass, b - first_block[k], parts[b], block_work[b]);
      ++k;
    };
    (run_if_owner(passes), ...);
  });
  const std::array<PairOutput, kPasses> outs{passes.out...};
  std::array<uint64_t, kPasses> totals{};
  for (size_t k = 0; k < kPasses; ++k) {
    if constexpr (std::is_same<Work, WorkCounts>::value)
      if (works[k])
        for (int32_t b = first_block[k]; b < first_block[k + 1]; ++b) works[k]->add(block_work[b]);
    totals[k] = write_pass(parts.data() + first_block[k], first_block[k + 1] - first_block[k], outs[k]);
  }
  return totals;
}

}  // namespace minkq::cpu
