// The CPU backend's pass runner: the queries of one call's passes in one TBB loop over fixed
// blocks, the counterpart of cuda/passes.cuh's single kernel launch.
#pragma once

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <type_traits>
#include <vector>

#include "backend.h"
#include "cpu/runtime.h"
#include "minkq/leaf_filter.h"
#include "minkq/packet.h"

namespace minkq::cpu {

// Queries per block: each block runs its queries in order into its own buffer.
constexpr int32_t kBlock = 256;

// One block's output: its pairs in query order, or only their number where the output has no
// room for any (capacity 0: a count-only query, or a count to size the caller's buffer).
struct BlockOut {
  std::vector<int32_t> pairs;
  uint64_t counted = 0;
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
  auto emit = [&part](int32_t first, int32_t second) {
    part.pairs.push_back(first);
    part.pairs.push_back(second);
  };
  run_queries(pass, begin, end, emit, work);
}

// Writes a pass's blocks, concatenated in block order, and sorts them if asked; returns the
// total. If it exceeds the capacity, a blocking query's output gets nothing and an asynchronous
// one's (out.count set) the first `capacity` pairs, unsorted.
inline uint64_t write_pass(const BlockOut* parts, int32_t blocks, const PairOutput& out) {
  uint64_t total = 0;
  for (int32_t b = 0; b < blocks; ++b) total += parts[b].pairs.size() / 2 + parts[b].counted;
  if (total > out.capacity && !out.count) return total;
  int32_t* cursor = out.pairs;
  size_t room = 2 * size_t(std::min<uint64_t>(total, out.capacity));  // int32 words
  for (int32_t b = 0; b < blocks && room > 0; ++b) {
    const size_t words = std::min(parts[b].pairs.size(), room);
    if (words) std::memcpy(cursor, parts[b].pairs.data(), words * sizeof(int32_t));
    cursor += words;
    room -= words;
  }
  if (total > out.capacity) return total;
  if (out.canonical) {
    std::vector<uint64_t> packed(total);
    parallel_for_each(int64_t(total), [&](int64_t i) { packed[i] = pack_pair(out.pairs[2 * i], out.pairs[2 * i + 1]); });
    tbb::parallel_sort(packed.begin(), packed.end());
    parallel_for_each(int64_t(total), [&](int64_t i) {
      const Pair pair = unpack_pair(packed[i]);
      out.pairs[2 * i] = pair.first;
      out.pairs[2 * i + 1] = pair.second;
    });
  }
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
