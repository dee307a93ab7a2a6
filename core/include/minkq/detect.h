// The detection idiom (C++17): whether an expression, written as an alias template over the
// types it names, is well-formed, and whether its type converts to the one a contract asks
// for. The contracts of shapes (shapes.h), work counters (traversal.h), box functors (bvh.h),
// query sources (query_sources.h), emitters (leaf_filter.h) and executors (core/src/executor.h)
// are stated with it, and checked by static_assert where they are used, each message naming
// the member that is missing.
#pragma once

#include <type_traits>

namespace minkq {
namespace detail {
template <class Void, template <class...> class Op, class... Args>
struct Detector : std::false_type {
  using type = void;
};
template <template <class...> class Op, class... Args>
struct Detector<std::void_t<Op<Args...>>, Op, Args...> : std::true_type {
  using type = Op<Args...>;
};
}  // namespace detail

// Op<Args...> is well-formed.
template <template <class...> class Op, class... Args>
constexpr bool is_detected = detail::Detector<void, Op, Args...>::value;

// Op<Args...> is well-formed and its type converts to To.
template <class To, template <class...> class Op, class... Args>
constexpr bool detected_as =
    is_detected<Op, Args...> && std::is_convertible<typename detail::Detector<void, Op, Args...>::type, To>::value;

// An optional static flag of T, read through Flag<T> (a std::integral_constant of it): its value
// where T has it, false where not. The opt-in flags of box functors (kByLeafPosition, refit.h)
// and emitters (kCountsOnly, leaf_filter.h).
template <template <class...> class Flag, class T>
constexpr bool flag_set =
    std::conditional_t<is_detected<Flag, T>, typename detail::Detector<void, Flag, T>::type, std::false_type>::value;

}  // namespace minkq
