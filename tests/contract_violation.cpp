// Compiled by ctest only, with one of MINKQ_VIOLATE_SHAPE, MINKQ_VIOLATE_SOURCE defined: a type
// that lacks one member of a contract, used where the library checks it. The tests expect the
// compiler to stop and to name the missing member (tests/CMakeLists.txt).
#include "minkq/leaf_filter.h"

namespace minkq {

#if defined(MINKQ_VIOLATE_SHAPE)
struct NoFiner {  // a shape without finer()
  static NoFiner from(const QueryGeometry&) { return {}; }
  bool may_overlap(const Box&) const { return true; }
  bool overlaps(const Box&) const { return true; }
  unsigned overlaps_group(const BoxGroup&, unsigned lanes) const { return lanes; }
};
void use(const BvhView& bvh) {
  auto on_leaf = [](int32_t, const Box&) {};
  NoWork work;
  traverse(bvh, NoFiner{}, -1, on_leaf, work);
}
#endif

#if defined(MINKQ_VIOLATE_SOURCE)
struct NoPair : UserQueries {  // a query source whose pair() is hidden
 private:
  using UserQueries::pair;
};
void use(const BvhView& bvh, const NoPair& queries) {
  auto emit = [](int32_t, int32_t) {};
  NoWork work;
  run_query<BoxShape>(bvh, queries, 0, emit, work);
}
#endif

}  // namespace minkq
