// The leaf layout of a tree's elements: four consecutive leaf positions' triangles or edges by
// lane, as a BoxGroup holds their boxes (bvh.h), the form the stores keep them in; their boxes
// by leaf position for a refit (LeafBoxes), and the incidence test four lanes at once.
#pragma once

#include "minkq/elements.h"
#include "minkq/simd.h"

namespace minkq {

// A tree's elements (triangles or edges) at four consecutive leaf positions, by lane as a
// BoxGroup holds their boxes: the store keeps a tree's elements in this form only, so that its
// leaf filters read them in leaf order, four at a time on the host, and a refit reads them
// sequentially (LeafBoxes). Lanes past the last element hold -1 (no vertex).
template <class Prim>
struct LeafGroup {
  static constexpr int kVertices = int(sizeof(Prim) / sizeof(int32_t));
  int32_t v[kVertices][4];
  // The element in lane k.
  MINKQ_HD Prim at(int k) const {
    Prim e;
    for (int j = 0; j < kVertices; ++j) e.v[j] = v[j][k];
    return e;
  }
  MINKQ_HD void set(int k, const Prim& e) {
    for (int j = 0; j < kVertices; ++j) v[j][k] = e.v[j];
  }
};
// The element at leaf position p of a tree whose elements `groups` holds.
template <class Prim>
MINKQ_HD Prim leaf_element(const LeafGroup<Prim>* groups, int64_t p) {
  return groups[p >> 2].at(int(p & 3));
}
using TriangleGroup = LeafGroup<Triangle>;
using EdgeGroup = LeafGroup<Edge>;
static_assert(sizeof(TriangleGroup) == 48 && sizeof(EdgeGroup) == 32, "a group holds four elements and nothing else");

// Group g of the tree whose leaf order is sorted_prims (n elements), from the elements by id.
template <class Prim>
MINKQ_HD void fill_leaf_group(int64_t g, const Prim* prims, const int32_t* sorted_prims, int32_t n,
                              LeafGroup<Prim>& out) {
  for (int k = 0; k < 4; ++k) {
    const int64_t p = 4 * g + k;
    Prim none;
    for (int j = 0; j < LeafGroup<Prim>::kVertices; ++j) none.v[j] = -1;
    out.set(k, p < n ? prims[sorted_prims[p]] : none);
  }
}
// The inverse: group g's elements back to their ids (a rebuild reads the elements by id).
template <class Prim>
MINKQ_HD void scatter_leaf_group(int64_t g, const LeafGroup<Prim>& group, const int32_t* sorted_prims, int32_t n,
                                 Prim* prims) {
  for (int k = 0; k < 4; ++k)
    if (4 * g + k < n) prims[sorted_prims[4 * g + k]] = group.at(k);
}

// The lanes of `lanes` whose element has vertex a or vertex b (a vertex's own triangles or
// edges: a == b; the edges sharing a vertex with edge (a, b)): has_vertex and share_vertex,
// lane by lane.
template <class Prim>
MINKQ_HD unsigned incident_lanes(const LeafGroup<Prim>& g, int32_t a, int32_t b, unsigned lanes) {
#if defined(__CUDACC__)
  return lanes_where(lanes, [&](int k) {
    bool any = false;
    for (int j = 0; j < LeafGroup<Prim>::kVertices; ++j) any |= g.v[j][k] == a || g.v[j][k] == b;
    return any;
  });
#else
  simd4::M4 any = {0, 0, 0, 0};
  for (int j = 0; j < LeafGroup<Prim>::kVertices; ++j) {
    const simd4::M4 u = simd4::load(g.v[j]);
    any |= (u == a) | (u == b);
  }
  return lanes & simd4::mask_bits(any);
#endif
}

// The box of the element at leaf position p, from the elements in leaf order (a refit's
// source: kByLeafPosition, refit.h).
template <class Prim>
struct LeafBoxes {
  static constexpr bool kByLeafPosition = true;
  const Vec3* vertices;
  const LeafGroup<Prim>* groups;
  const Vec3* vertices1 = nullptr;  // swept: the positions at t = 1
  MINKQ_HD Box operator()(int32_t p) const { return element_box(vertices, vertices1, leaf_element(groups, p)); }
  MINKQ_HD float thickness_of(const float* thickness, int32_t p) const {
    return element_thickness(thickness, leaf_element(groups, p));
  }
};

}  // namespace minkq
