// The CUDA backend's pass runner: the queries of one call's passes in one kernel launch (one
// thread per query, warp-aggregated pair output), device scratch for host outputs, and the
// canonical sort of pairs; the counterpart of cpu/passes.h. Included by cuda/backend.cu only.
#pragma once

#include <cooperative_groups.h>
#include <cooperative_groups/reduce.h>
#include <cooperative_groups/scan.h>
#include <cub/device/device_radix_sort.cuh>

#include <algorithm>
#include <array>
#include <tuple>
#include <type_traits>

#include "cuda/runtime.cuh"
#include "cuda/sort_size.h"
#include "backend.h"
#include "minkq/leaf_filter.h"

namespace minkq::cuda {

namespace cg = cooperative_groups;

constexpr int kQueryThreads = 128;  // traversal: divergent, local-memory stack per thread

// Where the pairs go: pair i at pairs[2i], pairs[2i + 1] if i < capacity; *count counts all.
struct PairSlots {
  int32_t* pairs;
  unsigned long long capacity;
  unsigned long long* count;
};

// Reserves n slots of *count for each lane that calls it: the lanes of a warp calling together
// share one atomicAdd (its last lane adds the group's total; each lane gets its prefix).
__device__ inline unsigned long long reserve_slots(unsigned long long* count, unsigned long long n) {
  const cg::coalesced_group group = cg::coalesced_threads();
  const unsigned long long before = cg::exclusive_scan(group, n);
  unsigned long long base = 0;
  if (group.thread_rank() == group.size() - 1) base = atomicAdd(count, before + n);
  return group.shfl(base, group.size() - 1) + before;
}

// emit() of one query's thread: buffers up to kFlush pairs and reserves their slots in one
// warp-aggregated atomic (reserve_slots), far fewer atomics than one per pair. Outputs with no
// room (capacity 0) count through PairCounter instead (run_pass_thread).
class PairBuffer {
 public:
  static constexpr int kFlush = 16;
  __device__ explicit PairBuffer(const PairSlots& slots) : slots_(slots) {}
  __device__ void operator()(int32_t first, int32_t second) {
    pairs_[n_] = make_int2(first, second);
    if (++n_ == kFlush) flush();
  }
  __device__ void flush() {
    if (n_ == 0) return;
    const unsigned long long first = reserve_slots(slots_.count, static_cast<unsigned long long>(n_));
    for (int k = 0; k < n_; ++k) {
      const unsigned long long slot = first + k;
      if (slot >= slots_.capacity) break;
      slots_.pairs[2 * slot] = pairs_[k].x;
      slots_.pairs[2 * slot + 1] = pairs_[k].y;
    }
    n_ = 0;
  }

 private:
  PairSlots slots_;
  int n_ = 0;
  int2 pairs_[kFlush];
};

__device__ inline unsigned long long warp_sum(unsigned long long x) {
  for (int offset = 16; offset > 0; offset /= 2) x += __shfl_down_sync(0xffffffffu, x, offset);
  return x;
}

// Adds each thread's counts into work[0..3] (one atomic per warp and counter).
__device__ inline void add_work(const WorkCounts& w, unsigned long long* work) {
  const unsigned long long counts[4] = {w.nodes_visited, w.node_tests, w.primitive_tests, w.candidates};
  for (int k = 0; k < 4; ++k) {
    const unsigned long long sum = warp_sum(counts[k]);
    if ((threadIdx.x & 31) == 0 && sum) atomicAdd(&work[k], sum);
  }
}

// A pass's queries on the device: thread first_thread + i runs query i of the QueryPass (whose
// `out` the device does not read: the slots say where the pairs go). Passes start at block
// boundaries, so every block (and warp) runs one pass.
template <class Pass>
struct DevicePass {
  Pass pass;
  int64_t first_thread;
  PairSlots slots;
  unsigned long long* work;  // WorkCounts' four counters
};

__host__ __device__ inline int64_t round_up_to_block(int64_t n) { return (n + kQueryThreads - 1) / kQueryThreads * kQueryThreads; }

// Adds each calling thread's count to *count: one atomicAdd per group of lanes calling together.
__device__ inline void add_count(unsigned long long* count, unsigned long long n) {
  const cg::coalesced_group group = cg::coalesced_threads();
  const unsigned long long sum = cg::reduce(group, n, cg::plus<unsigned long long>());
  if (group.thread_rank() == 0 && sum != 0) atomicAdd(count, sum);
}

// Thread i's share of a pass, if i lies in the pass's blocks. An output with no room for pairs
// (capacity 0: a count-only query, or a count to size the caller's buffer) is counted by the
// leaf filter's count-only path (PairCounter, as on the CPU), one atomic per group of lanes at
// the end. With WorkCounts, every thread of those blocks stays to the end so that whole warps
// take part in the reduction of the counts.
template <class Work, class Pass>
__device__ void run_pass_thread(const DevicePass<Pass>& d, int64_t i) {
  const int64_t q = i - d.first_thread;
  if (q < 0 || q >= round_up_to_block(d.pass.num_queries)) return;  // uniform over the block
  Work work;
  if (q < d.pass.num_queries) {
    if (d.slots.capacity == 0) {  // uniform over the pass
      PairCounter counter;
      d.pass.run(int32_t(q), counter, work);
      add_count(d.slots.count, counter.counted);
    } else {
      PairBuffer emit(d.slots);
      d.pass.run(int32_t(q), emit, work);
      emit.flush();
    }
  }
  if constexpr (std::is_same<Work, WorkCounts>::value) add_work(work, d.work);
}

// One thread per query of each pass: one launch answers them all.
template <class Work, class... Pass>
static __global__ void __launch_bounds__(kQueryThreads) query_kernel(Pass... passes) {
  const int64_t i = global_index();
  (run_pass_thread<Work>(passes, i), ...);
}

static __global__ void pack_pairs_kernel(const int32_t* pairs, int64_t n, uint64_t* keys) {
  const int64_t i = global_index();
  if (i < n) keys[i] = pack_pair(pairs[2 * i], pairs[2 * i + 1]);
}

static __global__ void unpack_pairs_kernel(const uint64_t* keys, int64_t n, int32_t* pairs) {
  const int64_t i = global_index();
  if (i >= n) return;
  const Pair pair = unpack_pair(keys[i]);
  pairs[2 * i] = pair.first;
  pairs[2 * i + 1] = pair.second;
}

// Device scratch a store keeps between queries, grown as needed.
struct QueryWorkspace {
  DeviceBuffer<unsigned long long> count;
  DeviceBuffer<unsigned long long> work;  // WorkCounts' four counters
  DeviceBuffer<int32_t> pairs;  // host output: pairs are collected here first
  DeviceBuffer<uint64_t> keys, sorted_keys;
  DeviceBuffer<char> temp;
  std::array<uint64_t, kQueryKinds> last_count{};  // per QueryKind: the most pairs a query of that kind found
};

inline int bit_width(uint64_t x) { return x == 0 ? 0 : 64 - __builtin_clzll(x); }
// The bits a canonical sort of pairs with query ids below num_queries covers.
inline int pair_key_bits(int32_t num_queries) { return 32 + bit_width(uint64_t(num_queries)); }

inline cudaError_t sort_keys(void* storage, size_t& bytes, QueryWorkspace& ws, int64_t n, int end_bit) {
  return cub::DeviceRadixSort::SortKeys(storage, bytes, ws.keys.data(), ws.sorted_keys.data(), n, 0, end_bit, stream());
}

// Sorts n pairs in device memory lexicographically: as uint64 keys (query << 32 | prim).
inline void sort_pairs(int32_t* pairs, int64_t n, int32_t num_queries, QueryWorkspace& ws) {
  if (n < 2) return;
  ws.keys.ensure(size_t(n));
  ws.sorted_keys.ensure(size_t(n));
  launch("pack_pairs_kernel launch", pack_pairs_kernel, n, kThreads, pairs, n, ws.keys.data());
  const int end_bit = pair_key_bits(num_queries);  // query ids are < num_queries
  run_cub(ws.temp, "cub::DeviceRadixSort::SortKeys", [&](void* storage, size_t& bytes) {
    return sort_keys(storage, bytes, ws, n, end_bit);
  });
  launch("unpack_pairs_kernel launch", unpack_pairs_kernel, n, kThreads, ws.sorted_keys.data(), n, pairs);
}

// Asynchronous queries sort their pairs without knowing their count on the host: all
// `capacity` keys (async_sort_keys), those past the count (min(*count, capacity)) set to `pad`,
// above every pair's.
static __global__ void pack_padded_kernel(const int32_t* pairs, int64_t capacity, const unsigned long long* count,
                                          uint64_t pad, uint64_t* keys) {
  const int64_t i = global_index();
  if (i >= capacity) return;
  keys[i] = uint64_t(i) < *count ? pack_pair(pairs[2 * i], pairs[2 * i + 1]) : pad;
}
static __global__ void unpack_counted_kernel(const uint64_t* keys, int64_t capacity, const unsigned long long* count,
                                             int32_t* pairs) {
  const int64_t i = global_index();
  if (i >= capacity || uint64_t(i) >= *count) return;
  const Pair pair = unpack_pair(keys[i]);
  pairs[2 * i] = pair.first;
  pairs[2 * i + 1] = pair.second;
}

// Sizes the workspace for asynchronous canonical sorts of up to `capacity` pairs (any number of
// queries: sized for all 64 key bits), kept from then on.
inline void reserve_canonical(QueryWorkspace& ws, size_t capacity) {
  ws.keys.ensure(capacity);
  ws.sorted_keys.ensure(capacity);
  size_t bytes = 0;
  check(sort_keys(nullptr, bytes, ws, int64_t(capacity), 64), "cub::DeviceRadixSort::SortKeys");
  ws.temp.ensure(std::max<size_t>(bytes, 1));
}

// sort_pairs for an asynchronous query: the first min(*count, capacity) pairs, sorted in place.
inline void sort_pairs_async(int32_t* pairs, int64_t capacity, const unsigned long long* count, int32_t num_queries,
                             QueryWorkspace& ws) {
  capacity = int64_t(async_sort_keys(uint64_t(capacity)));
  if (capacity < 2) return;
  const int end_bit = pair_key_bits(num_queries);
  const uint64_t pad = end_bit >= 64 ? ~uint64_t(0) : (uint64_t(1) << end_bit) - 1;  // above (num_queries - 1) << 32 | p
  launch("pack_padded_kernel launch", pack_padded_kernel, capacity, kThreads, pairs, capacity, count, pad,
         ws.keys.data());
  run_cub(ws.temp, "cub::DeviceRadixSort::SortKeys",
          [&](void* storage, size_t& bytes) { return sort_keys(storage, bytes, ws, capacity, end_bit); });
  launch("unpack_counted_kernel launch", unpack_counted_kernel, capacity, kThreads, ws.sorted_keys.data(), capacity,
         count, pairs);
}

// Host output goes through device scratch, sized first by a guess: the kind's last count, or
// 8 pairs per query up to 2^24 pairs (128 MiB: a caller's large host buffer must not claim
// gigabytes before anything is found); a pass whose guess was short (but not the caller's
// buffer) reruns with the exact count.
inline uint64_t scratch_guess(const QueryWorkspace& ws, QueryKind kind, int32_t num_queries) {
  const uint64_t per_query = std::min<uint64_t>(8 * uint64_t(num_queries) + 65536, uint64_t(1) << 24);
  return std::max<uint64_t>(ws.last_count[int(kind)], per_query);
}

template <class Work, class... Pass>
void launch_passes(const Pass&... passes) {
  const int64_t threads = (round_up_to_block(passes.pass.num_queries) + ...);
  launch("query_kernel launch", query_kernel<Work, Pass...>, threads, kQueryThreads, passes...);
}

// An asynchronous call's passes (outputs with count pointers, in device memory): one kernel
// launch that counts into the callers' counts and writes pairs up to their capacities, then the
// canonical sorts; nothing read back, nothing allocated (the workspace was reserved).
template <class Work, class... Pass>
void run_passes_async(QueryWorkspace& ws, const Pass&... passes) {
  static_assert(std::is_same<Work, NoWork>::value, "asynchronous queries count no work");
  int64_t first_thread = 0;
  auto device_pass = [&](const auto& pass) {
    auto* count = reinterpret_cast<unsigned long long*>(pass.out.count);
    zero(count, 1);
    const DevicePass<std::decay_t<decltype(pass)>> d{pass, first_thread, PairSlots{pass.out.pairs, pass.out.capacity, count},
                                                     nullptr};
    first_thread += round_up_to_block(pass.num_queries);
    return d;
  };
  const auto device_passes = std::tuple{device_pass(passes)...};  // braces: built left to right
  std::apply([](const auto&... d) { launch_passes<Work>(d...); }, device_passes);
  auto sort = [&](const auto& pass) {
    if (pass.out.canonical)
      sort_pairs_async(pass.out.pairs, int64_t(pass.out.capacity),
                       reinterpret_cast<const unsigned long long*>(pass.out.count), pass.first_ids(), ws);
  };
  (sort(passes), ...);
}

// Runs the passes in one kernel launch and one count readback; returns each pass's total,
// its pairs written (and sorted if asked) where they fit the caller's buffer.
template <class Work, class... Pass>
std::array<uint64_t, sizeof...(Pass)> run_passes(QueryWorkspace& ws, const std::array<WorkCounts*, sizeof...(Pass)>& works,
                                                 const Pass&... passes) {
  constexpr size_t kPasses = sizeof...(Pass);
  const std::array<QueryKind, kPasses> kinds{passes.kind...};
  const std::array<PairOutput, kPasses> outs{passes.out...};
  const std::array<int32_t, kPasses> num_queries{passes.num_queries...};
  const std::array<int32_t, kPasses> first_ids{passes.first_ids()...};
  std::array<uint64_t, kPasses> capacity{};
  for (size_t k = 0; k < kPasses; ++k) {
    capacity[k] = outs[k].capacity;
    if (outs[k].memory == Memory::kHost) capacity[k] = std::min<uint64_t>(outs[k].capacity, scratch_guess(ws, kinds[k], num_queries[k]));
  }
  ws.count.ensure(kPasses);
  ws.work.ensure(4 * kPasses);
  std::array<int32_t*, kPasses> pairs{};
  std::array<uint64_t, kPasses> totals{};
  for (int attempt = 0; attempt < 2; ++attempt) {
    size_t scratch = 0;  // host outputs' slots in ws.pairs, one after another
    for (size_t k = 0; k < kPasses; ++k)
      if (outs[k].memory == Memory::kHost) scratch += 2 * capacity[k];
    ws.pairs.ensure(scratch);
    scratch = 0;
    for (size_t k = 0; k < kPasses; ++k) {
      pairs[k] = outs[k].pairs;
      if (outs[k].memory == Memory::kHost) {
        pairs[k] = ws.pairs.data() + scratch;
        scratch += 2 * capacity[k];
      }
    }
    zero(ws.count, kPasses);
    zero(ws.work, 4 * kPasses);
    int64_t first_thread = 0;
    size_t k = 0;
    auto device_pass = [&](const auto& pass) {
      const DevicePass<std::decay_t<decltype(pass)>> d{pass, first_thread,
                                                       PairSlots{pairs[k], capacity[k], ws.count.data() + k},
                                                       ws.work.data() + 4 * k};
      first_thread += round_up_to_block(pass.num_queries);
      ++k;
      return d;
    };
    const auto device_passes = std::tuple{device_pass(passes)...};  // braces: built left to right
    std::apply([](const auto&... d) { launch_passes<Work>(d...); }, device_passes);
    unsigned long long counts[kPasses];
    copy(counts, ws.count.data(), sizeof(counts), cudaMemcpyDeviceToHost);
    bool rerun = false;
    for (size_t j = 0; j < kPasses; ++j) {
      totals[j] = counts[j];
      if (totals[j] <= outs[j].capacity && totals[j] > capacity[j]) {
        capacity[j] = totals[j];
        rerun = true;
      }
    }
    if (!rerun) break;
  }
  if constexpr (std::is_same<Work, WorkCounts>::value) {  // the last run's counts: a rerun repeats the same work
    unsigned long long counts[4 * kPasses];
    copy(counts, ws.work.data(), sizeof(counts), cudaMemcpyDeviceToHost);
    for (size_t k = 0; k < kPasses; ++k)
      if (works[k]) works[k]->add(WorkCounts{counts[4 * k], counts[4 * k + 1], counts[4 * k + 2], counts[4 * k + 3]});
  }
  for (size_t k = 0; k < kPasses; ++k) {
    ws.last_count[int(kinds[k])] = std::max(ws.last_count[int(kinds[k])], totals[k]);
    if (totals[k] > outs[k].capacity) continue;  // the caller learns the exact count; nothing copied
    if (totals[k] > capacity[k]) fail(Status::kInternal, "pair count changed between two runs of the same query");
    if (outs[k].canonical)
      sort_pairs(pairs[k], int64_t(blocking_sort_keys(totals[k], outs[k].capacity)), first_ids[k], ws);
    if (outs[k].memory == Memory::kHost)
      copy(outs[k].pairs, pairs[k], totals[k] * 2 * sizeof(int32_t), cudaMemcpyDeviceToHost);
  }
  check(cudaStreamSynchronize(stream()), "cudaStreamSynchronize");  // report kernel faults here
  return totals;
}

}  // namespace minkq::cuda
