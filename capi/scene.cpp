// The C ABI: mesh scenes, their topology, and their updates (refit, rebuild, swept, reserve,
// stream-ordered).
#include "front_end.h"

using namespace minkq::capi;

namespace {

// Every distinct undirected triangle edge as (min, max), in lexicographic order. A triangle
// with a repeated vertex contributes its zero-length edge (v, v) too.
std::vector<minkq::Edge> derive_edges(const std::vector<minkq::Triangle>& triangles) {
  std::vector<uint64_t> keys;
  keys.reserve(triangles.size() * 3);
  for (const auto& t : triangles)
    for (int k = 0; k < 3; ++k) {
      const int32_t a = t.v[k], b = t.v[(k + 1) % 3];  // non-negative (require_indices ran)
      keys.push_back(minkq::pack_pair(std::min(a, b), std::max(a, b)));
    }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  std::vector<minkq::Edge> edges(keys.size());
  for (size_t i = 0; i < keys.size(); ++i) {
    const minkq::Pair pair = minkq::unpack_pair(keys[i]);
    edges[i] = {{pair.first, pair.second}};
  }
  return edges;
}

// New vertex positions for a scene, validated: `verb` names the call in messages.
minkq::Strided checked_vertices(const minkq_scene* scene, minkq_buffer vertices, const char* verb,
                                const char* what = "vertices") {
  require(scene != nullptr, Status::kInvalidArgument, "scene is NULL");
  const minkq::Strided values = checked_vertex_buffer(scene->device, vertices, scene->flags, what);
  require(size_t(values.count) == scene->vertex_count, Status::kInvalidArgument,
          std::string(verb) + " with " + std::to_string(values.count) + " " + vertices_named(what) +
              " but the scene has " + std::to_string(scene->vertex_count));
  const std::string element = std::string(what) == "vertices" ? "vertex" : std::string(what) + " vertex";
  require_finite(*scene->device->backend, values, 3, element.c_str());
  return values;
}

// New vertex positions for an asynchronous refit or rebuild, validated as far as the host can
// (their coordinates are checked on the device), with the reservation the call needs.
minkq::Strided checked_async_vertices(const minkq_scene* scene, minkq_buffer vertices, const char* call,
                                      bool rebuild, bool swept = false, const char* what = "vertices") {
  require(scene != nullptr, Status::kInvalidArgument, "scene is NULL");
  const minkq::Reservation& reserved = scene->store->reservation();
  require((rebuild ? reserved.rebuild : reserved.refit) && (!swept || reserved.swept), Status::kInvalidArgument,
          std::string(call) + " needs scratch reserved first: minkq_scene_reserve(scene, " +
              (rebuild ? "MINKQ_RESERVE_REBUILD" : "MINKQ_RESERVE_REFIT") + (swept ? " | MINKQ_RESERVE_SWEPT" : "") +
              ", ...)");
  const minkq::Strided values = checked_vertex_buffer(scene->device, vertices, scene->flags, what);
  require(enum_value(vertices.memory) == async_memory(scene->device), Status::kInvalidArgument,
          std::string(what) + " are host memory but " + call + " on " + scene->device->name +
              " reads device memory (MINKQ_MEMORY_DEVICE)");
  require(size_t(values.count) == scene->vertex_count, Status::kInvalidArgument,
          std::string(call) + " with " + std::to_string(values.count) + " " + vertices_named(what) +
              " but the scene has " + std::to_string(scene->vertex_count));
  return values;
}

}  // namespace

extern "C" {

minkq_status minkq_scene_create(minkq_device* device, const minkq_scene_desc* desc, minkq_scene** out_scene) {
  return guarded([&] {
    require(out_scene != nullptr, Status::kInvalidArgument, "out_scene is NULL");
    *out_scene = nullptr;
    require(device != nullptr, Status::kInvalidArgument, "device is NULL");
    require(desc != nullptr, Status::kInvalidArgument, "desc is NULL");
    const uint32_t kinds = MINKQ_SCENE_VT | MINKQ_SCENE_EE | MINKQ_SCENE_VV | MINKQ_SCENE_EV;
    const uint32_t known = kinds | MINKQ_SCENE_DROP_INCIDENT | MINKQ_SCENE_FLOAT64;
    require((desc->flags & ~known) == 0, Status::kInvalidArgument, "desc->flags has unknown bits");
    require(desc->flags & kinds, Status::kInvalidArgument,
            "desc->flags asks for no query: set one or more of MINKQ_SCENE_VT, MINKQ_SCENE_EE, MINKQ_SCENE_VV and "
            "MINKQ_SCENE_EV");
    minkq::Backend& backend = *device->backend;
    const minkq::Strided vertices = checked_vertex_buffer(device, desc->vertices, desc->flags);
    const minkq::Strided triangles = checked_buffer(device, desc->triangles, 12, "triangles");
    const minkq::Strided edges = checked_buffer(device, desc->edges, 8, "edges");
    require_tree_size(size_t(vertices.count), "vertices.count");
    require_tree_size(size_t(triangles.count), "triangles.count");
    require_tree_size(size_t(edges.count), "edges.count");
    require_finite(backend, vertices, 3, "vertex");
    auto scene = std::make_unique<minkq_scene>();
    scene->device = device;
    scene->flags = desc->flags;
    scene->vertex_count = size_t(vertices.count);
    std::vector<minkq::Triangle> triangle_list = host_copy<minkq::Triangle>(backend, triangles);
    require_indices<3>(triangle_list, scene->vertex_count, "triangle");
    std::vector<minkq::Edge> edge_list;
    if (edges.count > 0) {
      edge_list = host_copy<minkq::Edge>(backend, edges);
      require_indices<2>(edge_list, scene->vertex_count, "edge");
    } else if (desc->flags & (MINKQ_SCENE_EE | MINKQ_SCENE_EV)) {
      edge_list = derive_edges(triangle_list);
      require_tree_size(edge_list.size(), "the triangles' edges");
    }
    scene->triangle_count = triangle_list.size();
    scene->edge_count = edge_list.size();
    minkq::MeshTrees trees;
    trees.triangles = desc->flags & MINKQ_SCENE_VT;
    trees.edges = desc->flags & (MINKQ_SCENE_EE | MINKQ_SCENE_EV);
    trees.vertices = desc->flags & MINKQ_SCENE_VV;
    trees.vertex_order = desc->flags & (MINKQ_SCENE_VT | MINKQ_SCENE_EV);
    scene->store = backend.create_mesh_store(vertices, std::move(triangle_list), std::move(edge_list), trees);
    *out_scene = scene.release();
  });
}

void minkq_scene_release(minkq_scene* scene) { delete scene; }
size_t minkq_scene_vertex_count(const minkq_scene* scene) { return scene ? scene->vertex_count : 0; }
size_t minkq_scene_triangle_count(const minkq_scene* scene) { return scene ? scene->triangle_count : 0; }
size_t minkq_scene_edge_count(const minkq_scene* scene) { return scene ? scene->edge_count : 0; }

minkq_status minkq_scene_edges(const minkq_scene* scene, int32_t* out_edges, size_t capacity) {
  return guarded([&] {
    require(scene != nullptr, Status::kInvalidArgument, "scene is NULL");
    require(capacity == 0 || out_edges != nullptr, Status::kInvalidArgument, "out_edges is NULL");
    require(scene->edge_count <= capacity, Status::kCapacity,
            "the scene has " + std::to_string(scene->edge_count) + " edges but the buffer holds " +
                std::to_string(capacity));
    if (scene->edge_count) scene->store->copy_edges(reinterpret_cast<minkq::Edge*>(out_edges));
  });
}

minkq_status minkq_scene_refit(minkq_scene* scene, minkq_buffer vertices) {
  return guarded([&] {
    const minkq::Strided values = checked_vertices(scene, vertices, "refit");  // checks scene first
    scene->store->refit(values);
  });
}

minkq_status minkq_scene_rebuild(minkq_scene* scene, minkq_buffer vertices) {
  return guarded([&] {
    const minkq::Strided values = checked_vertices(scene, vertices, "rebuild");  // checks scene first
    scene->store->rebuild(values);
  });
}

minkq_status minkq_scene_refit_swept(minkq_scene* scene, minkq_buffer x0, minkq_buffer x1) {
  return guarded([&] {
    const minkq::Strided start = checked_vertices(scene, x0, "refit_swept", "x0");  // checks scene first
    const minkq::Strided end = checked_vertices(scene, x1, "refit_swept", "x1");
    scene->store->refit_swept(start, end);
  });
}

minkq_status minkq_scene_rebuild_swept(minkq_scene* scene, minkq_buffer x0, minkq_buffer x1) {
  return guarded([&] {
    const minkq::Strided start = checked_vertices(scene, x0, "rebuild_swept", "x0");  // checks scene first
    const minkq::Strided end = checked_vertices(scene, x1, "rebuild_swept", "x1");
    scene->store->rebuild_swept(start, end);
  });
}

int minkq_scene_is_swept(const minkq_scene* scene) { return scene && scene->store->swept() ? 1 : 0; }

minkq_status minkq_scene_tree_growth(const minkq_scene* scene, double* out_growth) {
  return guarded([&] {
    require(scene != nullptr, Status::kInvalidArgument, "scene is NULL");
    require(out_growth != nullptr, Status::kInvalidArgument, "out_growth is NULL");
    *out_growth = scene->store->tree_growth();
  });
}

constexpr uint32_t kKnownReserveFlags = MINKQ_RESERVE_REFIT | MINKQ_RESERVE_REBUILD | MINKQ_RESERVE_SWEPT;

minkq_status minkq_scene_reserve(minkq_scene* scene, uint32_t flags, size_t canonical_capacity) {
  return guarded([&] {
    require(scene != nullptr, Status::kInvalidArgument, "scene is NULL");
    require((flags & ~kKnownReserveFlags) == 0, Status::kInvalidArgument, "flags has unknown bits");
    require(canonical_capacity <= SIZE_MAX / (2 * sizeof(uint64_t)), Status::kSizeOverflow,
            "canonical_capacity " + std::to_string(canonical_capacity) + " pairs overflows the address space");
    minkq::Reservation wanted;
    wanted.refit = (flags & (MINKQ_RESERVE_REFIT | MINKQ_RESERVE_REBUILD)) != 0;
    wanted.rebuild = (flags & MINKQ_RESERVE_REBUILD) != 0;
    wanted.swept = (flags & MINKQ_RESERVE_SWEPT) != 0;
    wanted.canonical_capacity = canonical_capacity;
    scene->store->reserve(wanted);
  });
}

minkq_status minkq_scene_refit_async(minkq_scene* scene, minkq_buffer vertices, minkq_stream stream) {
  return guarded([&] {
    const minkq::Strided values = checked_async_vertices(scene, vertices, "minkq_scene_refit_async", false);
    scene->store->refit_async(values, stream);
  });
}

minkq_status minkq_scene_rebuild_async(minkq_scene* scene, minkq_buffer vertices, minkq_stream stream) {
  return guarded([&] {
    const minkq::Strided values = checked_async_vertices(scene, vertices, "minkq_scene_rebuild_async", true);
    scene->store->rebuild_async(values, stream);
  });
}

minkq_status minkq_scene_refit_swept_async(minkq_scene* scene, minkq_buffer x0, minkq_buffer x1, minkq_stream stream) {
  return guarded([&] {
    const char* call = "minkq_scene_refit_swept_async";
    const minkq::Strided start = checked_async_vertices(scene, x0, call, false, true, "x0");
    const minkq::Strided end = checked_async_vertices(scene, x1, call, false, true, "x1");
    scene->store->refit_swept_async(start, end, stream);
  });
}

minkq_status minkq_scene_rebuild_swept_async(minkq_scene* scene, minkq_buffer x0, minkq_buffer x1,
                                             minkq_stream stream) {
  return guarded([&] {
    const char* call = "minkq_scene_rebuild_swept_async";
    const minkq::Strided start = checked_async_vertices(scene, x0, call, true, true, "x0");
    const minkq::Strided end = checked_async_vertices(scene, x1, call, true, true, "x1");
    scene->store->rebuild_swept_async(start, end, stream);
  });
}

minkq_status minkq_scene_async_status(minkq_scene* scene, minkq_stream stream) {
  return guarded([&] {
    require(scene != nullptr, Status::kInvalidArgument, "scene is NULL");
    const minkq::PendingError pending = scene->store->take_pending_error(stream);
    if (pending.call == minkq::PendingError::kNone) return;
    using Call = minkq::PendingError::Call;
    const bool rebuild = pending.call == Call::kRebuild || pending.call == Call::kRebuildSwept;
    const bool swept = pending.call == Call::kRefitSwept || pending.call == Call::kRebuildSwept;
    const std::string call = std::string("minkq_scene_") + (rebuild ? "rebuild" : "refit") + (swept ? "_swept" : "") + "_async";
    fail(Status::kNonFinite, call + ": vertex " + std::to_string(pending.vertex) +
                                 (swept ? " has a non-finite coordinate (in x0 or x1); the scene kept its positions, at rest"
                                        : " has a non-finite coordinate; the scene kept its positions") +
                                 (rebuild ? " and built its trees for them" : ""));
  });
}

}  // extern "C"
