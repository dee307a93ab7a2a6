// The CPU backend's runtime helper: TBB's parallel loop over element indices, the host
// counterpart of cuda/runtime.cuh's one-thread-per-element launch.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstdint>

namespace minkq {

// fn(i) for every i in [0, n), in parallel (chunks of at least 1024 elements).
template <class Fn>
void parallel_for_each(int64_t n, Fn&& fn) {
  tbb::parallel_for(tbb::blocked_range<int64_t>(0, n, 1024), [&](const tbb::blocked_range<int64_t>& range) {
    for (int64_t i = range.begin(); i != range.end(); ++i) fn(i);
  });
}

}  // namespace minkq
