// The C API fuzzer's device and scene ops (Session, capi_session.h): minkq_device_create and
// _release, minkq_scene_create, _release, _refit and _rebuild (with the tree growth), and the
// choice of a scene for a call, or of a valid one made for the stream-ordered calls.
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "capi_session.h"

namespace minkq::capi_fuzz {

minkq_device* Session::device(int* index) {
  const int d = gen_.choice(3);
  *index = d < 2 ? d : -1;
  return d < 2 ? st_.devices[d] : nullptr;
}

void Session::device_create() {
  static const char* specs[] = {"cpu", "auto", "cuda", "cuda:0", "cuda:7", "cuda:99999", "cuda:123456", "cuda:",
                                "cuda:-1", "cuda:1x", "CPU", "", "gpu", nullptr};
  const int which = gen_.choice(14);
  const char* spec = specs[which];
  const int slot = gen_.choice(2);
  const bool null_out = gen_.rarely();
  if (st_.devices[slot] && !null_out) {  // replace it only when nothing uses it
    if (st_.device_in_use(slot)) return;
    minkq_device_release(st_.devices[slot]);
    st_.devices[slot] = nullptr;
  }
  Misuse m;
  m.add(null_out, MINKQ_ERROR_INVALID_ARGUMENT, "out_device NULL");
  m.add(spec == nullptr, MINKQ_ERROR_INVALID_ARGUMENT, "spec NULL");
  const bool cuda = which >= 2 && which <= 5;  // well-formed CUDA specs: no CUDA in this build
  const bool malformed = spec && !cuda && which > 1;
  m.add(malformed, MINKQ_ERROR_INVALID_ARGUMENT, "unknown spec");
  m.add(cuda && minkq_cuda_device_count() <= (which == 4 ? 7 : which == 5 ? 99999 : 0), MINKQ_ERROR_UNSUPPORTED,
        "no such CUDA device");
  minkq_device* out = reinterpret_cast<minkq_device*>(0x1);
  const minkq_status s = minkq_device_create(spec, null_out ? nullptr : &out);
  expect("minkq_device_create", s, m);
  if (null_out) return;
  if (s == MINKQ_SUCCESS) {
    st_.devices[slot] = out;
    if (minkq_device_backend(out) != MINKQ_BACKEND_CPU && minkq_cuda_device_count() == 0)
      failure("a non-CPU device without CUDA");
    if (std::strlen(minkq_device_name(out)) == 0) failure("empty device name");
  } else if (out != nullptr) {
    failure("minkq_device_create failed but did not set *out_device to NULL");
  }
}

void Session::device_release() {
  const int d = gen_.choice(2);
  if (st_.device_in_use(d)) return;  // the contract: scenes and bvhs first
  minkq_device_release(st_.devices[d]);  // NULL is fine too
  st_.devices[d] = nullptr;
  note("minkq_device_release");
}

void Session::scene_create() {
  int d;
  minkq_device* dev = device(&d);
  const int slot = gen_.choice(3);
  if (st_.scenes[slot].handle) {
    minkq_scene_release(st_.scenes[slot].handle);
    st_.scenes[slot] = {};
  }
  uint32_t flags = uint32_t(gen_.choice(8));
  // Unknown bits only: 8 is MINKQ_SCENE_FLOAT64 (double vertices, which this model does not
  // make), 16 and 32 MINKQ_SCENE_VV and MINKQ_SCENE_EV (not modelled either).
  if (gen_.rarely()) flags |= gen_.choice(2) ? 64u : 0x80000000u;
  Buffer v = gen_.buffer(12, Fill::kCoordinates, "vertices", SIZE_MAX, 0, 32);
  const int32_t nv = int32_t(std::min<size_t>(v.count, 64));
  Buffer t = gen_.buffer(12, Fill::kIndices, "triangles", SIZE_MAX, nv, 32);
  Buffer e = gen_.choice(3) == 0 ? gen_.buffer(8, Fill::kIndices, "edges", SIZE_MAX, nv, 32)
                                 : gen_.buffer(8, Fill::kIndices, "edges", 0, nv, 0);
  const bool null_desc = gen_.rarely() && gen_.choice(2);
  const bool null_out = gen_.rarely() && gen_.choice(2);
  Misuse m;
  m.add(dev == nullptr, MINKQ_ERROR_INVALID_ARGUMENT, "device NULL");
  m.add(null_desc, MINKQ_ERROR_INVALID_ARGUMENT, "desc NULL");
  m.add(null_out, MINKQ_ERROR_INVALID_ARGUMENT, "out_scene NULL");
  if (!null_desc) {
    m.add(flags & ~63u, MINKQ_ERROR_INVALID_ARGUMENT, "unknown flag bits");
    m.add(!(flags & 3u), MINKQ_ERROR_INVALID_ARGUMENT, "no query kind");
    m.merge(v.misuse);
    m.merge(t.misuse);
    m.merge(e.misuse);
    if (v.honest) m.add(v.non_finite, MINKQ_ERROR_NON_FINITE, "non-finite vertex");
    if (t.honest && t.count > 0)
      m.add(t.min_index < 0 || t.max_index >= int32_t(v.count), MINKQ_ERROR_INDEX_OUT_OF_RANGE, "triangle index");
    if (e.honest && e.count > 0)
      m.add(e.min_index < 0 || e.max_index >= int32_t(v.count), MINKQ_ERROR_INDEX_OUT_OF_RANGE, "edge index");
  }
  minkq_scene_desc desc{};
  desc.flags = flags;
  desc.vertices = v.desc;
  desc.triangles = t.desc;
  desc.edges = e.desc;
  minkq_scene* out = reinterpret_cast<minkq_scene*>(0x1);
  const minkq_status s = minkq_scene_create(dev, null_desc ? nullptr : &desc, null_out ? nullptr : &out);
  expect("minkq_scene_create", s, m);
  if (null_out) return;
  if (s != MINKQ_SUCCESS) {
    if (out != nullptr && dev != nullptr && !null_desc) failure("minkq_scene_create failed but *out_scene is not NULL");
    return;
  }
  SceneSlot& slot_ref = st_.scenes[slot];
  slot_ref = SceneSlot::of(out, d, flags);
  if (slot_ref.vertices != v.count || slot_ref.triangles != t.count) failure("scene counts differ from the desc");
  if (e.count > 0 && slot_ref.edges != e.count) failure("scene edge count differs from the given edges");
  if (e.count == 0 && !(flags & MINKQ_SCENE_EE) && slot_ref.edges != 0) failure("edges derived for a VT-only scene");
  // Often reserve at once (the stream-ordered calls need it), as a simulator would.
  if (gen_.choice(2) == 0) reserve_on(&slot_ref, false, reserve_flags(), reserve_capacity());
}

void Session::scene_release() {
  const int slot = gen_.choice(3);
  minkq_scene_release(st_.scenes[slot].handle);
  st_.scenes[slot] = {};
  note("minkq_scene_release");
}

SceneSlot* Session::scene(bool* null_scene) {
  SceneSlot& s = st_.scenes[gen_.choice(3)];
  *null_scene = s.handle == nullptr;
  return &s;
}
// A slot for the stream-ordered calls: an empty one (a NULL scene) less often than scene();
// when every slot is empty, mostly a valid scene made for the purpose.
SceneSlot* Session::live_scene(bool* null_scene) {
  SceneSlot* s = scene(null_scene);
  if (!*null_scene || gen_.choice(4) == 0) return s;
  for (auto& other : st_.scenes)
    if (other.handle) {
      *null_scene = false;
      return &other;
    }
  *null_scene = false;
  return valid_scene();
}

// A small valid scene (a CPU device made if there is none) in a random slot, often with a
// reservation: something for the stream-ordered calls to act on.
SceneSlot* Session::valid_scene() {
  int d = st_.devices[0] ? 0 : st_.devices[1] ? 1 : -1;
  if (d < 0) {
    expect("minkq_device_create (for a valid scene)", minkq_device_create("cpu", &st_.devices[0]), Misuse{});
    d = 0;
  }
  SceneSlot& slot = st_.scenes[gen_.choice(3)];
  minkq_scene_release(slot.handle);
  slot = SceneSlot{};
  const int nv = 3 + gen_.choice(22), nt = 1 + gen_.choice(24);
  std::vector<float> xyz(3 * size_t(nv));
  for (float& x : xyz) x = float(gen_.choice(33) - 16) / 8.0f;
  std::vector<int32_t> tri(3 * size_t(nt));
  for (int32_t& v : tri) v = gen_.choice(nv);
  const uint32_t flags = uint32_t(1 + gen_.choice(3)) | (gen_.choice(2) ? uint32_t(MINKQ_SCENE_DROP_INCIDENT) : 0u);
  minkq_scene_desc desc{};
  desc.flags = flags;
  desc.vertices = shim_buffer(xyz.data(), 0, size_t(nv), MINKQ_MEMORY_HOST);
  desc.triangles = shim_buffer(tri.data(), 0, size_t(nt), MINKQ_MEMORY_HOST);
  desc.edges = shim_buffer(nullptr, 0, 0, MINKQ_MEMORY_HOST);
  minkq_scene* out = nullptr;
  expect("minkq_scene_create (a valid scene)", minkq_scene_create(st_.devices[d], &desc, &out), Misuse{});
  slot = SceneSlot::of(out, d, flags);
  if (slot.vertices != size_t(nv) || slot.triangles != size_t(nt)) failure("scene counts differ from the desc");
  if (gen_.choice(4) != 0) reserve_on(&slot, false, reserve_flags(), reserve_capacity());
  return &slot;
}

void Session::scene_refit() {
  bool null_scene;
  SceneSlot* s = scene(&null_scene);
  Buffer v = gen_.buffer(12, Fill::kCoordinates, "vertices", null_scene ? SIZE_MAX : s->vertices, 0, 32);
  Misuse m;
  m.add(null_scene, MINKQ_ERROR_INVALID_ARGUMENT, "scene NULL");
  m.merge(v.misuse);
  if (!null_scene) m.add(v.count != s->vertices, MINKQ_ERROR_INVALID_ARGUMENT, "vertex count differs");
  if (v.honest) m.add(v.non_finite, MINKQ_ERROR_NON_FINITE, "non-finite vertex");
  const uint64_t before = null_scene ? 0 : scene_state(*s);
  const bool rebuild = gen_.choice(3) == 0;
  minkq_scene* handle = null_scene ? nullptr : s->handle;
  const minkq_status st = rebuild ? minkq_scene_rebuild(handle, v.desc) : minkq_scene_refit(handle, v.desc);
  expect(rebuild ? "minkq_scene_rebuild" : "minkq_scene_refit", st, m);
  if (st != MINKQ_SUCCESS && !null_scene && scene_state(*s) != before)
    failure(std::string("a failed ") + (rebuild ? "rebuild" : "refit") + " changed the scene's positions");
  check_tree_growth("minkq_scene_tree_growth", minkq_scene_tree_growth, handle, rebuild && st == MINKQ_SUCCESS);
}

}  // namespace minkq::capi_fuzz
