// Splitting one whole mesh into ranks' parts, for minkq-mpi and the distributed tests: the
// partitions a simulator might use (slabs, Morton-order chunks) and the worst case (a random
// rank for every triangle and, independently, for every vertex).
#pragma once

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "minkq/morton.h"  // spread_bits_21

namespace minkq::mpi_tools {

enum class Partition { kSlab, kMorton, kRandom };

inline Partition parse_partition(const std::string& name) {
  if (name == "slab") return Partition::kSlab;
  if (name == "morton") return Partition::kMorton;
  if (name == "random") return Partition::kRandom;
  throw std::invalid_argument("unknown partition '" + name + "' (slab, morton, random)");
}
inline const char* partition_name(Partition p) {
  return p == Partition::kSlab ? "slab" : p == Partition::kMorton ? "morton" : "random";
}

// Who owns what: a rank for every triangle and every vertex of the whole mesh.
struct Owners {
  std::vector<int> triangle, vertex;
};

namespace detail {
// Splits `order` (elements sorted by a key) into `ranks` equal runs.
inline void chunks(const std::vector<size_t>& order, int ranks, std::vector<int>& owner) {
  for (size_t i = 0; i < order.size(); ++i) owner[order[i]] = int(i * size_t(ranks) / order.size());
}
}  // namespace detail

// Triangles by their centroids (slabs along x, or chunks of the Morton order); each vertex
// goes with its lowest-index triangle, a vertex of no triangle to rank v % ranks. Random:
// every triangle and every vertex drawn independently.
inline Owners partition(const std::vector<float>& xyz, const std::vector<int32_t>& tris, int ranks, Partition kind,
                        uint64_t seed) {
  const size_t nv = xyz.size() / 3, nt = tris.size() / 3;
  Owners o;
  o.triangle.assign(nt, 0), o.vertex.assign(nv, -1);
  std::mt19937_64 rng(seed);
  if (kind == Partition::kRandom) {
    std::uniform_int_distribution<int> pick(0, ranks - 1);
    for (int& r : o.triangle) r = pick(rng);
    for (int& r : o.vertex) r = pick(rng);
    return o;
  }
  std::vector<float> c(3 * nt);
  float lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
  for (size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) {
      c[3 * t + k] = (xyz[3 * size_t(tris[3 * t]) + k] + xyz[3 * size_t(tris[3 * t + 1]) + k] +
                      xyz[3 * size_t(tris[3 * t + 2]) + k]) / 3;
      lo[k] = t ? std::min(lo[k], c[3 * t + k]) : c[3 * t + k];
      hi[k] = t ? std::max(hi[k], c[3 * t + k]) : c[3 * t + k];
    }
  std::vector<size_t> order(nt);
  std::iota(order.begin(), order.end(), size_t(0));
  if (kind == Partition::kSlab) {
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return c[3 * a] < c[3 * b]; });
  } else {
    std::vector<uint64_t> code(nt);
    for (size_t t = 0; t < nt; ++t) {
      uint64_t m = 0;
      for (int k = 0; k < 3; ++k) {
        const float extent = hi[k] - lo[k];
        const double unit = extent > 0 ? (c[3 * t + k] - lo[k]) / extent : 0.0;
        m |= minkq::spread_bits_21(uint32_t(std::min(unit, 1.0) * double((1 << 21) - 1))) << k;
      }
      code[t] = m;
    }
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return code[a] < code[b]; });
  }
  detail::chunks(order, ranks, o.triangle);
  for (size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k) {
      int& owner = o.vertex[size_t(tris[3 * t + k])];
      if (owner < 0) owner = o.triangle[t];
    }
  for (size_t v = 0; v < nv; ++v)
    if (o.vertex[v] < 0) o.vertex[v] = int(v % size_t(ranks));
  return o;
}

// One rank's part, as minkq_mpi_scene_create takes it: its owned triangles and vertices, the
// corners of its triangles, and (with `copies`) copies of the triangles that share a vertex
// with its own, as a halo of a simulator's partition would hold. Global ids are the whole
// mesh's indices. With `shuffle` the local order is drawn at random, else it is by global id.
struct Part {
  std::vector<float> xyz;
  std::vector<int32_t> tris;
  std::vector<int64_t> vertex_ids, triangle_ids;
  std::vector<uint8_t> vertex_owned, triangle_owned;
  size_t vertex_count() const { return vertex_ids.size(); }
  size_t triangle_count() const { return triangle_ids.size(); }
};

inline Part part_of(const std::vector<float>& xyz, const std::vector<int32_t>& tris, const Owners& owners, int rank,
                    bool copies = false, bool shuffle = false, uint64_t seed = 0) {
  const size_t nv = xyz.size() / 3, nt = tris.size() / 3;
  std::vector<uint8_t> has_vertex(nv, 0), has_triangle(nt, 0);
  for (size_t v = 0; v < nv; ++v) has_vertex[v] = owners.vertex[v] == rank;
  for (size_t t = 0; t < nt; ++t) has_triangle[t] = owners.triangle[t] == rank;
  if (copies) {  // triangles sharing a vertex with an owned one
    std::vector<uint8_t> near(nv, 0);
    for (size_t t = 0; t < nt; ++t)
      if (has_triangle[t])
        for (int k = 0; k < 3; ++k) near[size_t(tris[3 * t + k])] = 1;
    for (size_t t = 0; t < nt; ++t)
      for (int k = 0; k < 3; ++k) has_triangle[t] |= near[size_t(tris[3 * t + k])];
  }
  for (size_t t = 0; t < nt; ++t)
    if (has_triangle[t])
      for (int k = 0; k < 3; ++k) has_vertex[size_t(tris[3 * t + k])] = 1;
  std::vector<int64_t> vs, ts;
  for (size_t v = 0; v < nv; ++v)
    if (has_vertex[v]) vs.push_back(int64_t(v));
  for (size_t t = 0; t < nt; ++t)
    if (has_triangle[t]) ts.push_back(int64_t(t));
  if (shuffle) {
    std::mt19937_64 rng(seed * 1000003 + uint64_t(rank));
    std::shuffle(vs.begin(), vs.end(), rng);
    std::shuffle(ts.begin(), ts.end(), rng);
  }
  Part p;
  std::vector<int32_t> local(nv, -1);
  for (size_t i = 0; i < vs.size(); ++i) {
    const size_t v = size_t(vs[i]);
    local[v] = int32_t(i);
    p.xyz.insert(p.xyz.end(), xyz.begin() + 3 * v, xyz.begin() + 3 * v + 3);
    p.vertex_ids.push_back(vs[i]);
    p.vertex_owned.push_back(owners.vertex[v] == rank);
  }
  for (int64_t t : ts) {
    for (int k = 0; k < 3; ++k) p.tris.push_back(local[size_t(tris[3 * size_t(t) + k])]);
    p.triangle_ids.push_back(t);
    p.triangle_owned.push_back(owners.triangle[size_t(t)] == rank);
  }
  return p;
}

// A rank's local positions in its part's order, from the whole mesh's positions `xyz` (a step's
// positions of the mesh the part was cut from).
inline std::vector<float> local_positions(const std::vector<float>& xyz, const Part& part) {
  std::vector<float> local;
  local.reserve(3 * part.vertex_count());
  for (int64_t v : part.vertex_ids) local.insert(local.end(), xyz.begin() + 3 * v, xyz.begin() + 3 * v + 3);
  return local;
}

}  // namespace minkq::mpi_tools
