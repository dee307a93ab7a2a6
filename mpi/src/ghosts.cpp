// The ghost layer of one query, and the local minkq scene over it.
//
// A rank's reach is a set of boxes over its owned triangles (VT) or owned edges (EE), which
// hold every element it reports pairs for: up to kReachBoxes boxes of runs of them in Morton
// order, so that a rank whose elements are scattered (a Morton chunk of a twisted sheet, a
// graph partition) does not draw in everything inside one large box. A rank sends another
// the vertices (VT) or edges (EE) it owns whose boxes, grown by R, overlap a box of that
// rank's reach (found with a minkq bvh over the reach boxes), with R = r (1 + 2^-12) + 2^-12 M and M
// the largest coordinate magnitude of the mesh: a margin far above the rounding of any of
// minkq's tests (leaf tests keep pairs within r + 2^-19 of the elements' size and distance),
// so every pair a single-process query reports has both elements on the rank that reports it.
// The margin is relative: the same mesh scaled gives the same ghosts.
#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <unordered_map>

#include "collective.h"
#include "minkq/morton.h"  // spread_bits_21
#include "scene.h"

namespace minkq::mpi {

namespace {

struct Box {
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  void add(const float* p) {
    for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], double(p[k])), hi[k] = std::max(hi[k], double(p[k]));
  }
  bool empty() const { return lo[0] > hi[0]; }
  // Whether this box grown by g overlaps `other` (never for an empty box).
  bool reaches(const Box& other, double g) const {
    if (empty() || other.empty()) return false;
    for (int k = 0; k < 3; ++k)
      if (lo[k] - g > other.hi[k] || hi[k] + g < other.lo[k]) return false;
    return true;
  }
};

struct GhostVertex {
  int64_t id;
  float p[3];
  int32_t unused;
};
struct GhostEdge {
  int64_t id;
  int64_t v[2];
  float p[2][3];
};

constexpr int kReachBoxes = 64;

// This rank's reach (what it reports pairs for, in up to kReachBoxes boxes; the rest empty),
// the box of its sources (what it may send as ghosts), and its coordinates' magnitude.
struct Extent {
  Box reach[kReachBoxes];
  Box source;
  double magnitude = 0;  // largest |coordinate| of its owned vertices
  Box reach_bounds() const {
    Box all;
    for (const Box& b : reach)
      if (!b.empty())
        for (int k = 0; k < 3; ++k) all.lo[k] = std::min(all.lo[k], b.lo[k]), all.hi[k] = std::max(all.hi[k], b.hi[k]);
    return all;
  }
  bool reached_by(const Box& b, double grow) const {
    if (!b.reaches(reach_bounds(), grow)) return false;
    for (const Box& r : reach)
      if (b.reaches(r, grow)) return true;
    return false;
  }
};
constexpr int kExtentDoubles = 6 * (kReachBoxes + 1) + 1;

// The boxes of elements grouped into kReachBoxes runs of `order`: their centres' Morton order,
// found at the first query and kept (the elements stay; a grouping that has moved since stays
// correct, only looser).
void group_boxes(const std::vector<Box>& boxes, std::vector<uint32_t>& order, Box* out) {
  if (order.size() != boxes.size()) {
    Box bounds;
    for (const Box& b : boxes)
      for (int k = 0; k < 3; ++k)
        bounds.lo[k] = std::min(bounds.lo[k], b.lo[k]), bounds.hi[k] = std::max(bounds.hi[k], b.hi[k]);
    std::vector<std::pair<uint64_t, uint32_t>> coded(boxes.size());
    for (size_t i = 0; i < boxes.size(); ++i) {
      uint64_t code = 0;
      for (int k = 0; k < 3; ++k) {
        const double extent = bounds.hi[k] - bounds.lo[k];
        const double centre = 0.5 * (boxes[i].lo[k] + boxes[i].hi[k]);
        const double unit = extent > 0 ? (centre - bounds.lo[k]) / extent : 0.0;
        code |= minkq::spread_bits_21(uint32_t(std::min(std::max(unit, 0.0), 1.0) * 2097151.0)) << k;
      }
      coded[i] = {code, uint32_t(i)};
    }
    std::sort(coded.begin(), coded.end());
    order.resize(boxes.size());
    for (size_t i = 0; i < coded.size(); ++i) order[i] = coded[i].second;
  }
  for (size_t i = 0; i < order.size(); ++i) {
    Box& group = out[i * kReachBoxes / order.size()];
    const Box& b = boxes[order[i]];
    for (int k = 0; k < 3; ++k) group.lo[k] = std::min(group.lo[k], b.lo[k]), group.hi[k] = std::max(group.hi[k], b.hi[k]);
  }
}

Box box_of(const float* x, const int32_t* v, int per) {
  Box b;
  for (int i = 0; i < per; ++i) b.add(x + 3 * size_t(v[i]));
  return b;
}

Extent extent(SceneState& s, minkq_query_kind kind) {
  Extent e;
  const float* x = s.xyz.data();
  for (size_t v = 0; v < s.vertex_owned.size(); ++v)
    if (s.vertex_owned[v])
      for (int k = 0; k < 3; ++k) e.magnitude = std::max(e.magnitude, std::fabs(double(x[3 * v + k])));
  std::vector<Box> elements;
  elements.reserve(kind == MINKQ_QUERY_VT ? s.triangle_ids.size() : s.edges.size());
  if (kind == MINKQ_QUERY_VT) {
    for (size_t t = 0; t < s.triangle_ids.size(); ++t) elements.push_back(box_of(x, &s.triangles[3 * t], 3));
    for (size_t v = 0; v < s.vertex_owned.size(); ++v)
      if (s.vertex_owned[v]) e.source.add(x + 3 * v);
  } else {
    for (const OwnedEdge& edge : s.edges) {
      const int32_t ends[2] = {edge.a, edge.b};
      elements.push_back(box_of(x, ends, 2));
      e.source.add(x + 3 * size_t(edge.a)), e.source.add(x + 3 * size_t(edge.b));
    }
  }
  group_boxes(elements, (kind == MINKQ_QUERY_VT ? s.vt : s.ee).reach_order, e.reach);
  return e;
}

void check_local(minkq_status status, const char* call) {
  if (status) fail(status, std::string(call) + ": " + minkq_last_error_message());
}

// A box grown by g, as floats rounded outward: what the bvh tests compare exactly.
void grown_corners(const Box& b, double g, float* lo, float* hi) {
  for (int k = 0; k < 3; ++k) {
    lo[k] = float(b.lo[k] - g), hi[k] = float(b.hi[k] + g);
    if (double(lo[k]) > b.lo[k] - g) lo[k] = std::nextafter(lo[k], -INFINITY);
    if (double(hi[k]) < b.hi[k] + g) hi[k] = std::nextafter(hi[k], INFINITY);
  }
}

// For each destination, which of `boxes` (this rank's source elements) grown by g overlap one
// of its reach boxes: one minkq bvh over the destinations' boxes, one box query.
std::vector<std::vector<uint32_t>> select(minkq_device* device, const std::vector<Box>& boxes, double g,
                                          const std::vector<int>& dests, const std::vector<Extent>& extents) {
  std::vector<std::vector<uint32_t>> chosen(dests.size());
  std::vector<float> reach;
  std::vector<uint32_t> reach_dest;
  for (size_t i = 0; i < dests.size(); ++i)
    for (const Box& b : extents[size_t(dests[i])].reach)
      if (!b.empty()) {
        for (int k = 0; k < 3; ++k) reach.push_back(float(b.lo[k]));  // floats exactly: boxes of floats
        for (int k = 0; k < 3; ++k) reach.push_back(float(b.hi[k]));
        reach_dest.push_back(uint32_t(i));
      }
  if (reach_dest.empty() || boxes.empty()) return chosen;
  std::vector<float> lo(3 * boxes.size()), hi(3 * boxes.size());
  for (size_t i = 0; i < boxes.size(); ++i) grown_corners(boxes[i], g, &lo[3 * i], &hi[3 * i]);
  minkq_bvh* bvh = nullptr;
  check_local(minkq_bvh_create(device, minkq_buffer{reach.data(), 0, reach_dest.size(), MINKQ_MEMORY_HOST}, &bvh),
        "minkq_bvh_create");
  std::unique_ptr<minkq_bvh, void (*)(minkq_bvh*)> owned(bvh, minkq_bvh_release);
  minkq_bvh_query_desc q{MINKQ_SHAPE_BOX, MINKQ_MODE_BOX, 0, 0.0f,
                         minkq_buffer{lo.data(), 0, boxes.size(), MINKQ_MEMORY_HOST},
                         minkq_buffer{hi.data(), 0, boxes.size(), MINKQ_MEMORY_HOST}};
  std::vector<int32_t> pairs(2 * std::max<size_t>(boxes.size(), 64));
  minkq_query_info info{};
  minkq_status status = minkq_bvh_query(bvh, &q, pairs.data(), pairs.size() / 2, MINKQ_MEMORY_HOST, &info);
  if (status == MINKQ_ERROR_CAPACITY) {
    pairs.resize(2 * size_t(info.count));
    status = minkq_bvh_query(bvh, &q, pairs.data(), pairs.size() / 2, MINKQ_MEMORY_HOST, &info);
  }
  check_local(status, "minkq_bvh_query");
  std::vector<uint64_t> keys(size_t(info.count));  // (destination, element), deduplicated
  for (size_t i = 0; i < keys.size(); ++i)
    keys[i] = uint64_t(reach_dest[size_t(pairs[2 * i + 1])]) << 32 | uint32_t(pairs[2 * i]);
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  for (uint64_t k : keys) chosen[size_t(k >> 32)].push_back(uint32_t(k));
  return chosen;
}

// The local scene's arrays for this query, before they go into a minkq scene.
struct Assembly {
  std::vector<float> xyz;
  std::vector<int64_t> vertex_ids;
  std::vector<int32_t> elements;  // 3 (VT) or 2 (EE) scene vertex indices each
  std::vector<int64_t> element_ids;
  std::vector<uint8_t> owned;
  std::vector<int64_t> signature;
  std::vector<std::vector<int32_t>> targets;  // per source: the scene vertex of each position
  uint64_t ghosts = 0;
  const std::unordered_map<int64_t, int32_t>& local;  // the rank's own vertices (SceneState)
  std::unordered_map<int64_t, int32_t> added;         // ghost vertices it does not hold

  explicit Assembly(const SceneState& s) : xyz(s.xyz), vertex_ids(s.vertex_ids), local(s.local_index) {}
  // The scene vertex of a ghost's vertex (received from the last source begun), added once.
  int32_t vertex(int64_t id, const float* p) {
    int32_t v;
    if (const auto mine = local.find(id); mine != local.end()) {
      v = mine->second;
    } else {
      const auto [it, is_new] = added.emplace(id, int32_t(vertex_ids.size()));
      if (is_new) vertex_ids.push_back(id), xyz.insert(xyz.end(), p, p + 3);
      v = it->second;
    }
    targets.back().push_back(v);
    return v;
  }
  void begin_source(int rank) { signature.push_back(-1 - rank), targets.emplace_back(); }
};

// Refits or rebuilds the local trees for new positions, as the last move asks.
void move_trees(SceneState& s, LocalScene& local, const minkq_buffer& vertices) {
  const auto t0 = std::chrono::steady_clock::now();
  if (local.rebuild)
    check_local(minkq_scene_rebuild(local.scene, vertices), "minkq_scene_rebuild"), ++s.builds;
  else if (local.refit)
    check_local(minkq_scene_refit(local.scene, vertices), "minkq_scene_refit"), ++s.refits;
  s.last.trees_ms += elapsed_ms(t0);
}

void require_local_size(size_t n, const char* what) {
  require(n <= size_t(INT32_MAX) - 1, MINKQ_ERROR_SIZE_OVERFLOW,
          std::string("the local scene with its ghosts has more than 2^31 - 2 ") + what);
}

// Brings `local` to the assembled arrays: refit or rebuild when its members are unchanged,
// else a new scene.
void update(SceneState& s, LocalScene& local, minkq_query_kind kind, Assembly& a) {
  const size_t per = kind == MINKQ_QUERY_VT ? 3 : 2;
  const size_t n = a.elements.size() / per;
  require_local_size(a.vertex_ids.size(), "vertices");
  require_local_size(n, kind == MINKQ_QUERY_VT ? "triangles" : "edges");
  const minkq_buffer vertices{a.xyz.data(), 12, a.vertex_ids.size(), MINKQ_MEMORY_HOST};
  const bool same = local.scene && a.signature == local.signature;
  if (same) {
    move_trees(s, local, vertices);
  } else {
    minkq_scene* fresh = nullptr;
    if (n > 0) {
      minkq_scene_desc desc{};
      desc.flags = (kind == MINKQ_QUERY_VT ? MINKQ_SCENE_VT : MINKQ_SCENE_EE) | (s.flags & MINKQ_SCENE_DROP_INCIDENT);
      desc.vertices = vertices;
      const minkq_buffer elements{a.elements.data(), 4 * per, n, MINKQ_MEMORY_HOST};
      (kind == MINKQ_QUERY_VT ? desc.triangles : desc.edges) = elements;
      const auto t0 = std::chrono::steady_clock::now();
      check_local(minkq_scene_create(s.device, &desc, &fresh), "minkq_scene_create");
      s.last.trees_ms += elapsed_ms(t0);
      ++s.builds;
    }
    minkq_scene_release(local.scene);
    local.scene = fresh;
    local.signature = std::move(a.signature);
  }
  local.pattern.targets = std::move(a.targets);
  local.pattern.xyz = std::move(a.xyz);
  local.vertex_ids = std::move(a.vertex_ids);
  local.element_ids = std::move(a.element_ids);
  local.owned = std::move(a.owned);
  local.refit = local.rebuild = false;
  local.ghosts = a.ghosts;
}

}  // namespace

namespace {

// With a skin: whether the last exchange's pattern still holds, every vertex having moved at
// most skin / 2 on each axis since (so two elements' boxes came at most one skin closer).
bool pattern_holds(const SceneState& s, const LocalScene& local, float radius) {
  if (!(s.skin > 0)) return false;
  double moved = local.pattern.valid && local.pattern.radius == radius ? 0.0 : INFINITY;
  for (size_t v = 0; v < s.vertex_owned.size() && moved <= s.skin; ++v)
    if (s.vertex_owned[v])
      for (int k = 0; k < 3; ++k)
        moved = std::max(moved, std::fabs(double(s.xyz[3 * v + k]) - double(local.pattern.reference[3 * v + k])));
  mpi_check(MPI_Allreduce(MPI_IN_PLACE, &moved, 1, MPI_DOUBLE, MPI_MAX, s.comm), "MPI_Allreduce");
  return moved <= 0.5 * s.skin;
}

// The ghosts' new positions along the pattern's messages, then the trees refit (or rebuilt).
minkq_status move_ghosts(SceneState& s, LocalScene& local, minkq_query_kind kind) {
  LocalScene::Pattern& p = local.pattern;
  const float* x = s.xyz.data();
  std::vector<std::vector<float>> send(p.dests.size());
  for (size_t i = 0; i < p.dests.size(); ++i)
    for (int32_t k : p.sent[i]) {
      if (kind == MINKQ_QUERY_VT) {
        send[i].insert(send[i].end(), x + 3 * size_t(k), x + 3 * size_t(k) + 3);
      } else {
        const OwnedEdge& e = s.edges[size_t(k)];
        send[i].insert(send[i].end(), x + 3 * size_t(e.a), x + 3 * size_t(e.a) + 3);
        send[i].insert(send[i].end(), x + 3 * size_t(e.b), x + 3 * size_t(e.b) + 3);
      }
    }
  s.last.bytes += payload(send);
  const auto in = neighbour_exchange(s.comm, p.dests, send, p.sources);
  return phase(s.comm, [&] {
    std::copy(s.xyz.begin(), s.xyz.end(), p.xyz.begin());
    for (size_t j = 0; j < in.size(); ++j)
      for (size_t t = 0; t < p.targets[j].size(); ++t)
        std::copy(in[j].begin() + 3 * t, in[j].begin() + 3 * t + 3, p.xyz.begin() + 3 * size_t(p.targets[j][t]));
    if (local.scene) move_trees(s, local, minkq_buffer{p.xyz.data(), 12, p.xyz.size() / 3, MINKQ_MEMORY_HOST});
    local.refit = local.rebuild = false;
    ++s.updates;
  });
}

}  // namespace

namespace {

minkq_status exchange_and_update(SceneState& s, minkq_query_kind kind, float radius) {
  const auto t0 = std::chrono::steady_clock::now();
  LocalScene& local = kind == MINKQ_QUERY_VT ? s.vt : s.ee;
  if (pattern_holds(s, local, radius)) {
    s.last.reach_ms = elapsed_ms(t0);
    return move_ghosts(s, local, kind);
  }
  local.pattern.valid = false;
  // Every rank's reach and sources, and the mesh's magnitude, in one all-gather.
  const Extent mine = extent(s, kind);
  std::vector<double> packed;
  packed.reserve(kExtentDoubles);
  for (const Box* b = mine.reach; b != mine.reach + kReachBoxes + 1; ++b) {
    const Box& box = b == mine.reach + kReachBoxes ? mine.source : *b;
    packed.insert(packed.end(), box.lo, box.lo + 3), packed.insert(packed.end(), box.hi, box.hi + 3);
  }
  packed.push_back(mine.magnitude);
  std::vector<double> all(kExtentDoubles * size_t(s.size));
  mpi_check(MPI_Allgather(packed.data(), kExtentDoubles, MPI_DOUBLE, all.data(), kExtentDoubles, MPI_DOUBLE, s.comm),
            "MPI_Allgather");
  std::vector<Extent> extents(s.size);
  double magnitude = 0;
  for (int p = 0; p < s.size; ++p) {
    const double* e = all.data() + kExtentDoubles * size_t(p);
    for (int b = 0; b <= kReachBoxes; ++b) {
      Box& box = b == kReachBoxes ? extents[p].source : extents[p].reach[b];
      std::copy(e + 6 * b, e + 6 * b + 3, box.lo), std::copy(e + 6 * b + 3, e + 6 * b + 6, box.hi);
    }
    magnitude = std::max(magnitude, e[kExtentDoubles - 1]);
  }
  s.last.reach_ms = elapsed_ms(t0);
  // With a skin s the layer is s wider, and the margin covers coordinates up to s / 2 larger.
  const double grow = double(radius) * (1 + 0x1p-12) + 0x1p-12 * (magnitude + 0.5 * s.skin) + s.skin;
  std::vector<int> dests, sources;
  for (int p = 0; p < s.size; ++p) {
    if (p == s.rank) continue;
    if (extents[p].reached_by(extents[s.rank].source, grow)) dests.push_back(p);
    if (extents[s.rank].reached_by(extents[p].source, grow)) sources.push_back(p);
  }
  std::vector<int> partners = dests;
  partners.insert(partners.end(), sources.begin(), sources.end());
  std::sort(partners.begin(), partners.end());
  s.neighbours = uint64_t(std::unique(partners.begin(), partners.end()) - partners.begin());

  // The elements this rank may send (local vertex or owned edge indices) and their boxes.
  const float* x = s.xyz.data();
  std::vector<int32_t> candidates;
  std::vector<Box> boxes;
  if (dests.empty()) {
    // Nothing to send: no candidates.
  } else if (kind == MINKQ_QUERY_VT) {
    for (size_t v = 0; v < s.vertex_owned.size(); ++v)
      if (s.vertex_owned[v]) candidates.push_back(int32_t(v)), boxes.push_back(box_of(x, &candidates.back(), 1));
  } else {
    for (size_t k = 0; k < s.edges.size(); ++k) {
      const int32_t ends[2] = {s.edges[k].a, s.edges[k].b};
      candidates.push_back(int32_t(k)), boxes.push_back(box_of(x, ends, 2));
    }
  }
  std::vector<std::vector<int32_t>> sent(dests.size());
  std::vector<std::vector<GhostVertex>> vertices(kind == MINKQ_QUERY_VT ? dests.size() : 0);
  std::vector<std::vector<GhostEdge>> edges(kind == MINKQ_QUERY_EE ? dests.size() : 0);
  minkq_status status = phase(s.comm, [&] {
    const auto chosen = select(s.device, boxes, grow, dests, extents);
    for (size_t i = 0; i < dests.size(); ++i)
      for (uint32_t c : chosen[i]) {
        const int32_t k = candidates[c];
        sent[i].push_back(k);
        if (kind == MINKQ_QUERY_VT) {
          vertices[i].push_back({s.vertex_ids[size_t(k)], {x[3 * k], x[3 * k + 1], x[3 * k + 2]}, 0});
          continue;
        }
        const OwnedEdge& e = s.edges[size_t(k)];
        GhostEdge g{e.id, {s.vertex_ids[e.a], s.vertex_ids[e.b]}, {}};
        std::copy(x + 3 * size_t(e.a), x + 3 * size_t(e.a) + 3, g.p[0]);
        std::copy(x + 3 * size_t(e.b), x + 3 * size_t(e.b) + 3, g.p[1]);
        edges[i].push_back(g);
      }
  });
  if (status) return status;
  Assembly a(s);
  if (kind == MINKQ_QUERY_VT) {
    s.last.bytes += payload(vertices);
    const auto in = neighbour_exchange(s.comm, dests, vertices, sources);
    status = phase(s.comm, [&] {
      for (size_t j = 0; j < in.size(); ++j) {
        a.begin_source(sources[j]);
        for (const GhostVertex& g : in[j]) a.vertex(g.id, g.p), a.signature.push_back(g.id), ++a.ghosts;
      }
      a.elements = s.triangles;
      a.element_ids = s.triangle_ids;
      update(s, local, kind, a);
    });
  } else {
    s.last.bytes += payload(edges);
    const auto in = neighbour_exchange(s.comm, dests, edges, sources);
    status = phase(s.comm, [&] {
      for (const OwnedEdge& e : s.edges) a.elements.push_back(e.a), a.elements.push_back(e.b), a.element_ids.push_back(e.id);
      a.owned.assign(s.edges.size(), 1);
      for (size_t j = 0; j < in.size(); ++j) {
        a.begin_source(sources[j]);
        for (const GhostEdge& g : in[j]) {
          a.elements.push_back(a.vertex(g.v[0], g.p[0]));
          a.elements.push_back(a.vertex(g.v[1], g.p[1]));
          a.element_ids.push_back(g.id), a.owned.push_back(0);
          a.signature.push_back(g.id), ++a.ghosts;
        }
      }
      update(s, local, kind, a);
    });
  }
  if (status) return status;
  ++s.exchanges;
  LocalScene::Pattern& p = local.pattern;
  p.valid = true, p.radius = radius;
  p.dests = std::move(dests), p.sources = std::move(sources), p.sent = std::move(sent);
  p.reference = s.xyz;
  return MINKQ_SUCCESS;
}

}  // namespace

minkq_status prepare_local_scene(SceneState& s, minkq_query_kind kind, float radius) {
  const auto t0 = std::chrono::steady_clock::now();
  s.last = {};
  const minkq_status status = exchange_and_update(s, kind, radius);
  // The ghost phase is what neither the reach boxes nor the trees took.
  s.last.ghost_ms = elapsed_ms(t0) - s.last.reach_ms - s.last.trees_ms;
  s.bytes_sent += s.last.bytes;
  return status;
}

}  // namespace minkq::mpi
