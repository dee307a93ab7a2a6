// How many keys the CUDA backend's canonical sort of one output runs over (cuda/passes.cuh),
// host code with no CUDA so that the CPU tests check it.
#pragma once

#include <cstdint>

namespace minkq::cuda {

// A blocking query has read its count: it sorts the pairs it wrote, all of them, or none when
// they did not fit (count > capacity: nothing is written and the caller learns the count), so
// a large reserved capacity costs nothing.
inline uint64_t blocking_sort_keys(uint64_t count, uint64_t capacity) { return count <= capacity ? count : 0; }

// A stream-ordered query cannot read its count on the host (the call may be captured into a
// graph and replayed), and CUB's radix sort takes its size from the host: it sorts all
// `capacity` keys, those past the count padded above every pair. Its cost follows the
// capacity, not the count (stated at minkq_scene_query_async).
inline uint64_t async_sort_keys(uint64_t capacity) { return capacity; }

}  // namespace minkq::cuda
