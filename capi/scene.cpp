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
// The count a whole-scene refit or rebuild takes, in messages.
std::string moving_vertices(const minkq_scene* scene) {
  const std::string n = std::to_string(scene->moving_vertex_count);
  return scene->geometries.size() == 1 ? "the scene has " + n : "the scene's moving geometries have " + n;
}

// Whole-scene moves take one precision: refused where the moving geometries mix them.
void require_one_precision(const minkq_scene* scene, const std::string& verb) {
  require(!scene->mixed_precision, Status::kInvalidArgument,
          verb + " of the whole scene, whose moving geometries mix float32 and float64 vertices: move "
                 "each with minkq_scene_geometry_" + verb);
}

minkq::Strided checked_vertices(const minkq_scene* scene, minkq_buffer vertices, const char* verb,
                                const char* what = "vertices") {
  require(scene != nullptr, Status::kInvalidArgument, "scene is NULL");
  require_one_precision(scene, verb);
  const minkq::Strided values = checked_vertex_buffer(scene->device, vertices, scene->flags, what);
  require(size_t(values.count) == scene->moving_vertex_count, Status::kInvalidArgument,
          std::string(verb) + " with " + std::to_string(values.count) + " " + vertices_named(what) + " but " +
              moving_vertices(scene));
  const std::string element = std::string(what) == "vertices" ? "vertex" : std::string(what) + " vertex";
  require_finite(*scene->device->backend, values, 3, element.c_str());
  return values;
}

// New vertex positions for an asynchronous refit or rebuild, validated as far as the host can
// (their coordinates are checked on the device), with the reservation the call needs.
minkq::Strided checked_async_vertices(const minkq_scene* scene, minkq_buffer vertices, const char* call,
                                      bool rebuild, bool swept = false, const char* what = "vertices") {
  require(scene != nullptr, Status::kInvalidArgument, "scene is NULL");
  require_one_precision(scene, std::string(rebuild ? "rebuild" : "refit") + (swept ? "_swept" : ""));
  const minkq::Reservation& reserved = scene->store->reservation();
  require((rebuild ? reserved.rebuild : reserved.refit) && (!swept || reserved.swept), Status::kInvalidArgument,
          std::string(call) + " needs scratch reserved first: minkq_scene_reserve(scene, " +
              (rebuild ? "MINKQ_RESERVE_REBUILD" : "MINKQ_RESERVE_REFIT") + (swept ? " | MINKQ_RESERVE_SWEPT" : "") +
              ", ...)");
  const minkq::Strided values = checked_vertex_buffer(scene->device, vertices, scene->flags, what);
  require(enum_value(vertices.memory) == async_memory(scene->device), Status::kInvalidArgument,
          std::string(what) + " are host memory but " + call + " on " + scene->device->name +
              " reads device memory (MINKQ_MEMORY_DEVICE)");
  require(size_t(values.count) == scene->moving_vertex_count, Status::kInvalidArgument,
          std::string(call) + " with " + std::to_string(values.count) + " " + vertices_named(what) + " but " +
              moving_vertices(scene));
  return values;
}

// Geometry g's new positions, validated: `verb` names the call in messages.
minkq::Strided checked_geometry_vertices(const minkq_scene* scene, uint32_t g, minkq_buffer vertices, const char* verb,
                                         const char* what = "vertices") {
  require(scene != nullptr, Status::kInvalidArgument, "scene is NULL");
  const std::string name = "geometry " + std::to_string(g);
  require(g < scene->geometries.size(), Status::kInvalidArgument,
          name + " is out of range: the scene has " + std::to_string(scene->geometries.size()) + " geometries");
  const minkq_scene::Geometry& geometry = scene->geometries[g];
  require(!(geometry.flags & MINKQ_GEOMETRY_STATIC), Status::kInvalidArgument,
          name + " is static (MINKQ_GEOMETRY_STATIC): it is built once and never moves");
  const uint32_t scalar = (geometry.flags & MINKQ_GEOMETRY_FLOAT64) ? uint32_t(MINKQ_SCENE_FLOAT64) : 0u;
  const minkq::Strided values = checked_vertex_buffer(scene->device, vertices, scalar, what);
  require(size_t(values.count) == geometry.count[MINKQ_ELEMENT_VERTEX], Status::kInvalidArgument,
          std::string(verb) + " of " + name + " with " + std::to_string(values.count) + " " + vertices_named(what) +
              " but the geometry has " + std::to_string(geometry.count[MINKQ_ELEMENT_VERTEX]));
  const std::string element = name + ": " + (std::string(what) == "vertices" ? "vertex" : std::string(what) + " vertex");
  require_finite(*scene->device->backend, values, 3, element.c_str());
  return values;
}

constexpr uint32_t kKindBits = MINKQ_SCENE_VT | MINKQ_SCENE_EE | MINKQ_SCENE_VV | MINKQ_SCENE_EV;
constexpr uint32_t kGeometryFlags =
    MINKQ_GEOMETRY_SELF | MINKQ_GEOMETRY_DROP_INCIDENT | MINKQ_GEOMETRY_FLOAT64 | MINKQ_GEOMETRY_STATIC;

// A geometry's thickness, checked: one finite value >= 0 per vertex, or none.
std::vector<float> checked_thickness(minkq_device* device, const minkq_buffer& buffer, size_t vertex_count) {
  if (buffer.count == 0) return {};
  require(buffer.count == vertex_count, Status::kInvalidArgument,
          "thickness.count " + std::to_string(buffer.count) + " is not the vertex count " + std::to_string(vertex_count) +
              " (one thickness per vertex, or none)");
  std::vector<float> thickness = host_copy<float>(*device->backend, checked_buffer(device, buffer, 4, "thickness"));
  for (size_t v = 0; v < thickness.size(); ++v) {
    require(std::isfinite(thickness[v]), Status::kNonFinite,
            "thickness of vertex " + std::to_string(v) + " is " + format_float(thickness[v]) + ", not finite");
    require(thickness[v] >= 0.0f, Status::kInvalidArgument,
            "thickness of vertex " + std::to_string(v) + " is " + format_float(thickness[v]) + ", negative");
  }
  return thickness;
}

// One geometry, checked and copied (its flags and kinds checked by the caller); `owner` names
// what holds the vertices in messages ("scene" or "geometry").
minkq::GeometryInput checked_geometry(minkq_device* device, const minkq_geometry_desc& desc, const char* owner) {
  minkq::Backend& backend = *device->backend;
  const uint32_t scalar = (desc.flags & MINKQ_GEOMETRY_FLOAT64) ? uint32_t(MINKQ_SCENE_FLOAT64) : 0u;
  minkq::GeometryInput in;
  in.vertices = checked_vertex_buffer(device, desc.vertices, scalar);
  const minkq::Strided triangles = checked_buffer(device, desc.triangles, 12, "triangles");
  const minkq::Strided edges = checked_buffer(device, desc.edges, 8, "edges");
  require_tree_size(size_t(in.vertices.count), "vertices.count");
  require_tree_size(size_t(triangles.count), "triangles.count");
  require_tree_size(size_t(edges.count), "edges.count");
  require_finite(backend, in.vertices, 3, "vertex");
  const size_t vertex_count = size_t(in.vertices.count);
  in.triangles = host_copy<minkq::Triangle>(backend, triangles);
  require_indices<3>(in.triangles, vertex_count, "triangle", owner);
  if (edges.count > 0) {
    in.edges = host_copy<minkq::Edge>(backend, edges);
    require_indices<2>(in.edges, vertex_count, "edge", owner);
  } else if (desc.kinds & (MINKQ_SCENE_EE | MINKQ_SCENE_EV)) {
    in.edges = derive_edges(in.triangles);
    require_tree_size(in.edges.size(), "the triangles' edges");
  }
  in.thickness = checked_thickness(device, desc.thickness, vertex_count);
  in.trees.triangles = desc.kinds & MINKQ_SCENE_VT;
  in.trees.edges = desc.kinds & (MINKQ_SCENE_EE | MINKQ_SCENE_EV);
  in.trees.vertices = desc.kinds & MINKQ_SCENE_VV;
  in.trees.vertex_order = desc.kinds & (MINKQ_SCENE_VT | MINKQ_SCENE_EV);
  static const std::pair<uint32_t, minkq::QueryKind> kKinds[] = {
      {MINKQ_SCENE_VT, minkq::QueryKind::kVertexTriangle}, {MINKQ_SCENE_EE, minkq::QueryKind::kEdgeEdge},
      {MINKQ_SCENE_VV, minkq::QueryKind::kVertexVertex}, {MINKQ_SCENE_EV, minkq::QueryKind::kVertexEdge}};
  for (const auto& [bit, kind] : kKinds)
    if (desc.kinds & bit) in.role.kinds |= minkq::kind_bit(kind);
  in.role.self = desc.flags & MINKQ_GEOMETRY_SELF;
  in.role.drop_incident = desc.flags & MINKQ_GEOMETRY_DROP_INCIDENT;
  in.role.is_static = desc.flags & MINKQ_GEOMETRY_STATIC;
  in.role.world = desc.world;
  in.role.group = desc.group;
  in.role.mask = desc.mask;
  return in;
}

// The scene of checked geometries (descriptions beside them, for their flags): its counts and
// numbering, and its store.
minkq_scene* make_scene(minkq_device* device, const std::vector<minkq_geometry_desc>& descs,
                        std::vector<minkq::GeometryInput> inputs) {
  auto scene = std::make_unique<minkq_scene>();
  scene->device = device;
  scene->flags = 0;
  size_t next[3] = {0, 0, 0};
  scene->moving_vertex_count = 0;
  bool moving_float32 = false, moving_float64 = false;
  for (size_t g = 0; g < inputs.size(); ++g) {
    minkq_scene::Geometry geometry{descs[g].flags, {next[0], next[1], next[2]},
                                   {size_t(inputs[g].vertices.count), inputs[g].triangles.size(), inputs[g].edges.size()}};
    for (int k = 0; k < 3; ++k) {
      next[k] += geometry.count[k];
      require(next[k] <= size_t(minkq::kMaxPrimitives), Status::kSizeOverflow,
              std::string("the geometries hold more than 2^31 - 2 ") + (k == 0 ? "vertices" : k == 1 ? "triangles" : "edges") +
                  " in all (global ids are int32)");
    }
    scene->flags |= descs[g].kinds;
    if (!(descs[g].flags & MINKQ_GEOMETRY_STATIC)) {
      scene->moving_vertex_count += geometry.count[0];
      ((descs[g].flags & MINKQ_GEOMETRY_FLOAT64) ? moving_float64 : moving_float32) = true;
    }
    scene->geometries.push_back(geometry);
  }
  if (moving_float64 && !moving_float32) scene->flags |= MINKQ_SCENE_FLOAT64;
  scene->mixed_precision = moving_float64 && moving_float32;
  scene->vertex_count = next[0];
  scene->triangle_count = next[1];
  scene->edge_count = next[2];
  scene->store = device->backend->create_mesh_store(std::move(inputs));
  return scene.release();
}

}  // namespace

extern "C" {

minkq_status minkq_scene_create(minkq_device* device, const minkq_scene_desc* desc, minkq_scene** out_scene) {
  return guarded([&] {
    require(out_scene != nullptr, Status::kInvalidArgument, "out_scene is NULL");
    *out_scene = nullptr;
    require(device != nullptr, Status::kInvalidArgument, "device is NULL");
    require(desc != nullptr, Status::kInvalidArgument, "desc is NULL");
    const uint32_t known = kKindBits | MINKQ_SCENE_DROP_INCIDENT | MINKQ_SCENE_FLOAT64;
    require((desc->flags & ~known) == 0, Status::kInvalidArgument, "desc->flags has unknown bits");
    require(desc->flags & kKindBits, Status::kInvalidArgument,
            "desc->flags asks for no query: set one or more of MINKQ_SCENE_VT, MINKQ_SCENE_EE, MINKQ_SCENE_VV and "
            "MINKQ_SCENE_EV");
    // The scene of one moving geometry with its own pairs.
    minkq_geometry_desc geometry;
    minkq_geometry_desc_init(&geometry);
    geometry.kinds = desc->flags & kKindBits;
    geometry.flags = MINKQ_GEOMETRY_SELF | ((desc->flags & MINKQ_SCENE_DROP_INCIDENT) ? uint32_t(MINKQ_GEOMETRY_DROP_INCIDENT) : 0u) |
                     ((desc->flags & MINKQ_SCENE_FLOAT64) ? uint32_t(MINKQ_GEOMETRY_FLOAT64) : 0u);
    geometry.vertices = desc->vertices;
    geometry.triangles = desc->triangles;
    geometry.edges = desc->edges;
    std::vector<minkq::GeometryInput> inputs;
    inputs.push_back(checked_geometry(device, geometry, "scene"));
    *out_scene = make_scene(device, {geometry}, std::move(inputs));
  });
}

void minkq_geometry_desc_init(minkq_geometry_desc* desc) {
  if (desc == nullptr) return;
  *desc = minkq_geometry_desc{};
  desc->struct_size = sizeof(minkq_geometry_desc);
  desc->kinds = MINKQ_SCENE_VT | MINKQ_SCENE_EE;
  desc->flags = MINKQ_GEOMETRY_SELF | MINKQ_GEOMETRY_DROP_INCIDENT;
  desc->world = 0;
  desc->group = 1;
  desc->mask = ~0u;
}

minkq_status minkq_scene_create_geometries(minkq_device* device, const minkq_geometry_desc* geometries, size_t count,
                                           minkq_scene** out_scene) {
  return guarded([&] {
    require(out_scene != nullptr, Status::kInvalidArgument, "out_scene is NULL");
    *out_scene = nullptr;
    require(device != nullptr, Status::kInvalidArgument, "device is NULL");
    require(count > 0, Status::kInvalidArgument, "count is 0: a scene holds at least one geometry");
    require(geometries != nullptr, Status::kInvalidArgument, "geometries is NULL");
    const size_t stride = geometries[0].struct_size;
    require(stride >= sizeof(minkq_geometry_desc), Status::kInvalidArgument,
            "geometries[0].struct_size " + std::to_string(stride) + " is under sizeof(minkq_geometry_desc) " +
                std::to_string(sizeof(minkq_geometry_desc)) + ": set it with minkq_geometry_desc_init");
    std::vector<minkq_geometry_desc> descs(count);
    std::vector<minkq::GeometryInput> inputs;
    for (size_t g = 0; g < count; ++g) {
      const std::string name = "geometry " + std::to_string(g);
      const char* raw = reinterpret_cast<const char*>(geometries) + g * stride;
      std::memcpy(&descs[g], raw, sizeof(minkq_geometry_desc));
      const minkq_geometry_desc& desc = descs[g];
      require(desc.struct_size == stride, Status::kInvalidArgument,
              name + ": struct_size " + std::to_string(desc.struct_size) + " differs from geometries[0]'s " +
                  std::to_string(stride));
      for (size_t b = sizeof(minkq_geometry_desc); b < stride; ++b)
        require(raw[b] == 0, Status::kInvalidArgument,
                name + ": struct_size " + std::to_string(stride) + " holds fields this library (ABI " +
                    std::to_string(MINKQ_ABI_VERSION) + ") does not know, and they are not zero");
      require((desc.kinds & ~kKindBits) == 0, Status::kInvalidArgument, name + ": kinds has unknown bits");
      require(desc.kinds != 0, Status::kInvalidArgument,
              name + ": kinds is 0: set one or more of MINKQ_SCENE_VT, MINKQ_SCENE_EE, MINKQ_SCENE_VV and MINKQ_SCENE_EV");
      require((desc.flags & ~kGeometryFlags) == 0, Status::kInvalidArgument, name + ": flags has unknown bits");
      require(desc.world >= -1, Status::kInvalidArgument,
              name + ": world " + std::to_string(desc.world) + " is negative (-1 means every world)");
      try {
        inputs.push_back(checked_geometry(device, desc, "geometry"));
      } catch (const Failure& failure) {
        fail(failure.status, name + ": " + failure.what());
      }
    }
    *out_scene = make_scene(device, descs, std::move(inputs));
  });
}

uint32_t minkq_scene_geometry_count(const minkq_scene* scene) {
  return scene ? uint32_t(scene->geometries.size()) : 0u;
}

minkq_status minkq_scene_geometry_range(const minkq_scene* scene, uint32_t geometry, minkq_element element,
                                        size_t* out_first, size_t* out_count) {
  return guarded([&] {
    require(scene != nullptr, Status::kInvalidArgument, "scene is NULL");
    require(out_first != nullptr && out_count != nullptr, Status::kInvalidArgument, "out_first or out_count is NULL");
    require(geometry < scene->geometries.size(), Status::kInvalidArgument,
            "geometry " + std::to_string(geometry) + " is out of range: the scene has " +
                std::to_string(scene->geometries.size()) + " geometries");
    const int64_t k = enum_value(element);
    require(k >= MINKQ_ELEMENT_VERTEX && k <= MINKQ_ELEMENT_EDGE, Status::kInvalidArgument,
            "element is not a minkq_element value");
    *out_first = scene->geometries[geometry].first[k];
    *out_count = scene->geometries[geometry].count[k];
  });
}

minkq_status minkq_scene_geometry_refit(minkq_scene* scene, uint32_t geometry, minkq_buffer vertices) {
  return guarded([&] {
    const minkq::Strided values = checked_geometry_vertices(scene, geometry, vertices, "refit");
    scene->store->move_geometry(int32_t(geometry), values, nullptr, false);
  });
}

minkq_status minkq_scene_geometry_rebuild(minkq_scene* scene, uint32_t geometry, minkq_buffer vertices) {
  return guarded([&] {
    const minkq::Strided values = checked_geometry_vertices(scene, geometry, vertices, "rebuild");
    scene->store->move_geometry(int32_t(geometry), values, nullptr, true);
  });
}

minkq_status minkq_scene_geometry_refit_swept(minkq_scene* scene, uint32_t geometry, minkq_buffer x0, minkq_buffer x1) {
  return guarded([&] {
    const minkq::Strided start = checked_geometry_vertices(scene, geometry, x0, "refit_swept", "x0");
    const minkq::Strided end = checked_geometry_vertices(scene, geometry, x1, "refit_swept", "x1");
    scene->store->move_geometry(int32_t(geometry), start, &end, false);
  });
}

minkq_status minkq_scene_geometry_rebuild_swept(minkq_scene* scene, uint32_t geometry, minkq_buffer x0,
                                                minkq_buffer x1) {
  return guarded([&] {
    const minkq::Strided start = checked_geometry_vertices(scene, geometry, x0, "rebuild_swept", "x0");
    const minkq::Strided end = checked_geometry_vertices(scene, geometry, x1, "rebuild_swept", "x1");
    scene->store->move_geometry(int32_t(geometry), start, &end, true);
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
    // Which geometry holds the buffer's vertex: the moving ones, one after another. Each
    // geometry takes its positions or keeps them as a whole.
    std::string kept = "the scene kept its positions";
    if (scene->geometries.size() > 1) {
      size_t first = 0;
      for (size_t g = 0; g < scene->geometries.size(); ++g) {
        const minkq_scene::Geometry& geometry = scene->geometries[g];
        if (geometry.flags & MINKQ_GEOMETRY_STATIC) continue;
        if (size_t(pending.vertex) < first + geometry.count[MINKQ_ELEMENT_VERTEX]) {
          kept = "geometry " + std::to_string(g) + " (its vertex " + std::to_string(size_t(pending.vertex) - first) +
                 ") kept its positions, as did any other geometry with one";
          break;
        }
        first += geometry.count[MINKQ_ELEMENT_VERTEX];
      }
    }
    fail(Status::kNonFinite, call + ": vertex " + std::to_string(pending.vertex) +
                                 (swept ? " has a non-finite coordinate (in x0 or x1); " + kept + ", at rest"
                                        : " has a non-finite coordinate; " + kept) +
                                 (rebuild ? " and built its trees for them" : ""));
  });
}

}  // extern "C"
