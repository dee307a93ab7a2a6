// arborx_bench's ArborX helpers (declared in arborx_peer.h): element boxes and trees, count
// reductions, CSR output as pair sets, and EE pairs stored by the half traversal.
#include "arborx_peer.h"

#include <algorithm>

namespace peer {

View<AxBox> triangle_boxes(const Exec& space, const AxMesh& m) {
  View<AxBox> boxes(Kokkos::view_alloc(space, Kokkos::WithoutInitializing, "triangle boxes"), m.tris.extent(0));
  Kokkos::parallel_for(
      "triangle boxes", Kokkos::RangePolicy<Exec>(space, 0, m.tris.extent(0)), KOKKOS_LAMBDA(int i) {
        const Tri t = m.tris(i);
        const AxPoint &a = m.points(t.v[0]), &b = m.points(t.v[1]), &c = m.points(t.v[2]);
        boxes(i) = AxBox{pmin(pmin(a, b), c), pmax(pmax(a, b), c)};
      });
  return boxes;
}
View<AxBox> edge_boxes(const Exec& space, const AxMesh& m) {
  View<AxBox> boxes(Kokkos::view_alloc(space, Kokkos::WithoutInitializing, "edge boxes"), m.edges.extent(0));
  Kokkos::parallel_for(
      "edge boxes", Kokkos::RangePolicy<Exec>(space, 0, m.edges.extent(0)), KOKKOS_LAMBDA(int i) {
        const Seg s = m.edges(i);
        const AxPoint &a = m.points(s.v[0]), &b = m.points(s.v[1]);
        boxes(i) = AxBox{pmin(a, b), pmax(a, b)};
      });
  return boxes;
}
AxBvh build_tree(const Exec& space, const View<AxBox>& boxes) {
  return AxBvh(space, ArborX::Experimental::attach_indices<int>(boxes));
}

uint64_t sum(const Exec& space, const View<int>& counts) {
  uint64_t total = 0;
  Kokkos::parallel_reduce(
      "sum", Kokkos::RangePolicy<Exec>(space, 0, counts.extent(0)),
      KOKKOS_LAMBDA(int i, uint64_t& acc) { acc += uint64_t(counts(i)); }, total);
  return total;
}
int max_count(const Exec& space, const View<int>& offsets) {
  int m = 0;
  Kokkos::parallel_reduce(
      "max", Kokkos::RangePolicy<Exec>(space, 0, offsets.extent(0) - 1),
      KOKKOS_LAMBDA(int i, int& acc) { acc = std::max(acc, offsets(i + 1) - offsets(i)); }, Kokkos::Max<int>(m));
  return m;
}

// CSR (offsets, values) -> sorted pairs (query, value), or (min, max) for symmetric output.
mb::PairSet csr_set(const View<int>& offsets, const View<int>& values, bool symmetric) {
  mb::PairSet s;
  s.reserve(values.extent(0));
  for (size_t q = 0; q + 1 < offsets.extent(0); ++q)
    for (int j = offsets(q); j < offsets(q + 1); ++j) {
      const int a = int(q), b = values(j);
      s.push_back(symmetric ? mb::pack(std::min(a, b), std::max(a, b)) : mb::pack(a, b));
    }
  std::sort(s.begin(), s.end());
  return s;
}

// EE by the half traversal, stored: count per leaf, scan, fill. Leaves offsets/values in CSR.
void half_traversal_store(const Exec& space, const AxBvh& tree, const AxMesh& m, float r, View<int>& counts,
                          View<int>& offsets, View<int>& values) {
  const int n = int(m.edges.extent(0));
  Kokkos::deep_copy(space, counts, 0);
  ArborX::Details::HalfTraversal(space, tree, HalfCount{m.edges, counts}, GrownBoxGetter{r});
  if (int(offsets.extent(0)) != n + 1) offsets = View<int>(Kokkos::view_alloc(Kokkos::WithoutInitializing, "offsets"), n + 1);
  int total = 0;
  Kokkos::parallel_scan(
      "offsets", Kokkos::RangePolicy<Exec>(space, 0, n + 1),
      KOKKOS_LAMBDA(int i, int& acc, bool final) {
        const int c = i < n ? counts(i) : 0;
        if (final) offsets(i) = acc;
        acc += c;
      },
      total);
  if (int(values.extent(0)) != total) values = View<int>(Kokkos::view_alloc(Kokkos::WithoutInitializing, "values"), total);
  Kokkos::deep_copy(space, counts, Kokkos::subview(offsets, Kokkos::make_pair(0, n)));  // counts become cursors
  ArborX::Details::HalfTraversal(space, tree, HalfFill{m.edges, counts, values}, GrownBoxGetter{r});
  space.fence();
}

}  // namespace peer
