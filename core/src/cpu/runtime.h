// The CPU backend's runtime helpers: TBB's parallel loop over element indices, the host
// counterpart of cuda/runtime.cuh's one-thread-per-element launch, and the vector its arrays
// live in.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstdint>
#include <memory>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace minkq {

// fn(i) for every i in [0, n), in parallel (chunks of at least 1024 elements).
template <class Fn>
void parallel_for_each(int64_t n, Fn&& fn) {
  tbb::parallel_for(tbb::blocked_range<int64_t>(0, n, 1024), [&](const tbb::blocked_range<int64_t>& range) {
    for (int64_t i = range.begin(); i != range.end(); ++i) fn(i);
  });
}

// std::allocator, but an element made with no arguments is default-initialised (left as it is
// for the PODs of the CPU backend) instead of value-initialised (zeroed). A vector over it
// grows without a serial pass that zeroes the new elements and takes their page faults on one
// thread: every buffer of a build or a gather is written in full by a parallel loop next,
// whose threads then touch each their own part first.
template <class T>
struct DefaultInitAllocator : std::allocator<T> {
  using value_type = T;
  template <class U>
  struct rebind {
    using other = DefaultInitAllocator<U>;
  };
  DefaultInitAllocator() noexcept = default;
  template <class U>
  DefaultInitAllocator(const DefaultInitAllocator<U>&) noexcept {}
  template <class U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible<U>::value) {
    ::new (static_cast<void*>(p)) U;
  }
  template <class U, class... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};
template <class T, class U>
bool operator==(const DefaultInitAllocator<T>&, const DefaultInitAllocator<U>&) noexcept { return true; }
template <class T, class U>
bool operator!=(const DefaultInitAllocator<T>&, const DefaultInitAllocator<U>&) noexcept { return false; }

// The CPU backend's arrays: resize() leaves new elements unwritten (DefaultInitAllocator);
// assign(n, value) and resize(n, value) still write them.
template <class T>
using HostVector = std::vector<T, DefaultInitAllocator<T>>;

}  // namespace minkq
