// The C API fuzzer's stream-ordered ops (Session, capi_session.h): minkq_scene_reserve, the
// asynchronous refits, rebuilds and queries, and minkq_scene_async_status, each checked
// against the model's reservation and pending error and against the blocking call.
//
// Stream-ordered calls (minkq_async.h): on the CPU they run at once, on host
// memory, the stream ignored; non-finite vertices become the scene's pending error.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "capi_session.h"

namespace minkq::capi_fuzz {

// A stream argument: ignored on the CPU, so any value (never dereferenced) must do.
minkq_stream Session::stream() {
  switch (gen_.choice(4)) {
    case 0: return reinterpret_cast<minkq_stream>(uintptr_t(0x5eed));
    case 1: return reinterpret_cast<minkq_stream>(&st_);
    default: return nullptr;
  }
}

// Reservation flags and capacities: mostly valid, sometimes unknown bits or overflowing sizes.
uint32_t Session::reserve_flags() {
  switch (gen_.choice(8)) {
    case 0: return 0u;
    case 1: case 2: return MINKQ_RESERVE_REFIT;
    case 3: return MINKQ_RESERVE_REFIT | MINKQ_RESERVE_REBUILD;
    case 4: return uint32_t(gen_.choice(8)) | (8u << gen_.choice(28));  // unknown bits (above SWEPT)
    default: return MINKQ_RESERVE_REBUILD;
  }
}
size_t Session::reserve_capacity() {
  switch (gen_.choice(12)) {
    case 0: return 0;
    case 1: return size_t(gen_.choice(8));
    case 2: case 3: return size_t(gen_.choice(1024));
    case 4: return size_t(1) << 20;
    case 5: return kMaxElements + 1;
    case 6: return SIZE_MAX / 16;      // the largest capi/scene.cpp accepts (2 uint64_t per pair)
    case 7: return SIZE_MAX / 16 + 1;  // its byte size overflows: SIZE_OVERFLOW
    case 8: return SIZE_MAX;
    default: return size_t(gen_.choice(256));
  }
}

// One minkq_scene_reserve call on `s` (NULL scene when null_scene), checked and modelled.
void Session::reserve_on(SceneSlot* s, bool null_scene, uint32_t flags, size_t capacity) {
  Misuse m;
  m.add(null_scene, MINKQ_ERROR_INVALID_ARGUMENT, "scene NULL");
  m.add(flags & ~uint32_t(MINKQ_RESERVE_REFIT | MINKQ_RESERVE_REBUILD | MINKQ_RESERVE_SWEPT),
        MINKQ_ERROR_INVALID_ARGUMENT, "unknown reserve flags");
  m.add(capacity > SIZE_MAX / (2 * sizeof(uint64_t)), MINKQ_ERROR_SIZE_OVERFLOW, "canonical_capacity overflows");
  const uint64_t before = null_scene ? 0 : scene_full_state(*s);
  const minkq_status st = minkq_scene_reserve(null_scene ? nullptr : s->handle, flags, capacity);
  // A valid reservation beyond 2^31 pairs may be refused for memory (not on the CPU, which
  // reserves nothing, but minkq.h allows it).
  if (m.none() && capacity > kMaxElements && st == MINKQ_ERROR_OUT_OF_MEMORY) {
    Misuse oom;
    oom.add(true, MINKQ_ERROR_OUT_OF_MEMORY, "a huge valid reservation");
    expect("minkq_scene_reserve", st, oom);
  } else {
    expect("minkq_scene_reserve", st, m);
  }
  if (null_scene) return;
  if (scene_full_state(*s) != before) failure("minkq_scene_reserve changed the scene's pairs");
  if (st != MINKQ_SUCCESS) return;
  s->reserved_refit |= (flags & (MINKQ_RESERVE_REFIT | MINKQ_RESERVE_REBUILD)) != 0;
  s->reserved_rebuild |= (flags & MINKQ_RESERVE_REBUILD) != 0;
  s->reserved_canonical = std::max(s->reserved_canonical, capacity);
}

void Session::scene_reserve() {
  bool null_scene;
  SceneSlot* s = live_scene(&null_scene);
  const uint32_t flags = reserve_flags();
  const size_t capacity = reserve_capacity();
  reserve_on(s, null_scene, flags, capacity);
}

// minkq_scene_refit_async / minkq_scene_rebuild_async: the blocking calls' buffer misuses
// (minus NON_FINITE), the reservation, the vertex count. Non-finite coordinates succeed, keep
// the positions and become the pending error (the first one only); finite ones give the state
// the blocking call gives for the same vertices.
void Session::scene_refit_async() {
  bool null_scene;
  SceneSlot* s = live_scene(&null_scene);
  const bool rebuild = gen_.choice(3) == 0;
  const char* call = rebuild ? "minkq_scene_rebuild_async" : "minkq_scene_refit_async";
  // Half the scenes without the reservation get it now (a simulator reserves before its loop).
  if (!null_scene && !(rebuild ? s->reserved_rebuild : s->reserved_refit) && gen_.choice(2))
    reserve_on(s, false, rebuild || gen_.choice(2) ? MINKQ_RESERVE_REBUILD : MINKQ_RESERVE_REFIT, reserve_capacity());
  Buffer v = gen_.buffer(12, Fill::kCoordinates, "vertices", null_scene ? SIZE_MAX : s->vertices, 0, 32);
  switch (gen_.choice(4)) {
    case 0: case 1: v.make_finite3(); break;
    case 2:  // one NaN or infinity at a chosen record and axis (maybe after others)
      if (v.honest && v.stride >= 12 && v.count > 0) {
        const size_t i = size_t(gen_.choice(int(std::min<size_t>(v.count, 64))));
        const float bad_value = gen_.choice(2) ? std::numeric_limits<float>::quiet_NaN() : (gen_.choice(2) ? INFINITY : -INFINITY);
        std::memcpy(v.storage.data() + i * v.stride + 4 * size_t(gen_.choice(3)), &bad_value, 4);
        v.non_finite = true;
      }
      break;
    default: break;  // as generated
  }
  Misuse m;
  m.add(null_scene, MINKQ_ERROR_INVALID_ARGUMENT, "scene NULL");
  if (!null_scene) {
    m.add(rebuild ? !s->reserved_rebuild : !s->reserved_refit, MINKQ_ERROR_INVALID_ARGUMENT,
          rebuild ? "no MINKQ_RESERVE_REBUILD" : "no MINKQ_RESERVE_REFIT");
    m.add(v.count != s->vertices, MINKQ_ERROR_INVALID_ARGUMENT, "vertex count differs");
  }
  m.merge(v.misuse);
  const int64_t bad = m.none() ? v.first_non_finite3() : -1;
  if (m.none() && (bad >= 0) != v.non_finite) failure("harness: first_non_finite3 disagrees with the generator");
  const uint64_t before = null_scene ? 0 : scene_full_state(*s);
  const double growth_before = null_scene ? 0.0 : scene_growth(*s);
  const minkq_stream strm = stream();
  minkq_scene* handle = null_scene ? nullptr : s->handle;
  const minkq_status st = rebuild ? minkq_scene_rebuild_async(handle, v.desc, strm)
                                  : minkq_scene_refit_async(handle, v.desc, strm);
  expect(call, st, m);
  if (null_scene) return;
  const uint64_t after = scene_full_state(*s);
  const double growth = scene_growth(*s);
  if (st != MINKQ_SUCCESS) {
    if (after != before) failure(std::string("a failed ") + call + " changed the scene's positions");
    if (growth != growth_before) failure(std::string("a failed ") + call + " changed the tree growth");
    return;
  }
  if (rebuild && growth != 1.0)
    failure(std::string(call) + ": tree growth " + std::to_string(growth) + " after the rebuild, not 1");
  if (bad >= 0) {
    note("  (non-finite vertex " + std::to_string(bad) + ": pending " +
         (s->pending.call ? "already set" : "recorded") + ")");
    if (after != before) failure(std::string(call) + " with a non-finite vertex changed the scene's positions");
    // A refit to the kept positions leaves every box, so the growth, as it was.
    if (!rebuild && growth != growth_before)
      failure(std::string(call) + " with a non-finite vertex changed the tree growth from " +
              std::to_string(growth_before) + " to " + std::to_string(growth));
    if (s->pending.call == 0) s->pending = {rebuild ? 2 : 1, bad + (g_inject ? 1 : 0)};
    ++g_async_non_finite;
    if (gen_.choice(3) == 0) scene_query_async_on(s, false);
    if (gen_.choice(2) == 0) async_status_on(s, false);
    return;
  }
  // The reference: the blocking call with the same vertices must leave the same state (a
  // refit to the positions the scene already holds changes no pair and no box).
  const minkq_status bs = rebuild ? minkq_scene_rebuild(s->handle, v.desc) : minkq_scene_refit(s->handle, v.desc);
  expect(rebuild ? "minkq_scene_rebuild (reference)" : "minkq_scene_refit (reference)", bs, Misuse{});
  if (scene_full_state(*s) != after)
    failure(std::string(call) + ": the scene's pairs differ from those of the blocking call with the same vertices");
  ++g_async_moves;
  const double blocking_growth = scene_growth(*s);
  if (blocking_growth != growth)
    failure(std::string(call) + ": tree growth " + std::to_string(growth) + " but the blocking call then gives " +
            std::to_string(blocking_growth));
  if (gen_.choice(3) == 0) scene_query_async_on(s, false);
  if (gen_.choice(4) == 0) async_status_on(s, false);
}

Session::AsyncOutput Session::async_output(uint64_t needed) {
  AsyncOutput o;
  switch (gen_.choice(8)) {
    case 0: o.capacity = 0; break;
    case 1: o.capacity = needed > 0 ? size_t(needed - 1) : 0; break;
    case 2: o.capacity = size_t(needed) + size_t(gen_.choice(4)); break;
    case 3: o.capacity = size_t(gen_.choice(4)); break;
    default: o.capacity = size_t(needed); break;
  }
  o.raw.assign(2 * o.capacity + kGuardWords, kGuard);
  o.data = o.capacity || gen_.choice(2) ? o.raw.data() : nullptr;
  if (gen_.rarely()) {
    const int c = gen_.choice(3);
    o.declared_only = true;
    o.raw.assign(kGuardWords, kGuard);
    if (c == 0) {
      o.data = nullptr;
      o.capacity = 1 + size_t(gen_.choice(3));
      o.misuse.add(true, MINKQ_ERROR_INVALID_ARGUMENT, "out_pairs NULL with capacity");
    } else {
      o.data = o.raw.data();
      o.capacity = c == 1 ? SIZE_MAX : SIZE_MAX / 8 + 1;
      o.misuse.add(true, MINKQ_ERROR_SIZE_OVERFLOW, "capacity overflows");
    }
  }
  return o;
}

// Checks an asynchronous query's outputs after the call: `ok` whether it succeeded; `needed`
// and `expected` the blocking query's count and canonical pairs.
void Session::check_async_output(const char* call, bool ok, const AsyncOutput& o, const uint64_t* count_word,
                                 uint64_t count_value, const SceneSlot& s, const QueryArgs& a, uint64_t needed,
                                 const std::vector<int32_t>& expected) {
  const size_t held = o.declared_only ? 0 : 2 * o.capacity;
  for (size_t i = held; i < o.raw.size(); ++i)
    if (o.raw[i] != kGuard) failure(std::string(call) + " wrote past the capacity (guard word " + std::to_string(i - held) + ")");
  if (!ok) {
    if (count_word && count_value != kCountSentinel) failure(std::string(call) + " failed but wrote the count");
    for (size_t i = 0; i < held; ++i)
      if (o.raw[i] != kGuard) failure(std::string(call) + " failed but wrote pairs");
    return;
  }
  if (count_value != needed)
    failure(std::string(call) + ": count " + std::to_string(count_value) + " but the blocking query finds " +
            std::to_string(needed));
  ++(needed > o.capacity ? g_async_short : g_async_fit);
  auto as_set = [](const std::vector<int32_t>& flat) {
    std::vector<std::pair<int32_t, int32_t>> p(flat.size() / 2);
    for (size_t i = 0; i < p.size(); ++i) p[i] = {flat[2 * i], flat[2 * i + 1]};
    std::sort(p.begin(), p.end());
    return p;
  };
  if (needed > o.capacity) {  // min(count, capacity) of the pairs, distinct, in any order (minkq.h)
    if (held == 0) return;
    const auto some = as_set(std::vector<int32_t>(o.raw.begin(), o.raw.begin() + std::ptrdiff_t(held)));
    const auto all = as_set(expected);
    if (std::adjacent_find(some.begin(), some.end()) != some.end())
      failure(std::string(call) + ": the pairs do not fit and one was written twice");
    if (!std::includes(all.begin(), all.end(), some.begin(), some.end()))
      failure(std::string(call) + ": the pairs do not fit and one written is not a pair of the blocking query");
    return;
  }
  for (size_t i = 2 * size_t(needed); i < held; ++i)
    if (o.raw[i] != kGuard) failure(std::string(call) + " wrote past the pairs it counted");
  const uint32_t flags = a.flags & uint32_t(MINKQ_QUERY_CANONICAL);  // no digest here
  check_pairs(call, o.raw.data(), needed, queries_of(s, a.kind), prims_of(s, a.kind), a.kind == MINKQ_QUERY_EE,
              flags, 0);
  std::vector<int32_t> got(o.raw.begin(), o.raw.begin() + 2 * std::ptrdiff_t(needed));
  if (a.flags & MINKQ_QUERY_CANONICAL) {
    if (got != expected) failure(std::string(call) + ": canonical pairs differ from the blocking query's (in order)");
    return;
  }
  if (as_set(got) != as_set(expected)) failure(std::string(call) + ": pairs differ from the blocking query's set");
}

// The asynchronous checks of one description beyond the blocking query's: DIGEST and STATS
// are unsupported, canonical order needs the capacity reserved.
void Session::async_desc_misuse(Misuse& m, const QueryArgs& a, const SceneSlot* s, bool null_scene,
                                size_t capacity, const char* which) {
  if (a.null_desc) return;
  m.add(a.flags & uint32_t(MINKQ_QUERY_DIGEST | MINKQ_QUERY_STATS), MINKQ_ERROR_UNSUPPORTED,
        std::string(which) + " DIGEST or STATS");
  if (!null_scene)
    m.add((a.flags & MINKQ_QUERY_CANONICAL) && capacity > s->reserved_canonical, MINKQ_ERROR_INVALID_ARGUMENT,
          std::string(which) + " canonical capacity " + std::to_string(capacity) + " over the reservation " +
              std::to_string(s->reserved_canonical));
}

void Session::scene_query_async() {
  bool null_scene;
  SceneSlot* s = live_scene(&null_scene);
  scene_query_async_on(s, null_scene);
}
void Session::scene_query_async_on(SceneSlot* s, bool null_scene) {
  QueryArgs a = query_args(s, null_scene, -1, true);
  Misuse m = a.misuse;
  uint64_t needed = 0;
  std::vector<int32_t> expected;
  const bool desc_ok = m.none() && !(a.flags & (MINKQ_QUERY_DIGEST | MINKQ_QUERY_STATS));
  if (desc_ok && !reference_count(s->handle, a.desc, &needed, &expected))
    failure("a valid query failed through minkq_scene_query_result: " + std::string(minkq_last_error_message()));
  AsyncOutput o = async_output(needed);
  m.merge(o.misuse);
  async_desc_misuse(m, a, s, null_scene, o.capacity, "query");
  const bool null_count = gen_.rarely() && gen_.choice(2);
  m.add(null_count, MINKQ_ERROR_INVALID_ARGUMENT, "out_count NULL");
  uint64_t count = kCountSentinel;
  const uint64_t before = null_scene ? 0 : scene_full_state(*s);
  const minkq_status st = minkq_scene_query_async(null_scene ? nullptr : s->handle, a.null_desc ? nullptr : &a.desc,
                                                  o.data, o.capacity, null_count ? nullptr : &count, stream());
  expect("minkq_scene_query_async", st, m);
  if (null_scene) return;
  check_async_output("minkq_scene_query_async", st == MINKQ_SUCCESS, o, null_count ? nullptr : &count, count, *s, a,
                     needed, expected);
  if (scene_full_state(*s) != before) failure("minkq_scene_query_async changed the scene");
}

void Session::scene_query_vt_ee_async() {
  bool null_scene;
  SceneSlot* s = live_scene(&null_scene);
  const QueryArgs vt = query_args(s, null_scene, MINKQ_QUERY_VT, true);
  const QueryArgs ee = query_args(s, null_scene, MINKQ_QUERY_EE, true);
  Misuse m = vt.misuse;
  m.merge(ee.misuse);
  m.add(!vt.null_desc && vt.kind != MINKQ_QUERY_VT, MINKQ_ERROR_INVALID_ARGUMENT, "vt_query not VT");
  m.add(!ee.null_desc && ee.kind != MINKQ_QUERY_EE, MINKQ_ERROR_INVALID_ARGUMENT, "ee_query not EE");
  const uint32_t unsupported = MINKQ_QUERY_DIGEST | MINKQ_QUERY_STATS;
  uint64_t needed[2] = {0, 0};
  std::vector<int32_t> expected[2];
  if (m.none() && !(vt.flags & unsupported) && !(ee.flags & unsupported) &&
      !(reference_count(s->handle, vt.desc, &needed[0], &expected[0]) &&
        reference_count(s->handle, ee.desc, &needed[1], &expected[1])))
    failure("a valid query failed through minkq_scene_query_result: " + std::string(minkq_last_error_message()));
  AsyncOutput o[2] = {async_output(needed[0]), async_output(needed[1])};
  m.merge(o[0].misuse);
  m.merge(o[1].misuse);
  async_desc_misuse(m, vt, s, null_scene, o[0].capacity, "vt_query");
  async_desc_misuse(m, ee, s, null_scene, o[1].capacity, "ee_query");
  uint64_t counts[2] = {kCountSentinel, kCountSentinel};
  uint64_t* vt_count = &counts[0];
  uint64_t* ee_count = &counts[1];
  switch (gen_.choice(16)) {
    case 0: vt_count = nullptr; m.add(true, MINKQ_ERROR_INVALID_ARGUMENT, "vt_count NULL"); break;
    case 1: ee_count = nullptr; m.add(true, MINKQ_ERROR_INVALID_ARGUMENT, "ee_count NULL"); break;
    case 2: ee_count = vt_count; m.add(true, MINKQ_ERROR_INVALID_ARGUMENT, "vt_count == ee_count"); break;
    default: break;
  }
  const uint64_t before = null_scene ? 0 : scene_full_state(*s);
  const minkq_status st = minkq_scene_query_vt_ee_async(
      null_scene ? nullptr : s->handle, vt.null_desc ? nullptr : &vt.desc, ee.null_desc ? nullptr : &ee.desc,
      o[0].data, o[0].capacity, vt_count, o[1].data, o[1].capacity, ee_count, stream());
  expect("minkq_scene_query_vt_ee_async", st, m);
  if (null_scene) return;
  const bool ok = st == MINKQ_SUCCESS;
  if (ok && ee_count == vt_count) failure("minkq_scene_query_vt_ee_async succeeded with vt_count == ee_count");
  check_async_output("minkq_scene_query_vt_ee_async (VT)", ok, o[0], vt_count, counts[0], *s, vt, needed[0],
                     expected[0]);
  check_async_output("minkq_scene_query_vt_ee_async (EE)", ok, o[1], ee_count, ee_count ? *ee_count : kCountSentinel,
                     *s, ee, needed[1], expected[1]);
  if (scene_full_state(*s) != before) failure("minkq_scene_query_vt_ee_async changed the scene");
}

// minkq_scene_async_status: the pending error of the model, once, with a message naming the
// call and the vertex; then SUCCESS.
void Session::scene_async_status() {
  bool null_scene;
  SceneSlot* s = live_scene(&null_scene);
  async_status_on(s, null_scene);
}
void Session::async_status_on(SceneSlot* s, bool null_scene) {
  const int times = gen_.choice(3) == 0 ? 2 : 1;
  for (int k = 0; k < times; ++k) {
    Misuse m;
    m.add(null_scene, MINKQ_ERROR_INVALID_ARGUMENT, "scene NULL");
    const PendingModel pending = null_scene ? PendingModel{} : s->pending;
    const uint64_t before = null_scene ? 0 : scene_full_state(*s);
    const minkq_status st = minkq_scene_async_status(null_scene ? nullptr : s->handle, stream());
    const std::string message = minkq_last_error_message();
    expect("minkq_scene_async_status", st, m, pending.call ? MINKQ_ERROR_NON_FINITE : MINKQ_SUCCESS);
    if (null_scene) return;
    if (st == MINKQ_ERROR_NON_FINITE) {
      ++g_async_pending;
      const std::string want = std::string(pending.call == 2 ? "minkq_scene_rebuild_async" : "minkq_scene_refit_async") +
                               ": vertex " + std::to_string(pending.vertex) + " ";
      if (message.compare(0, want.size(), want) != 0 || message.find("non-finite") == std::string::npos)
        failure("minkq_scene_async_status: message \"" + message + "\" does not name the call and vertex (\"" + want +
                "...\")");
    }
    s->pending = {};
    if (scene_full_state(*s) != before) failure("minkq_scene_async_status changed the scene");
  }
}

}  // namespace minkq::capi_fuzz
