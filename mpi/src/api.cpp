// The C functions of minkq_mpi.h: each rank's checks, the collective phases, the results.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <unordered_map>

#include "collective.h"
#include "staging.h"
#include "scene.h"

using namespace minkq::mpi;

namespace {

// A buffer of `count` records of `size` bytes, checked; `name` in messages. Device memory is
// for CUDA devices, whose buffers are staged through the host.
void check_buffer(const minkq_device* device, const minkq_buffer& b, size_t size, size_t count, const char* name,
                  const char* of) {
  require(b.memory == MINKQ_MEMORY_HOST || b.memory == MINKQ_MEMORY_DEVICE, MINKQ_ERROR_INVALID_ARGUMENT,
          std::string(name) + ".memory is not a minkq_memory");
  require(b.memory == MINKQ_MEMORY_HOST || minkq_device_backend(device) == MINKQ_BACKEND_CUDA,
          MINKQ_ERROR_INVALID_ARGUMENT,
          std::string(name) + " is device memory (MINKQ_MEMORY_DEVICE) but the rank's device " +
              minkq_device_name(device) + " is not a CUDA device");
  require(b.count == count, MINKQ_ERROR_INVALID_ARGUMENT,
          std::string(name) + " has " + std::to_string(b.count) + " entries but there are " + std::to_string(count) + " " +
              of);
  require(b.byte_stride == 0 || b.byte_stride >= size, MINKQ_ERROR_INVALID_ARGUMENT,
          std::string(name) + ".byte_stride " + std::to_string(b.byte_stride) + " is under the element's " +
              std::to_string(size) + " bytes");
  require(b.data != nullptr || count == 0, MINKQ_ERROR_INVALID_ARGUMENT, std::string(name) + ".data is NULL");
}

// A buffer's records, packed, on the host.
template <class T, int N>
std::vector<T> read(const minkq_device* device, const minkq_buffer& b, size_t count, const char* name, const char* of) {
  check_buffer(device, b, N * sizeof(T), count, name, of);
  const size_t stride = b.byte_stride ? b.byte_stride : N * sizeof(T);
  std::vector<T> out(N * count);
  if (count == 0) return out;
  if (b.memory == MINKQ_MEMORY_DEVICE) {
    stage_from_device(out.data(), N * sizeof(T), b.data, stride, count, name);
    return out;
  }
  const char* p = static_cast<const char*>(b.data);
  for (size_t i = 0; i < count; ++i) std::memcpy(out.data() + N * i, p + i * stride, N * sizeof(T));
  return out;
}

std::string vertex_name(const SceneState& s, size_t v) {
  return "vertex " + std::to_string(v) + " (global id " + std::to_string(s.vertex_ids[v]) + ")";
}

// New local positions, checked: the vertex count and finite coordinates.
std::vector<float> checked_positions(const SceneState& s, minkq_buffer vertices, const char* call) {
  require(vertices.count == s.vertex_ids.size(), MINKQ_ERROR_INVALID_ARGUMENT,
          std::string(call) + " with " + std::to_string(vertices.count) + " vertices but the rank has " +
              std::to_string(s.vertex_ids.size()));
  std::vector<float> xyz = read<float, 3>(s.device, vertices, vertices.count, "vertices", "vertices");
  for (size_t v = 0; v < vertices.count; ++v)
    if (!std::isfinite(xyz[3 * v]) || !std::isfinite(xyz[3 * v + 1]) || !std::isfinite(xyz[3 * v + 2]))
      fail(MINKQ_ERROR_NON_FINITE, vertex_name(s, v) + " has a non-finite coordinate (" + std::to_string(xyz[3 * v]) +
                                       ", " + std::to_string(xyz[3 * v + 1]) + ", " + std::to_string(xyz[3 * v + 2]) + ")");
  return xyz;
}

// A call on a NULL scene cannot reach the others: it fails here, alone.
minkq_status lone_failure(minkq_status status, const std::string& message) {
  set_last_error(message);
  return status;
}

template <class Call>
minkq_status guarded(Call&& call) {
  try {
    const minkq_status status = call();
    if (status == MINKQ_SUCCESS) set_last_error("");
    return status;
  } catch (const Failure& f) {
    return lone_failure(f.status, f.what());
  } catch (const std::bad_alloc&) {
    return lone_failure(MINKQ_ERROR_OUT_OF_MEMORY, "out of host memory");
  } catch (const std::exception& e) {
    return lone_failure(MINKQ_ERROR_INTERNAL, e.what());
  }
}

// One phase of local checks on a rank whose rank number names the failure.
template <class Work>
minkq_status checked_phase(const SceneState& s, Work&& work) {
  return phase(s.comm, [&] {
    try {
      work();
    } catch (const Failure& f) {
      throw Failure(f.status, "rank " + std::to_string(s.rank) + ": " + f.what());
    }
  });
}

minkq_status move(minkq_mpi_scene* scene, minkq_buffer vertices, bool rebuild) {
  if (!scene) return lone_failure(MINKQ_ERROR_INVALID_ARGUMENT, "scene is NULL");
  return guarded([&] {
    std::vector<float> xyz;
    const minkq_status status = checked_phase(
        *scene, [&] { xyz = checked_positions(*scene, vertices, rebuild ? "minkq_mpi_scene_rebuild" : "minkq_mpi_scene_refit"); });
    if (status) return status;
    // The copies' positions from their owners; a failed exchange (every rank fails it together)
    // leaves the positions as they were.
    std::swap(scene->xyz, xyz);
    try {
      exchange_halo(*scene);
    } catch (...) {
      std::swap(scene->xyz, xyz);
      throw;
    }
    for (LocalScene* local : {&scene->vt, &scene->ee}) (rebuild ? local->rebuild : local->refit) = true;
    return MINKQ_SUCCESS;
  });
}

}  // namespace

extern "C" {

minkq_status minkq_mpi_scene_create(MPI_Comm comm, minkq_device* device, const minkq_mpi_scene_desc* desc,
                                    minkq_mpi_scene** out_scene) {
  if (out_scene) *out_scene = nullptr;
  return guarded([&]() -> minkq_status {
    int initialized = 0;
    MPI_Initialized(&initialized);
    require(initialized, MINKQ_ERROR_INVALID_ARGUMENT, "MPI is not initialised: call MPI_Init first");
    require(comm != MPI_COMM_NULL, MINKQ_ERROR_INVALID_ARGUMENT, "comm is MPI_COMM_NULL");
    struct Release {
      void operator()(minkq_mpi_scene* s) const { minkq_mpi_scene_release(s); }
    };
    std::unique_ptr<minkq_mpi_scene, Release> s(new minkq_mpi_scene());
    mpi_check(MPI_Comm_dup(comm, &s->comm), "MPI_Comm_dup");
    MPI_Comm_set_errhandler(s->comm, MPI_ERRORS_RETURN);
    MPI_Comm_rank(s->comm, &s->rank);
    MPI_Comm_size(s->comm, &s->size);
    s->device = device;

    // ---- Each rank's own part.
    std::vector<int32_t> triangles;
    std::vector<int64_t> triangle_ids;
    std::vector<uint8_t> triangle_owned;
    minkq_status status = checked_phase(*s, [&] {
      require(out_scene != nullptr, MINKQ_ERROR_INVALID_ARGUMENT, "out_scene is NULL");
      require(device != nullptr, MINKQ_ERROR_INVALID_ARGUMENT, "device is NULL");
      require(desc != nullptr, MINKQ_ERROR_INVALID_ARGUMENT, "desc is NULL");
      const uint32_t known = MINKQ_SCENE_VT | MINKQ_SCENE_EE | MINKQ_SCENE_DROP_INCIDENT | MINKQ_SCENE_FLOAT64 |
                             MINKQ_SCENE_VV | MINKQ_SCENE_EV;
      require((desc->flags & ~known) == 0, MINKQ_ERROR_INVALID_ARGUMENT, "desc->flags has unknown bits");
      require(!(desc->flags & (MINKQ_SCENE_FLOAT64 | MINKQ_SCENE_VV | MINKQ_SCENE_EV)), MINKQ_ERROR_UNSUPPORTED,
              "desc->flags: MINKQ_SCENE_FLOAT64, MINKQ_SCENE_VV and MINKQ_SCENE_EV are not distributed yet");
      require(desc->flags & (MINKQ_SCENE_VT | MINKQ_SCENE_EE), MINKQ_ERROR_INVALID_ARGUMENT,
              "desc->flags asks for no query: set MINKQ_SCENE_VT, MINKQ_SCENE_EE or both");
      s->flags = desc->flags;
      const size_t nv = desc->vertices.count, nt = desc->triangles.count;
      require(nv <= size_t(INT32_MAX) - 1 && nt <= size_t(INT32_MAX) - 1, MINKQ_ERROR_SIZE_OVERFLOW,
              "over 2^31 - 2 local vertices or triangles");
      s->vertex_ids = read<int64_t, 1>(device, desc->vertex_ids, nv, "vertex_ids", "vertices");
      s->vertex_owned = read<uint8_t, 1>(device, desc->vertex_owned, nv, "vertex_owned", "vertices");
      triangles = read<int32_t, 3>(device, desc->triangles, nt, "triangles", "triangles");
      triangle_ids = read<int64_t, 1>(device, desc->triangle_ids, nt, "triangle_ids", "triangles");
      triangle_owned = read<uint8_t, 1>(device, desc->triangle_owned, nt, "triangle_owned", "triangles");
      std::unordered_map<int64_t, int32_t>& seen = s->local_index;
      seen.reserve(nv);
      for (size_t v = 0; v < nv; ++v) {
        require(s->vertex_ids[v] >= 0, MINKQ_ERROR_INVALID_ARGUMENT,
                "vertex " + std::to_string(v) + " has a negative global id " + std::to_string(s->vertex_ids[v]));
        require(s->vertex_owned[v] <= 1, MINKQ_ERROR_INVALID_ARGUMENT,
                "vertex_owned[" + std::to_string(v) + "] is " + std::to_string(s->vertex_owned[v]) + ", not 0 or 1");
        const auto [it, added] = seen.emplace(s->vertex_ids[v], int32_t(v));
        require(added, MINKQ_ERROR_INVALID_ARGUMENT,
                "vertices " + std::to_string(it->second) + " and " + std::to_string(v) + " have the same global id " +
                    std::to_string(s->vertex_ids[v]));
      }
      s->xyz = checked_positions(*s, desc->vertices, "minkq_mpi_scene_create");
      std::unordered_map<int64_t, size_t> triangle_seen;
      for (size_t t = 0; t < nt; ++t) {
        for (int k = 0; k < 3; ++k)
          require(triangles[3 * t + k] >= 0 && size_t(triangles[3 * t + k]) < nv, MINKQ_ERROR_INDEX_OUT_OF_RANGE,
                  "triangle " + std::to_string(t) + " references vertex " + std::to_string(triangles[3 * t + k]) +
                      " but the rank has " + std::to_string(nv) + " vertices");
        require(triangle_ids[t] >= 0, MINKQ_ERROR_INVALID_ARGUMENT,
                "triangle " + std::to_string(t) + " has a negative global id " + std::to_string(triangle_ids[t]));
        require(triangle_owned[t] <= 1, MINKQ_ERROR_INVALID_ARGUMENT,
                "triangle_owned[" + std::to_string(t) + "] is " + std::to_string(triangle_owned[t]) + ", not 0 or 1");
        const auto [it, added] = triangle_seen.emplace(triangle_ids[t], t);
        require(added, MINKQ_ERROR_INVALID_ARGUMENT,
                "triangles " + std::to_string(it->second) + " and " + std::to_string(t) + " have the same global id " +
                    std::to_string(triangle_ids[t]));
      }
      minkq_status made = minkq_result_create(&s->local_result);
      require(made == MINKQ_SUCCESS, made, minkq_last_error_message());
    });
    if (status) return status;
    // Every rank takes part in the same collectives from here on.
    int flags_min = int(s->flags), flags_max = int(s->flags);
    mpi_check(MPI_Allreduce(MPI_IN_PLACE, &flags_min, 1, MPI_INT, MPI_MIN, s->comm), "MPI_Allreduce");
    mpi_check(MPI_Allreduce(MPI_IN_PLACE, &flags_max, 1, MPI_INT, MPI_MAX, s->comm), "MPI_Allreduce");
    status = checked_phase(*s, [&] {
      require(flags_min == flags_max, MINKQ_ERROR_INVALID_ARGUMENT, "desc->flags differ between the ranks");
    });
    if (status) return status;
    for (uint8_t owned : s->vertex_owned) (owned ? s->owned_vertices : s->copied_vertices) += 1;
    if ((status = setup_ownership(*s, triangles, triangle_ids, triangle_owned))) return status;
    exchange_halo(*s);
    if ((s->flags & MINKQ_SCENE_EE) && (status = setup_edges(*s))) return status;
    for (LocalScene* local : {&s->vt, &s->ee}) local->rebuild = true;
    *out_scene = s.release();
    return MINKQ_SUCCESS;
  });
}

void minkq_mpi_scene_release(minkq_mpi_scene* scene) {
  if (!scene) return;
  minkq_scene_release(scene->vt.scene);
  minkq_scene_release(scene->ee.scene);
  minkq_result_release(scene->local_result);
  if (scene->comm != MPI_COMM_NULL) MPI_Comm_free(&scene->comm);
  delete scene;
}

minkq_status minkq_mpi_scene_refit(minkq_mpi_scene* scene, minkq_buffer vertices) { return move(scene, vertices, false); }
minkq_status minkq_mpi_scene_rebuild(minkq_mpi_scene* scene, minkq_buffer vertices) { return move(scene, vertices, true); }

minkq_status minkq_mpi_scene_set_skin(minkq_mpi_scene* scene, double skin) {
  if (!scene) return lone_failure(MINKQ_ERROR_INVALID_ARGUMENT, "scene is NULL");
  return guarded([&] {
    minkq_status status = checked_phase(*scene, [&] {
      require(std::isfinite(skin), MINKQ_ERROR_NON_FINITE, "the skin " + std::to_string(skin) + " is not finite");
      require(skin >= 0, MINKQ_ERROR_INVALID_ARGUMENT, "the skin " + std::to_string(skin) + " is negative");
    });
    if (status) return status;
    double range[2] = {skin, -skin};
    mpi_check(MPI_Allreduce(MPI_IN_PLACE, range, 2, MPI_DOUBLE, MPI_MIN, scene->comm), "MPI_Allreduce");
    status = checked_phase(*scene, [&] {
      require(range[0] == -range[1], MINKQ_ERROR_INVALID_ARGUMENT,
              "the skins differ between the ranks (from " + std::to_string(range[0]) + " to " +
                  std::to_string(-range[1]) + ")");
    });
    if (status) return status;
    scene->skin = skin;
    scene->vt.pattern.valid = scene->ee.pattern.valid = false;
    return MINKQ_SUCCESS;
  });
}

minkq_status minkq_mpi_scene_tree_growth(minkq_mpi_scene* scene, double* out_growth) {
  if (!scene) return lone_failure(MINKQ_ERROR_INVALID_ARGUMENT, "scene is NULL");
  return guarded([&] {
    double growth = 1;
    minkq_status status = checked_phase(*scene, [&] {
      require(out_growth != nullptr, MINKQ_ERROR_INVALID_ARGUMENT, "out_growth is NULL");
      for (const LocalScene* local : {&scene->vt, &scene->ee}) {
        double g = 1;
        if (local->scene && minkq_scene_tree_growth(local->scene, &g) == MINKQ_SUCCESS) growth = std::max(growth, g);
      }
    });
    if (status) return status;
    mpi_check(MPI_Allreduce(MPI_IN_PLACE, &growth, 1, MPI_DOUBLE, MPI_MAX, scene->comm), "MPI_Allreduce");
    *out_growth = growth;
    return MINKQ_SUCCESS;
  });
}

minkq_status minkq_mpi_result_create(minkq_mpi_result** out_result) {
  return guarded([&] {
    require(out_result != nullptr, MINKQ_ERROR_INVALID_ARGUMENT, "out_result is NULL");
    *out_result = new minkq_mpi_result();
    return MINKQ_SUCCESS;
  });
}
void minkq_mpi_result_release(minkq_mpi_result* result) { delete result; }
uint64_t minkq_mpi_result_count(const minkq_mpi_result* result) { return result ? result->count : 0; }
const int64_t* minkq_mpi_result_pairs(const minkq_mpi_result* result) {
  return result && result->has_pairs && result->count ? result->pairs.data() : nullptr;
}
minkq_query_stats minkq_mpi_result_stats(const minkq_mpi_result* result) {
  return result ? result->stats : minkq_query_stats{};
}

minkq_status minkq_mpi_scene_query(minkq_mpi_scene* scene, const minkq_query_desc* query, minkq_mpi_result* result) {
  if (!scene) return lone_failure(MINKQ_ERROR_INVALID_ARGUMENT, "scene is NULL");
  if (result) result->pairs.clear(), result->count = 0, result->has_pairs = false, result->stats = {};
  return guarded([&] {
    minkq_status status = checked_phase(*scene, [&] {
      require(query != nullptr, MINKQ_ERROR_INVALID_ARGUMENT, "query is NULL");
      require(result != nullptr, MINKQ_ERROR_INVALID_ARGUMENT, "result is NULL");
      require(query->kind == MINKQ_QUERY_VT || query->kind == MINKQ_QUERY_EE, MINKQ_ERROR_INVALID_ARGUMENT,
              "query->kind: a distributed scene answers MINKQ_QUERY_VT and MINKQ_QUERY_EE");
      const uint32_t needs = query->kind == MINKQ_QUERY_VT ? MINKQ_SCENE_VT : MINKQ_SCENE_EE;
      require(scene->flags & needs, MINKQ_ERROR_INVALID_ARGUMENT,
              std::string("query->kind: the scene was created without ") +
                  (needs == MINKQ_SCENE_VT ? "MINKQ_SCENE_VT" : "MINKQ_SCENE_EE"));
      require(int(query->mode) >= int(MINKQ_MODE_BOX) && int(query->mode) <= int(MINKQ_MODE_CAPSULE_EXACT), MINKQ_ERROR_INVALID_ARGUMENT,
              "query->mode is not a minkq_mode");
      require(!(query->kind == MINKQ_QUERY_EE && query->mode == MINKQ_MODE_SPHERE), MINKQ_ERROR_INVALID_ARGUMENT,
              "query->mode: sphere is a point query (VT); EE takes box, capsule_ray or capsule_exact");
      const uint32_t known = MINKQ_QUERY_LEAF_EXACT | MINKQ_QUERY_CANONICAL | MINKQ_QUERY_DIGEST | MINKQ_QUERY_STATS |
                             MINKQ_QUERY_COUNT;
      require((query->flags & ~known) == 0, MINKQ_ERROR_INVALID_ARGUMENT, "query->flags has unknown bits");
      require(!(query->flags & MINKQ_QUERY_DIGEST), MINKQ_ERROR_UNSUPPORTED,
              "query->flags: MINKQ_QUERY_DIGEST is not distributed (each rank holds a share of the pairs)");
      require(!((query->flags & MINKQ_QUERY_COUNT) && (query->flags & MINKQ_QUERY_CANONICAL)),
              MINKQ_ERROR_INVALID_ARGUMENT, "query->flags: MINKQ_QUERY_COUNT with MINKQ_QUERY_CANONICAL");
      require(std::isfinite(query->radius), MINKQ_ERROR_NON_FINITE, "query->radius is not finite");
      require(query->radius >= 0, MINKQ_ERROR_INVALID_ARGUMENT, "query->radius is negative");
    });
    if (status) return status;
    if ((status = prepare_local_scene(*scene, query->kind, query->radius))) return status;
    const LocalScene& local = query->kind == MINKQ_QUERY_VT ? scene->vt : scene->ee;
    const auto started = std::chrono::steady_clock::now();
    status = checked_phase(*scene, [&] {
      if (!local.scene) {
        result->has_pairs = !(query->flags & MINKQ_QUERY_COUNT);
        return;
      }
      // EE keeps the pairs whose lower edge is owned here, so even a count needs the pairs.
      const bool count_only = (query->flags & MINKQ_QUERY_COUNT) && query->kind == MINKQ_QUERY_VT;
      minkq_query_desc q = *query;
      q.flags &= ~uint32_t(MINKQ_QUERY_CANONICAL);
      if (!count_only) q.flags &= ~uint32_t(MINKQ_QUERY_COUNT);
      const minkq_status ran = minkq_scene_query_result(local.scene, &q, scene->local_result);
      require(ran == MINKQ_SUCCESS, ran, std::string("minkq_scene_query_result: ") + minkq_last_error_message());
      result->stats = minkq_result_stats(scene->local_result);
      if (count_only) {
        result->count = minkq_result_count(scene->local_result);
        return;
      }
      const int32_t* p = minkq_result_pairs(scene->local_result);
      const size_t n = size_t(minkq_result_count(scene->local_result));
      std::vector<int64_t>& out = result->pairs;
      out.reserve(2 * n);
      if (query->kind == MINKQ_QUERY_VT) {
        for (size_t i = 0; i < n; ++i)
          out.push_back(local.vertex_ids[size_t(p[2 * i])]), out.push_back(local.element_ids[size_t(p[2 * i + 1])]);
      } else {
        for (size_t i = 0; i < n; ++i) {
          size_t e = size_t(p[2 * i]), f = size_t(p[2 * i + 1]);
          if (local.element_ids[e] > local.element_ids[f]) std::swap(e, f);
          if (local.owned[e]) out.push_back(local.element_ids[e]), out.push_back(local.element_ids[f]);
        }
      }
      result->count = out.size() / 2;
      if (query->flags & MINKQ_QUERY_COUNT) {
        out.clear();
        return;
      }
      result->has_pairs = true;
      if (query->flags & MINKQ_QUERY_CANONICAL) {
        std::vector<std::pair<int64_t, int64_t>> sorted(result->count);
        for (size_t i = 0; i < sorted.size(); ++i) sorted[i] = {out[2 * i], out[2 * i + 1]};
        std::sort(sorted.begin(), sorted.end());
        for (size_t i = 0; i < sorted.size(); ++i) out[2 * i] = sorted[i].first, out[2 * i + 1] = sorted[i].second;
      }
    });
    scene->last.query_ms = elapsed_ms(started);
    if (status) result->pairs.clear(), result->count = 0, result->has_pairs = false, result->stats = {};
    return status;
  });
}

minkq_status minkq_mpi_scene_rank_info(const minkq_mpi_scene* scene, minkq_mpi_rank_info* out_info) {
  if (!scene) return lone_failure(MINKQ_ERROR_INVALID_ARGUMENT, "scene is NULL");
  if (!out_info) return lone_failure(MINKQ_ERROR_INVALID_ARGUMENT, "out_info is NULL");
  minkq_mpi_rank_info& i = *out_info;
  i.owned_vertices = scene->owned_vertices;
  i.owned_triangles = scene->triangle_ids.size();
  i.owned_edges = scene->edges.size();
  i.copied_vertices = scene->copied_vertices;
  i.ghost_vertices = scene->vt.ghosts;
  i.ghost_edges = scene->ee.ghosts;
  i.neighbours = scene->neighbours;
  i.global_edges = scene->global_edges;
  i.local_builds = scene->builds;
  i.local_refits = scene->refits;
  i.ghost_exchanges = scene->exchanges;
  i.ghost_updates = scene->updates;
  i.bytes_sent = scene->bytes_sent;
  i.last_bytes_sent = scene->last.bytes;
  i.last_reach_ms = scene->last.reach_ms;
  i.last_ghost_ms = scene->last.ghost_ms;
  i.last_trees_ms = scene->last.trees_ms;
  i.last_query_ms = scene->last.query_ms;
  set_last_error("");
  return MINKQ_SUCCESS;
}

}  // extern "C"
