// The ghost layer of one query, and the local minkq scene over it.
//
// A rank's reach is the box of its owned triangles (VT) or owned edges (EE), which holds every
// element it reports pairs for. A rank sends another the vertices (VT) or edges (EE) it owns
// whose boxes, grown by R, overlap that rank's reach, with R = r (1 + 2^-12) + 2^-12 M and M
// the largest coordinate magnitude of the mesh: a margin far above the rounding of any of
// minkq's tests (leaf tests keep pairs within r + 2^-19 of the elements' size and distance),
// so every pair a single-process query reports has both elements on the rank that reports it.
// The margin is relative: the same mesh scaled gives the same ghosts.
#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_map>

#include "collective.h"
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

// This rank's reach (what it reports pairs for) and its sources (what it may send as ghosts).
struct Extent {
  Box reach, source;
  double magnitude = 0;  // largest |coordinate| of its owned vertices
};

Extent extent(const SceneState& s, minkq_query_kind kind) {
  Extent e;
  const float* x = s.xyz.data();
  for (size_t v = 0; v < s.vertex_owned.size(); ++v)
    if (s.vertex_owned[v])
      for (int k = 0; k < 3; ++k) e.magnitude = std::max(e.magnitude, std::fabs(double(x[3 * v + k])));
  if (kind == MINKQ_QUERY_VT) {
    for (int32_t v : s.triangles) e.reach.add(x + 3 * size_t(v));
    for (size_t v = 0; v < s.vertex_owned.size(); ++v)
      if (s.vertex_owned[v]) e.source.add(x + 3 * v);
  } else {
    for (const OwnedEdge& edge : s.edges) e.reach.add(x + 3 * size_t(edge.a)), e.reach.add(x + 3 * size_t(edge.b));
    e.source = e.reach;
  }
  return e;
}

// The local scene's arrays for this query, before they go into a minkq scene.
struct Assembly {
  std::vector<float> xyz;
  std::vector<int64_t> vertex_ids;
  std::vector<int32_t> elements;  // 3 (VT) or 2 (EE) scene vertex indices each
  std::vector<int64_t> element_ids;
  std::vector<uint8_t> owned;
  std::vector<int64_t> signature;
  uint64_t ghosts = 0;
  std::unordered_map<int64_t, int32_t> index;  // global vertex id -> scene vertex

  explicit Assembly(const SceneState& s) : xyz(s.xyz), vertex_ids(s.vertex_ids) {
    for (size_t v = 0; v < vertex_ids.size(); ++v) index.emplace(vertex_ids[v], int32_t(v));
  }
  int32_t vertex(int64_t id, const float* p) {
    const auto [it, added] = index.emplace(id, int32_t(vertex_ids.size()));
    if (added) vertex_ids.push_back(id), xyz.insert(xyz.end(), p, p + 3);
    return it->second;
  }
};

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
  auto check = [&](minkq_status status, const char* call) {
    if (status) fail(status, std::string(call) + ": " + minkq_last_error_message());
  };
  const bool same = local.scene && a.signature == local.signature;
  if (same && (local.rebuild || local.refit)) {
    if (local.rebuild)
      check(minkq_scene_rebuild(local.scene, vertices), "minkq_scene_rebuild"), ++s.builds;
    else
      check(minkq_scene_refit(local.scene, vertices), "minkq_scene_refit"), ++s.refits;
  } else if (!same) {
    minkq_scene* fresh = nullptr;
    if (n > 0) {
      minkq_scene_desc desc{};
      desc.flags = (kind == MINKQ_QUERY_VT ? MINKQ_SCENE_VT : MINKQ_SCENE_EE) | (s.flags & MINKQ_SCENE_DROP_INCIDENT);
      desc.vertices = vertices;
      const minkq_buffer elements{a.elements.data(), 4 * per, n, MINKQ_MEMORY_HOST};
      (kind == MINKQ_QUERY_VT ? desc.triangles : desc.edges) = elements;
      check(minkq_scene_create(s.device, &desc, &fresh), "minkq_scene_create");
      ++s.builds;
    }
    minkq_scene_release(local.scene);
    local.scene = fresh;
    local.signature = std::move(a.signature);
  }
  local.vertex_ids = std::move(a.vertex_ids);
  local.element_ids = std::move(a.element_ids);
  local.owned = std::move(a.owned);
  local.refit = local.rebuild = false;
  local.ghosts = a.ghosts;
}

}  // namespace

minkq_status prepare_local_scene(SceneState& s, minkq_query_kind kind, float radius) {
  // Every rank's reach and sources, and the mesh's magnitude, in one all-gather.
  const Extent mine = extent(s, kind);
  std::array<double, 13> packed;
  std::copy(mine.reach.lo, mine.reach.lo + 3, packed.begin());
  std::copy(mine.reach.hi, mine.reach.hi + 3, packed.begin() + 3);
  std::copy(mine.source.lo, mine.source.lo + 3, packed.begin() + 6);
  std::copy(mine.source.hi, mine.source.hi + 3, packed.begin() + 9);
  packed[12] = mine.magnitude;
  std::vector<double> all(13 * size_t(s.size));
  mpi_check(MPI_Allgather(packed.data(), 13, MPI_DOUBLE, all.data(), 13, MPI_DOUBLE, s.comm), "MPI_Allgather");
  std::vector<Extent> extents(s.size);
  double magnitude = 0;
  for (int p = 0; p < s.size; ++p) {
    const double* e = all.data() + 13 * size_t(p);
    std::copy(e, e + 3, extents[p].reach.lo), std::copy(e + 3, e + 6, extents[p].reach.hi);
    std::copy(e + 6, e + 9, extents[p].source.lo), std::copy(e + 9, e + 12, extents[p].source.hi);
    magnitude = std::max(magnitude, e[12]);
  }
  const double grow = double(radius) * (1 + 0x1p-12) + 0x1p-12 * magnitude;
  std::vector<int> dests, sources;
  for (int p = 0; p < s.size; ++p) {
    if (p == s.rank) continue;
    if (extents[s.rank].source.reaches(extents[p].reach, grow)) dests.push_back(p);
    if (extents[p].source.reaches(extents[s.rank].reach, grow)) sources.push_back(p);
  }
  std::vector<int> partners = dests;
  partners.insert(partners.end(), sources.begin(), sources.end());
  std::sort(partners.begin(), partners.end());
  s.neighbours = uint64_t(std::unique(partners.begin(), partners.end()) - partners.begin());

  const float* x = s.xyz.data();
  if (kind == MINKQ_QUERY_VT) {
    std::vector<std::vector<GhostVertex>> send(dests.size());
    for (size_t i = 0; i < dests.size(); ++i)
      for (size_t v = 0; v < s.vertex_owned.size(); ++v) {
        if (!s.vertex_owned[v]) continue;
        Box b;
        b.add(x + 3 * v);
        if (b.reaches(extents[dests[i]].reach, grow))
          send[i].push_back({s.vertex_ids[v], {x[3 * v], x[3 * v + 1], x[3 * v + 2]}, 0});
      }
    const auto in = neighbour_exchange(s.comm, dests, send, sources);
    return phase(s.comm, [&] {
      Assembly a(s);
      for (size_t j = 0; j < in.size(); ++j) {
        a.signature.push_back(-1 - sources[j]);
        for (const GhostVertex& g : in[j]) a.vertex(g.id, g.p), a.signature.push_back(g.id), ++a.ghosts;
      }
      a.elements = s.triangles;
      a.element_ids = s.triangle_ids;
      update(s, s.vt, kind, a);
    });
  }
  std::vector<std::vector<GhostEdge>> send(dests.size());
  for (size_t i = 0; i < dests.size(); ++i)
    for (const OwnedEdge& e : s.edges) {
      Box b;
      b.add(x + 3 * size_t(e.a)), b.add(x + 3 * size_t(e.b));
      if (!b.reaches(extents[dests[i]].reach, grow)) continue;
      GhostEdge g{e.id, {s.vertex_ids[e.a], s.vertex_ids[e.b]}, {}};
      std::copy(x + 3 * size_t(e.a), x + 3 * size_t(e.a) + 3, g.p[0]);
      std::copy(x + 3 * size_t(e.b), x + 3 * size_t(e.b) + 3, g.p[1]);
      send[i].push_back(g);
    }
  const auto in = neighbour_exchange(s.comm, dests, send, sources);
  return phase(s.comm, [&] {
    Assembly a(s);
    for (const OwnedEdge& e : s.edges) a.elements.push_back(e.a), a.elements.push_back(e.b), a.element_ids.push_back(e.id);
    a.owned.assign(s.edges.size(), 1);
    for (size_t j = 0; j < in.size(); ++j) {
      a.signature.push_back(-1 - sources[j]);
      for (const GhostEdge& g : in[j]) {
        a.elements.push_back(a.vertex(g.v[0], g.p[0]));
        a.elements.push_back(a.vertex(g.v[1], g.p[1]));
        a.element_ids.push_back(g.id), a.owned.push_back(0);
        a.signature.push_back(g.id), ++a.ghosts;
      }
    }
    update(s, s.ee, kind, a);
  });
}

}  // namespace minkq::mpi
