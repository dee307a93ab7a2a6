// Box tests the studies need beyond the library's shape contract (core/include/minkq/shapes.h):
// a shape's box test on a group of four boxes (the wide-node study tests child boxes so), and
// a shape's tests box by box over a group (the 'before' variants of the leaf scan).
#pragma once

#include <type_traits>

#include "minkq/shapes.h"

namespace minkq::bench {

// may_overlap box by box over the lanes asked for.
template <class Shape>
unsigned may_overlap_each(const Shape& shape, const BoxGroup& g, unsigned lanes) {
  unsigned bits = 0;
  for (unsigned rest = lanes; rest != 0; rest &= rest - 1u) {
    const int k = lowest_bit(rest);
    bits |= unsigned(shape.may_overlap(group_box(g, k))) << k;
  }
  return bits;
}

template <class Shape, class = void>
struct HasBoxTest : std::false_type {};
template <class Shape>
struct HasBoxTest<Shape, std::void_t<decltype(std::declval<const Shape&>().box_test())>> : std::true_type {};

// The shape's box test (may_overlap) on the lanes asked for: in vector lanes for the library's
// shapes (BoxShape's own group test, or a finer shape's box_test()), box by box otherwise.
template <class Shape>
unsigned may_overlap_group(const Shape& shape, const BoxGroup& g, unsigned lanes) {
  if constexpr (std::is_same<Shape, BoxShape>::value) return shape.overlaps_group(g, lanes);
  else if constexpr (HasBoxTest<Shape>::value) return shape.box_test().overlaps_group(g, lanes);
  else return may_overlap_each(shape, g, lanes);
}

}  // namespace minkq::bench
