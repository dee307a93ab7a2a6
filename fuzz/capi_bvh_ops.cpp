// The C API fuzzer's BVH ops (Session, capi_session.h): minkq_bvh_create, _refit and _rebuild
// (with the tree growth), and minkq_bvh_query over user boxes.
#include <cmath>
#include <cstdint>
#include <string>

#include "capi_session.h"

namespace minkq::capi_fuzz {

void Session::bvh_create() {
  int d;
  minkq_device* dev = device(&d);
  const int slot = gen_.choice(2);
  if (st_.bvhs[slot].handle) {
    minkq_bvh_release(st_.bvhs[slot].handle);
    st_.bvhs[slot] = {};
  }
  Buffer b = gen_.buffer(24, Fill::kBoxes, "boxes", SIZE_MAX, 0, 32);
  const bool null_out = gen_.rarely() && gen_.choice(2);
  Misuse m;
  m.add(null_out, MINKQ_ERROR_INVALID_ARGUMENT, "out_bvh NULL");
  m.add(dev == nullptr, MINKQ_ERROR_INVALID_ARGUMENT, "device NULL");
  m.merge(b.misuse);
  if (b.honest) {
    m.add(b.non_finite, MINKQ_ERROR_NON_FINITE, "non-finite box");
    m.add(b.unordered_box, MINKQ_ERROR_INVALID_ARGUMENT, "box lo > hi");
  }
  minkq_bvh* out = reinterpret_cast<minkq_bvh*>(0x1);
  const minkq_status st = minkq_bvh_create(dev, b.desc, null_out ? nullptr : &out);
  expect("minkq_bvh_create", st, m);
  if (null_out) return;
  if (st != MINKQ_SUCCESS) {
    if (out != nullptr && dev != nullptr) failure("minkq_bvh_create failed but *out_bvh is not NULL");
    return;
  }
  st_.bvhs[slot] = {out, d, b.count};
}

void Session::bvh_refit() {
  BvhSlot& b = st_.bvhs[gen_.choice(2)];
  const bool null_bvh = b.handle == nullptr;
  Buffer v = gen_.buffer(24, Fill::kBoxes, "boxes", null_bvh ? SIZE_MAX : b.boxes, 0, 32);
  Misuse m;
  m.add(null_bvh, MINKQ_ERROR_INVALID_ARGUMENT, "bvh NULL");
  m.merge(v.misuse);
  if (!null_bvh) m.add(v.count != b.boxes, MINKQ_ERROR_INVALID_ARGUMENT, "box count differs");
  if (v.honest) {
    m.add(v.non_finite, MINKQ_ERROR_NON_FINITE, "non-finite box");
    m.add(v.unordered_box, MINKQ_ERROR_INVALID_ARGUMENT, "box lo > hi");
  }
  const uint64_t before = null_bvh ? 0 : bvh_state(b);
  const bool rebuild = gen_.choice(3) == 0;
  minkq_bvh* handle = null_bvh ? nullptr : b.handle;
  const minkq_status st = rebuild ? minkq_bvh_rebuild(handle, v.desc) : minkq_bvh_refit(handle, v.desc);
  expect(rebuild ? "minkq_bvh_rebuild" : "minkq_bvh_refit", st, m);
  if (st != MINKQ_SUCCESS && !null_bvh && bvh_state(b) != before)
    failure(std::string("a failed bvh ") + (rebuild ? "rebuild" : "refit") + " changed its boxes");
  check_tree_growth("minkq_bvh_tree_growth", minkq_bvh_tree_growth, handle, rebuild && st == MINKQ_SUCCESS);
}

void Session::bvh_query() {
  BvhSlot& b = st_.bvhs[gen_.choice(2)];
  const bool null_bvh = b.handle == nullptr;
  const int sh = gen_.choice(13);
  const int shape = sh < 12 ? sh % 3 : (sh == 12 ? 3 : -2);
  const int md = gen_.choice(14);
  const int mode = md < 12 ? md % 4 : (md == 12 ? -1 : 17);
  const uint32_t flags = uint32_t(gen_.choice(16)) | (gen_.rarely() ? 32u : 0u);
  const float r = gen_.choice(3) == 0 ? 0.0f : gen_.radius();
  Buffer first = gen_.buffer(12, Fill::kCoordinates, "first", SIZE_MAX, 0, 16);
  Buffer second = shape == MINKQ_SHAPE_SPHERE && gen_.choice(4) != 0
                      ? gen_.buffer(12, Fill::kCoordinates, "second", 0, 0, 0)
                      : gen_.buffer(12, Fill::kCoordinates, "second", first.count, 0, 16);
  const bool null_desc = gen_.rarely() && gen_.choice(2);
  minkq_bvh_query_desc d;
  shim_bvh_query_desc(&d, shape, mode, flags, r, first.desc, second.desc);
  Misuse m;
  m.add(null_bvh, MINKQ_ERROR_INVALID_ARGUMENT, "bvh NULL");
  m.add(null_desc, MINKQ_ERROR_INVALID_ARGUMENT, "query NULL");
  if (!null_desc) {
    m.add(shape < 0 || shape > 2, MINKQ_ERROR_INVALID_ARGUMENT, "shape invalid");
    m.add(mode < 0 || mode > 3, MINKQ_ERROR_INVALID_ARGUMENT, "mode invalid");
    m.add(flags & ~31u, MINKQ_ERROR_INVALID_ARGUMENT, "unknown flags");
    m.add(flags & MINKQ_QUERY_LEAF_EXACT, MINKQ_ERROR_INVALID_ARGUMENT, "LEAF_EXACT on a bvh");
    m.add(shape == MINKQ_SHAPE_CAPSULE && mode == MINKQ_MODE_SPHERE, MINKQ_ERROR_INVALID_ARGUMENT, "capsule sphere mode");
    m.add(shape == MINKQ_SHAPE_BOX && mode != MINKQ_MODE_BOX, MINKQ_ERROR_INVALID_ARGUMENT, "box query non-box mode");
    m.add(!std::isfinite(r), MINKQ_ERROR_NON_FINITE, "radius not finite");
    m.add(r < 0, MINKQ_ERROR_INVALID_ARGUMENT, "radius negative");
    // minkq.h: "MINKQ_SHAPE_BOX ... radius must be 0".
    m.add(shape == MINKQ_SHAPE_BOX && std::isfinite(r) && r != 0, MINKQ_ERROR_INVALID_ARGUMENT, "box query radius not 0");
    m.merge(first.misuse);
    m.merge(second.misuse);
    if (shape == MINKQ_SHAPE_SPHERE) m.add(second.count != 0, MINKQ_ERROR_INVALID_ARGUMENT, "second not empty");
    else m.add(second.count != first.count, MINKQ_ERROR_INVALID_ARGUMENT, "second.count differs");
    if (first.honest) m.add(first.non_finite, MINKQ_ERROR_NON_FINITE, "non-finite query point");
    if (second.honest) m.add(second.non_finite, MINKQ_ERROR_NON_FINITE, "non-finite query point");
  }
  // The count a valid query needs, from a capacity-0 call of the same arguments.
  uint64_t needed = 0;
  if (m.none()) {
    minkq_query_info probe{};
    const minkq_status ps = shim_bvh_query(b.handle, &d, nullptr, 0, MINKQ_MEMORY_HOST, &probe);
    if (ps != MINKQ_SUCCESS && ps != MINKQ_ERROR_CAPACITY) failure("a valid bvh query failed: " + name(ps));
    needed = probe.count;
  }
  Output o = output(needed);
  m.merge(o.misuse);
  minkq_query_info info{};
  const minkq_status st = shim_bvh_query(null_bvh ? nullptr : b.handle, null_desc ? nullptr : &d, o.data, o.capacity,
                                         o.memory, o.null_info ? nullptr : &info);
  expect("minkq_bvh_query", st, m, needed > o.capacity ? MINKQ_ERROR_CAPACITY : MINKQ_SUCCESS);
  if (st == MINKQ_ERROR_CAPACITY && info.count != needed) failure("bvh CAPACITY: info.count is not the count needed");
  if (st != MINKQ_SUCCESS) return;
  check_pairs("minkq_bvh_query", o.pairs.data(), info.count, first.count, b.boxes, false, flags, info.digest);
}

}  // namespace minkq::capi_fuzz
