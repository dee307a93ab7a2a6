// The C API fuzzer's ops on scenes of many geometries (Session, capi_session.h):
// minkq_scene_create_geometries with good and bad descriptions (struct sizes, unknown kinds and
// flags, worlds, thickness counts and values, and every buffer misuse of minkq_scene_create),
// minkq_scene_geometry_count and _range (out-of-range geometries, elements that are not
// minkq_element values, NULL outputs), and the per-geometry refit, rebuild and swept calls with
// bad buffers and static geometries. The scene lives within the op: the one-mesh ops' models
// never see it. Vertices are float (FLOAT64 would need double buffers this model does not make).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "capi_session.h"

namespace minkq::capi_fuzz {

namespace {

constexpr uint32_t kKindBits = MINKQ_SCENE_VT | MINKQ_SCENE_EE | MINKQ_SCENE_VV | MINKQ_SCENE_EV;

// A digest of every kind the scene answers (box mode, r 0.5, canonical pairs): its state,
// compared before and after a failed move.
uint64_t geometry_state(minkq_scene* scene, uint32_t kinds) {
  const minkq::cxx::Result r = own_result();
  uint64_t digest = 0;
  const int query_kinds[] = {MINKQ_QUERY_VT, MINKQ_QUERY_EE, MINKQ_QUERY_VV, MINKQ_QUERY_EV};
  const uint32_t bits[] = {MINKQ_SCENE_VT, MINKQ_SCENE_EE, MINKQ_SCENE_VV, MINKQ_SCENE_EV};
  for (int k = 0; k < 4; ++k) {
    if (!(kinds & bits[k])) continue;
    minkq_query_desc d;
    shim_query_desc(&d, query_kinds[k], MINKQ_MODE_BOX, MINKQ_QUERY_DIGEST, 0.5f);
    if (minkq_scene_query_result(scene, &d, r.get()) != MINKQ_SUCCESS) failure("geometry state query failed");
    digest = digest * 31 + (minkq_result_digest(r.get()) ^ minkq_result_count(r.get()));
  }
  return digest;
}

}  // namespace

// Draws the descriptions (in `args`) and creates the scene, checking the status against the
// misuses drawn; returns the status.
minkq_status Session::create_geometries(std::vector<GeometryArgs>& args, minkq_scene** out) {
  int d;
  minkq_device* dev = device(&d);
  const size_t count = gen_.rarely() && gen_.choice(2) ? 0 : 1 + size_t(gen_.choice(3));
  args.resize(count);
  Misuse m;
  m.add(dev == nullptr, MINKQ_ERROR_INVALID_ARGUMENT, "device NULL");
  m.add(count == 0, MINKQ_ERROR_INVALID_ARGUMENT, "count 0");
  for (size_t g = 0; g < count; ++g) {
    GeometryArgs& a = args[g];
    const std::string name = "geometry " + std::to_string(g) + " ";
    minkq_geometry_desc_init(&a.desc);
    a.desc.kinds = uint32_t(1 + gen_.choice(15));
    a.desc.kinds = (a.desc.kinds & 3u) | ((a.desc.kinds & 12u) << 2);
    if (gen_.rarely()) a.desc.kinds = gen_.choice(2) ? 0u : a.desc.kinds | (gen_.choice(2) ? 4u : 0x100u);
    a.desc.flags = uint32_t(gen_.choice(4)) | (gen_.choice(4) == 0 ? uint32_t(MINKQ_GEOMETRY_STATIC) : 0u);
    if (gen_.rarely()) a.desc.flags |= gen_.choice(2) ? 16u : 0x80000000u;
    a.desc.world = gen_.rarely() ? (gen_.choice(2) ? -2 : INT32_MIN) : gen_.choice(4) - 1;
    a.desc.group = uint32_t(gen_.choice(8)), a.desc.mask = gen_.choice(2) ? ~0u : uint32_t(gen_.choice(8));
    a.vertices = gen_.buffer(12, Fill::kCoordinates, (name + "vertices").c_str(), SIZE_MAX, 0, 16);
    const int32_t nv = int32_t(std::min<size_t>(a.vertices.count, 64));
    a.triangles = gen_.buffer(12, Fill::kIndices, (name + "triangles").c_str(), SIZE_MAX, nv, 16);
    a.edges = gen_.choice(3) == 0 ? gen_.buffer(8, Fill::kIndices, (name + "edges").c_str(), SIZE_MAX, nv, 16)
                                  : gen_.buffer(8, Fill::kIndices, (name + "edges").c_str(), 0, nv, 0);
    a.thickness = gen_.choice(2) ? gen_.buffer(4, Fill::kCoordinates, (name + "thickness").c_str(), a.vertices.count, 0, 16)
                                 : gen_.buffer(4, Fill::kCoordinates, (name + "thickness").c_str(), 0, 0, 0);
    a.desc.vertices = a.vertices.desc, a.desc.triangles = a.triangles.desc, a.desc.edges = a.edges.desc;
    a.desc.thickness = a.thickness.desc;
    Misuse& x = a.misuse;
    x.add(a.desc.kinds == 0 || (a.desc.kinds & ~kKindBits), MINKQ_ERROR_INVALID_ARGUMENT, name + "kinds");
    x.add(a.desc.flags & ~15u, MINKQ_ERROR_INVALID_ARGUMENT, name + "unknown flag bits");
    x.add(a.desc.world < -1, MINKQ_ERROR_INVALID_ARGUMENT, name + "world below -1");
    x.merge(a.vertices.misuse);
    x.merge(a.triangles.misuse);
    x.merge(a.edges.misuse);
    if (a.vertices.honest) x.add(a.vertices.non_finite, MINKQ_ERROR_NON_FINITE, name + "non-finite vertex");
    if (a.triangles.honest && a.triangles.count > 0)
      x.add(a.triangles.min_index < 0 || a.triangles.max_index >= int32_t(a.vertices.count),
            MINKQ_ERROR_INDEX_OUT_OF_RANGE, name + "triangle index");
    if (a.edges.honest && a.edges.count > 0)
      x.add(a.edges.min_index < 0 || a.edges.max_index >= int32_t(a.vertices.count), MINKQ_ERROR_INDEX_OUT_OF_RANGE,
            name + "edge index");
    if (a.thickness.count > 0) {
      x.add(a.thickness.count != a.vertices.count, MINKQ_ERROR_INVALID_ARGUMENT, name + "thickness count");
      x.merge(a.thickness.misuse);
      for (size_t v = 0; a.thickness.honest && a.thickness.stride >= 4 && v < a.thickness.count; ++v) {
        float t;  // records may be unaligned (an odd stride is allowed)
        std::memcpy(&t, a.thickness.floats(v), sizeof t);
        x.add(!std::isfinite(t), MINKQ_ERROR_NON_FINITE, name + "non-finite thickness");
        x.add(t < 0, MINKQ_ERROR_INVALID_ARGUMENT, name + "negative thickness");
      }
    }
    m.merge(x);
  }
  // The descriptions' layout: struct_size exact, larger (tail zero: accepted; not zero:
  // refused), under sizeof, or differing between geometries.
  size_t stride = sizeof(minkq_geometry_desc);
  const int layout = gen_.choice(10);
  if (layout == 1 || layout == 2) stride += 16;
  if (layout == 3) stride -= 4;
  std::vector<char> raw(std::max<size_t>(count, 1) * stride, 0);
  for (size_t g = 0; g < count; ++g) {
    args[g].desc.struct_size = uint32_t(stride);
    std::memcpy(raw.data() + g * stride, &args[g].desc, std::min(stride, sizeof(minkq_geometry_desc)));
  }
  if (count > 0) {
    m.add(layout == 3, MINKQ_ERROR_INVALID_ARGUMENT, "struct_size under sizeof");
    if (layout == 2) raw[(count - 1) * stride + stride - 1 - size_t(gen_.choice(16))] = 1;
    m.add(layout == 2, MINKQ_ERROR_INVALID_ARGUMENT, "unknown fields not zero");
    if (layout == 4 && count > 1) {
      const uint32_t other = uint32_t(stride + 8);
      std::memcpy(raw.data() + stride, &other, sizeof other);  // geometry 1's struct_size
      m.add(true, MINKQ_ERROR_INVALID_ARGUMENT, "struct_size differs between geometries");
    }
  }
  const bool null_geometries = gen_.rarely() && gen_.choice(2);
  const bool null_out = gen_.rarely() && gen_.choice(2);
  m.add(null_geometries && count > 0, MINKQ_ERROR_INVALID_ARGUMENT, "geometries NULL");
  m.add(null_out, MINKQ_ERROR_INVALID_ARGUMENT, "out_scene NULL");
  *out = reinterpret_cast<minkq_scene*>(0x1);
  const minkq_status s = minkq_scene_create_geometries(
      dev, null_geometries ? nullptr : reinterpret_cast<const minkq_geometry_desc*>(raw.data()), count,
      null_out ? nullptr : out);
  expect("minkq_scene_create_geometries", s, m);
  if (null_out) *out = nullptr;
  if (s != MINKQ_SUCCESS && !null_out && *out != nullptr) {
    failure("minkq_scene_create_geometries failed but *out_scene is not NULL");
    *out = nullptr;
  }
  return s;
}

// minkq_scene_geometry_count and _range: the ranges tile the global numbering in order, with
// each geometry's own counts; bad geometries, elements and outputs refused.
void Session::geometry_ranges(minkq_scene* scene, const std::vector<GeometryArgs>& args) {
  if (minkq_scene_geometry_count(scene) != args.size()) failure("minkq_scene_geometry_count differs");
  size_t next[3] = {0, 0, 0};
  for (size_t g = 0; g < args.size(); ++g)
    for (int e = 0; e < 3; ++e) {
      size_t first = 0, count = 0;
      expect("minkq_scene_geometry_range", minkq_scene_geometry_range(scene, uint32_t(g), minkq_element(e), &first, &count),
             Misuse{});
      const GeometryArgs& a = args[g];
      const bool derived = e == 2 && a.edges.count == 0 && (a.desc.kinds & (MINKQ_SCENE_EE | MINKQ_SCENE_EV));
      const size_t want = e == 0 ? a.vertices.count : e == 1 ? a.triangles.count : a.edges.count;
      if (first != next[e] || (!derived && count != want))
        failure("geometry " + std::to_string(g) + " element " + std::to_string(e) + ": range (" + std::to_string(first) +
                ", " + std::to_string(count) + "), expected first " + std::to_string(next[e]));
      next[e] += count;
    }
  if (next[0] != minkq_scene_vertex_count(scene) || next[1] != minkq_scene_triangle_count(scene) ||
      next[2] != minkq_scene_edge_count(scene))
    failure("the geometry ranges do not add up to the scene's counts");
  const uint32_t g = gen_.choice(3) == 0 ? uint32_t(args.size()) + uint32_t(gen_.choice(3)) : uint32_t(gen_.choice(int(args.size())));
  const int element = gen_.choice(4) == 0 ? (gen_.choice(2) ? 3 : -1) : gen_.choice(3);
  const bool null_scene = gen_.rarely(), null_first = gen_.rarely(), null_count = gen_.rarely();
  Misuse m;
  m.add(null_scene, MINKQ_ERROR_INVALID_ARGUMENT, "scene NULL");
  m.add(null_first || null_count, MINKQ_ERROR_INVALID_ARGUMENT, "output NULL");
  m.add(g >= args.size(), MINKQ_ERROR_INVALID_ARGUMENT, "geometry out of range");
  m.add(element < 0 || element > 2, MINKQ_ERROR_INVALID_ARGUMENT, "not a minkq_element");
  size_t first = 0, count = 0;
  expect("minkq_scene_geometry_range", shim_scene_geometry_range(null_scene ? nullptr : scene, g, element,
                                                                 null_first ? nullptr : &first,
                                                                 null_count ? nullptr : &count), m);
}

// One geometry refit, rebuilt, or moved through a swept step, or the whole scene refit or
// rebuilt: bad geometries, static ones, bad buffers refused, and a refused move changes nothing.
void Session::geometry_move(minkq_scene* scene, const std::vector<GeometryArgs>& args) {
  uint32_t kinds = 0;
  size_t moving_vertices = 0;
  for (const GeometryArgs& a : args) {
    kinds |= a.desc.kinds;
    if (!(a.desc.flags & MINKQ_GEOMETRY_STATIC)) moving_vertices += a.vertices.count;
  }
  const int call = gen_.choice(6);  // refit, rebuild, refit_swept, rebuild_swept (one geometry); whole refit, rebuild
  const bool whole = call >= 4, swept = call == 2 || call == 3;
  const uint32_t g = gen_.choice(4) == 0 ? uint32_t(args.size()) + uint32_t(gen_.choice(2)) : uint32_t(gen_.choice(int(args.size())));
  const bool in_range = g < args.size();
  const size_t want = whole ? moving_vertices : in_range ? args[g].vertices.count : 0;
  Buffer x0 = gen_.buffer(12, Fill::kCoordinates, "x0", want, 0, 16);
  Buffer x1 = swept ? gen_.buffer(12, Fill::kCoordinates, "x1", want, 0, 16) : Buffer{};
  const bool null_scene = gen_.rarely();
  Misuse m;
  m.add(null_scene, MINKQ_ERROR_INVALID_ARGUMENT, "scene NULL");
  if (!whole) {
    m.add(!in_range, MINKQ_ERROR_INVALID_ARGUMENT, "geometry out of range");
    m.add(in_range && (args[g].desc.flags & MINKQ_GEOMETRY_STATIC), MINKQ_ERROR_INVALID_ARGUMENT, "static geometry");
  } else {
    m.add(moving_vertices == 0, MINKQ_ERROR_INVALID_ARGUMENT, "no moving geometry");
  }
  for (const Buffer* b : {&x0, &x1}) {
    if (b == &x1 && !swept) continue;
    m.merge(b->misuse);
    m.add(b->count != want, MINKQ_ERROR_INVALID_ARGUMENT, "vertex count differs");
    if (b->honest) m.add(b->non_finite, MINKQ_ERROR_NON_FINITE, "non-finite vertex");
  }
  const uint64_t before = geometry_state(scene, kinds);
  minkq_scene* handle = null_scene ? nullptr : scene;
  const char* names[] = {"minkq_scene_geometry_refit", "minkq_scene_geometry_rebuild", "minkq_scene_geometry_refit_swept",
                         "minkq_scene_geometry_rebuild_swept", "minkq_scene_refit", "minkq_scene_rebuild"};
  minkq_status s = MINKQ_SUCCESS;
  switch (call) {
    case 0: s = minkq_scene_geometry_refit(handle, g, x0.desc); break;
    case 1: s = minkq_scene_geometry_rebuild(handle, g, x0.desc); break;
    case 2: s = minkq_scene_geometry_refit_swept(handle, g, x0.desc, x1.desc); break;
    case 3: s = minkq_scene_geometry_rebuild_swept(handle, g, x0.desc, x1.desc); break;
    case 4: s = minkq_scene_refit(handle, x0.desc); break;
    default: s = minkq_scene_rebuild(handle, x0.desc); break;
  }
  // A whole-scene call with no moving geometry has nothing to move: either answer is the
  // library's to choose, as long as it is not a crash.
  if (whole && moving_vertices == 0 && m.codes.size() == 1 && s == MINKQ_SUCCESS) m = Misuse{};
  expect(names[call], s, m);
  if (s != MINKQ_SUCCESS && geometry_state(scene, kinds) != before)
    failure(std::string("a failed ") + names[call] + " changed the scene");
  if (s == MINKQ_SUCCESS && swept && minkq_scene_is_swept(scene) != 1)
    failure(std::string(names[call]) + ": the scene is not swept");
}

void Session::geometry_scene() {
  std::vector<GeometryArgs> args;
  minkq_scene* scene = nullptr;
  if (create_geometries(args, &scene) != MINKQ_SUCCESS || scene == nullptr) return;
  const minkq::cxx::Scene owner(scene);
  geometry_ranges(scene, args);
  for (int moves = gen_.choice(4); moves > 0; --moves) geometry_move(scene, args);
}

}  // namespace minkq::capi_fuzz
