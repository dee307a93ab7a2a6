// Thickness: a scene's geometries may give each vertex a thickness t >= 0 (cloth, shells and
// rods carry one; particles a radius). An element's thickness is the largest of its vertices',
// and a pair of elements a, b is within reach when its distance is <= r + t(a) + t(b). The
// trees hold each element's box grown by its thickness, and a query element tests with radius
// r + t(query): a pair within reach then passes every node test (the grown box holds the
// element's points within t of it, so the query lies within r + t(query) of it). The sums and
// the growth round away from the pair, so float arithmetic never loses one. A null thickness
// array means thickness 0 everywhere, with the same arithmetic as no thickness at all.
#pragma once

#include "minkq/float64.h"
#include "minkq/hd.h"

namespace minkq {

// Vertex v's thickness (0 without a thickness array).
MINKQ_HD float vertex_thickness(const float* thickness, int32_t v) { return thickness ? thickness[v] : 0.0f; }
// An element's thickness: the largest of its vertices' (Prim: Triangle or Edge, vertex ids in v).
template <class Prim>
MINKQ_HD float element_thickness(const float* thickness, const Prim& e) {
  if (!thickness) return 0.0f;
  float t = 0.0f;
  for (int k = 0; k < int(sizeof(Prim) / sizeof(int32_t)); ++k) t = t > thickness[e.v[k]] ? t : thickness[e.v[k]];
  return t;
}

// r + a + b, rounded up past the exact sum (one step more covers the rounding of the double
// sum); r itself when a and b are 0, so that zero thickness changes nothing.
MINKQ_HD float reach(float r, float a, float b = 0.0f) {
  if (a == 0.0f && b == 0.0f) return r;
  return next_up(float_at_or_above(double(r) + double(a) + double(b)));
}

// The box grown by t on every side, rounded outward (b itself for t == 0).
MINKQ_HD Box grow_box(const Box& b, float t) {
  if (t == 0.0f) return b;
  return {{next_down(b.lo.x - t), next_down(b.lo.y - t), next_down(b.lo.z - t)},
          {next_up(b.hi.x + t), next_up(b.hi.y + t), next_up(b.hi.z + t)}};
}

}  // namespace minkq
