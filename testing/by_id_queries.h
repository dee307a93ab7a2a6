// The query sources by id: the leaf filter's verdict on one (query, primitive) pair, reading
// the elements by id where the library's sources (minkq/query_sources.h) read them by leaf
// position in a tree. The brute-force definitions of the candidate sets (scene_definitions.h),
// the Embree reference and the leaf filter tests apply it to every pair; the incidence test is
// stated here element by element (the library tests four lanes at once: incident_lanes), and
// every other test is the library source's own (keeps, geometry_of, geometry).
//
// Each wraps a library source (its leaf-order members unused) with the elements by id, and
// offers geometry(q), the query's geometry by id, accept<Shape>(q, p), whether the leaf filter
// keeps the pair (reached because Shape(q) overlaps p's box), and pair(q, p), the pair reported.
#pragma once

#include "minkq/query_sources.h"

namespace minkq {

// Vertex against triangles (VT) or edges (EV).
template <class Prim>
struct VertexPrimById {
  VertexPrimQueries<Prim> source;
  const Prim* prims;
  QueryGeometry geometry(int32_t v) const { return source.geometry(QueryTarget{v, -1}); }
  template <class Shape>
  bool accept(int32_t v, int32_t t) const {
    if ((source.filters & kDropIncident) && has_vertex(prims[t], v)) return false;
    return source.keeps(v, prims[t]);
  }
  Pair pair(int32_t v, int32_t t) const { return source.pair(v, t); }
};
using VertexTriangleById = VertexPrimById<Triangle>;
using VertexEdgeById = VertexPrimById<Edge>;

// The edges against themselves (EE), each unordered pair once (the caller's e < f).
struct EdgeEdgeById {
  EdgeEdgeQueries source;
  const Edge* edges;
  QueryGeometry geometry(int32_t e) const { return source.geometry_of(edges[e]); }
  template <class Shape>
  bool accept(int32_t e, int32_t f) const {
    if ((source.filters & kDropIncident) && share_vertex(edges[e], edges[f])) return false;
    return source.template keeps<Shape>(e, edges[e], f, edges[f]);
  }
  Pair pair(int32_t e, int32_t f) const { return source.pair(e, f); }
};

// User queries against user boxes: no leaf filter.
struct UserById {
  UserQueries source;
  QueryGeometry geometry(int32_t q) const { return source.geometry(QueryTarget{q, -1}); }
  template <class Shape>
  bool accept(int32_t, int32_t) const {
    return true;
  }
  Pair pair(int32_t q, int32_t b) const { return source.pair(q, b); }
};

}  // namespace minkq
