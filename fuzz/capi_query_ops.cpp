// The C API fuzzer's blocking scene queries (Session, capi_session.h): a query's arguments and
// output buffers with their misuses, the library-owned result path as the reference, and
// minkq_scene_query, _query_vt_ee, _query_result and minkq_scene_edges.
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "capi_session.h"

namespace minkq::capi_fuzz {

// `want_kind` >= 0: mostly that kind (the fused calls); `async`: mostly flags an asynchronous
// query supports (no DIGEST, no STATS), so that most asynchronous queries get past the checks.
Session::QueryArgs Session::query_args(const SceneSlot* s, bool null_scene, int want_kind, bool async) {
  QueryArgs a;
  const int k = gen_.choice(12);
  a.kind = k < 5 ? MINKQ_QUERY_VT : k < 10 ? MINKQ_QUERY_EE : (k == 10 ? 4 : -1);  // (2, 3: VV, EV, not modelled)
  if (want_kind >= 0 && gen_.choice(6) != 0) a.kind = want_kind;
  const int md = gen_.choice(14);
  a.mode = md < 12 ? md % 4 : (md == 12 ? 4 : 99);
  // (MINKQ_QUERY_COUNT, 16, is not modelled: the unknown bits drawn start above it.)
  a.flags = uint32_t(gen_.choice(16)) | (gen_.rarely() ? 32u << gen_.choice(19) : 0u);
  if (async && gen_.choice(4) != 0) a.flags &= ~uint32_t(MINKQ_QUERY_DIGEST | MINKQ_QUERY_STATS);
  a.r = gen_.radius();
  a.null_desc = gen_.rarely() && gen_.choice(2);
  shim_query_desc(&a.desc, a.kind, a.mode, a.flags, a.r);
  Misuse& m = a.misuse;
  m.add(null_scene, MINKQ_ERROR_INVALID_ARGUMENT, "scene NULL");
  m.add(a.null_desc, MINKQ_ERROR_INVALID_ARGUMENT, "query NULL");
  if (!a.null_desc) {
    const bool kind_ok = a.kind == MINKQ_QUERY_VT || a.kind == MINKQ_QUERY_EE;
    m.add(!kind_ok, MINKQ_ERROR_INVALID_ARGUMENT, "kind invalid");
    m.add(a.mode < 0 || a.mode > 3, MINKQ_ERROR_INVALID_ARGUMENT, "mode invalid");
    m.add(a.flags & ~31u, MINKQ_ERROR_INVALID_ARGUMENT, "unknown query flags");
    if (!null_scene && kind_ok)
      m.add(!(s->flags & (a.kind == MINKQ_QUERY_VT ? MINKQ_SCENE_VT : MINKQ_SCENE_EE)), MINKQ_ERROR_INVALID_ARGUMENT,
            "kind not built");
    m.add(a.kind == MINKQ_QUERY_EE && a.mode == MINKQ_MODE_SPHERE, MINKQ_ERROR_INVALID_ARGUMENT, "EE sphere mode");
    m.add(!std::isfinite(a.r), MINKQ_ERROR_NON_FINITE, "radius not finite");
    m.add(a.r < 0, MINKQ_ERROR_INVALID_ARGUMENT, "radius negative");
  }
  return a;
}
// `own_memory` false: host memory, never misused (the fused call's second buffer shares the first's).
Session::Output Session::output(uint64_t needed, bool own_memory) {
  Output o;
  switch (gen_.choice(8)) {
    case 0: o.capacity = 0; break;
    case 1: o.capacity = needed > 0 ? size_t(needed - 1) : 0; break;  // one short
    case 2: o.capacity = size_t(needed) + size_t(gen_.choice(4)); break;
    case 3: o.capacity = size_t(gen_.choice(4)); break;
    default: o.capacity = size_t(needed); break;
  }
  o.pairs.assign(2 * o.capacity, -5);
  o.data = o.capacity ? o.pairs.data() : (gen_.choice(2) ? nullptr : reinterpret_cast<int32_t*>(&o));
  if (gen_.rarely()) {
    const int c = gen_.choice(3);
    if (c == 0) {
      o.data = nullptr;
      o.capacity = 1 + size_t(gen_.choice(3));
      o.misuse.add(true, MINKQ_ERROR_INVALID_ARGUMENT, "out_pairs NULL with capacity");
    } else {
      o.capacity = c == 1 ? SIZE_MAX : SIZE_MAX / 8 + 1;  // declared, not held: must be rejected
      if (o.data == nullptr) o.data = reinterpret_cast<int32_t*>(&o);
      o.misuse.add(true, MINKQ_ERROR_SIZE_OVERFLOW, "capacity overflows");
    }
  }
  o.memory = own_memory && gen_.choice(6) == 0 ? gen_.memory() : MINKQ_MEMORY_HOST;
  o.misuse.add(o.memory != MINKQ_MEMORY_HOST && o.memory != MINKQ_MEMORY_DEVICE, MINKQ_ERROR_INVALID_ARGUMENT,
               "out_memory invalid");
  o.misuse.add(o.memory == MINKQ_MEMORY_DEVICE, MINKQ_ERROR_INVALID_ARGUMENT, "out_memory device on CPU");
  o.null_info = gen_.rarely() && gen_.choice(2);
  o.misuse.add(o.null_info, MINKQ_ERROR_INVALID_ARGUMENT, "info NULL");
  return o;
}

// The count and digest of a query through the library-owned result (trusted after checks).
bool Session::reference_count(minkq_scene* scene, const minkq_query_desc& d, uint64_t* count,
                              std::vector<int32_t>* pairs) {
  const minkq::cxx::Result r = own_result();
  const minkq_status st = minkq_scene_query_result(scene, &d, r.get());
  *count = minkq_result_count(r.get());
  if (pairs) pairs->assign(minkq_result_pairs(r.get()), minkq_result_pairs(r.get()) + 2 * *count);
  return st == MINKQ_SUCCESS;
}

void Session::scene_query() {
  bool null_scene;
  SceneSlot* s = scene(&null_scene);
  QueryArgs a = query_args(s, null_scene);
  uint64_t needed = 0;
  std::vector<int32_t> expected;
  if (a.misuse.none() && !reference_count(s->handle, a.desc, &needed, &expected))
    failure("a valid query failed through minkq_scene_query_result: " + std::string(minkq_last_error_message()));
  Output o = output(needed);
  Misuse m = a.misuse;
  m.merge(o.misuse);
  minkq_query_info info{12345, 67890, {1, 2, 3, 4}};
  const minkq_status st = shim_scene_query(null_scene ? nullptr : s->handle, a.null_desc ? nullptr : &a.desc, o.data,
                                           o.capacity, o.memory, o.null_info ? nullptr : &info);
  expect("minkq_scene_query", st, m, needed > o.capacity ? MINKQ_ERROR_CAPACITY : MINKQ_SUCCESS);
  if (st == MINKQ_ERROR_CAPACITY && info.count != needed) failure("CAPACITY: info.count is not the exact count needed");
  if ((st == MINKQ_SUCCESS || st == MINKQ_ERROR_CAPACITY) &&
      info.stats.candidates != ((a.flags & MINKQ_QUERY_STATS) ? info.count : 0u))
    failure("info.stats.candidates is not the count with MINKQ_QUERY_STATS, or not 0 without");
  if (st != MINKQ_SUCCESS) return;
  if (info.count != needed) failure("minkq_scene_query and minkq_scene_query_result disagree on the count");
  check_pairs("minkq_scene_query", o.pairs.data(), info.count, queries_of(*s, a.kind), prims_of(*s, a.kind),
              a.kind == MINKQ_QUERY_EE, a.flags, info.digest);
  for (size_t i = 2 * size_t(info.count); i < o.pairs.size(); ++i)
    if (o.pairs[i] != -5) failure("minkq_scene_query wrote past the pairs it reported");
  if (a.flags & (MINKQ_QUERY_CANONICAL | MINKQ_QUERY_DIGEST)) {
    o.pairs.resize(2 * size_t(info.count));
    if (o.pairs != expected) failure("canonical pairs differ between minkq_scene_query and the result path");
  }
}

// The fused call: a VT and an EE description (either may be misused, or of the wrong kind),
// two outputs in one memory; each query that fits must be written as the result path gives it.
void Session::scene_query_vt_ee() {
  bool null_scene;
  SceneSlot* s = scene(&null_scene);
  const QueryArgs vt = query_args(s, null_scene), ee = query_args(s, null_scene);
  Misuse m = vt.misuse;
  m.merge(ee.misuse);
  m.add(!vt.null_desc && vt.kind != MINKQ_QUERY_VT, MINKQ_ERROR_INVALID_ARGUMENT, "vt_query not VT");
  m.add(!ee.null_desc && ee.kind != MINKQ_QUERY_EE, MINKQ_ERROR_INVALID_ARGUMENT, "ee_query not EE");
  uint64_t needed[2] = {0, 0};
  std::vector<int32_t> expected[2];
  if (m.none() && !(reference_count(s->handle, vt.desc, &needed[0], &expected[0]) &&
                    reference_count(s->handle, ee.desc, &needed[1], &expected[1])))
    failure("a valid query failed through minkq_scene_query_result: " + std::string(minkq_last_error_message()));
  Output o[2] = {output(needed[0]), output(needed[1], false)};
  m.merge(o[0].misuse);
  m.merge(o[1].misuse);
  minkq_query_info info[2] = {{12345, 67890, {1, 2, 3, 4}}, {54321, 9876, {4, 3, 2, 1}}};
  const minkq_status st = shim_scene_query_vt_ee(
      null_scene ? nullptr : s->handle, vt.null_desc ? nullptr : &vt.desc, ee.null_desc ? nullptr : &ee.desc,
      o[0].data, o[0].capacity, o[1].data, o[1].capacity, o[0].memory, o[0].null_info ? nullptr : &info[0],
      o[1].null_info ? nullptr : &info[1]);
  const bool short_buffer = needed[0] > o[0].capacity || needed[1] > o[1].capacity;
  expect("minkq_scene_query_vt_ee", st, m, short_buffer ? MINKQ_ERROR_CAPACITY : MINKQ_SUCCESS);
  if (st != MINKQ_SUCCESS && st != MINKQ_ERROR_CAPACITY) return;
  const QueryArgs* args[2] = {&vt, &ee};
  for (int k = 0; k < 2; ++k) {
    if (info[k].count != needed[k]) failure("minkq_scene_query_vt_ee: a count is not the exact count");
    if (info[k].stats.candidates != ((args[k]->flags & MINKQ_QUERY_STATS) ? info[k].count : 0u))
      failure("minkq_scene_query_vt_ee: stats.candidates is not the count with MINKQ_QUERY_STATS, or not 0 without");
    if (needed[k] > o[k].capacity) {
      for (int32_t x : o[k].pairs)
        if (x != -5) failure("minkq_scene_query_vt_ee wrote into a buffer too small for its query");
      continue;
    }
    check_pairs("minkq_scene_query_vt_ee", o[k].pairs.data(), info[k].count, queries_of(*s, args[k]->kind),
                prims_of(*s, args[k]->kind), k == 1, args[k]->flags, info[k].digest);
    for (size_t i = 2 * size_t(info[k].count); i < o[k].pairs.size(); ++i)
      if (o[k].pairs[i] != -5) failure("minkq_scene_query_vt_ee wrote past the pairs it reported");
    if (args[k]->flags & (MINKQ_QUERY_CANONICAL | MINKQ_QUERY_DIGEST)) {
      o[k].pairs.resize(2 * size_t(info[k].count));
      if (o[k].pairs != expected[k]) failure("minkq_scene_query_vt_ee: canonical pairs differ from the result path");
    }
  }
}

void Session::scene_query_result() {
  bool null_scene;
  SceneSlot* s = scene(&null_scene);
  QueryArgs a = query_args(s, null_scene);
  const int which = gen_.choice(3);
  minkq_result* r = which < 2 ? st_.results[which] : nullptr;
  if (which < 2 && r == nullptr) {
    if (minkq_result_create(&st_.results[which]) != MINKQ_SUCCESS) failure("minkq_result_create");
    r = st_.results[which];
  }
  Misuse m = a.misuse;
  m.add(r == nullptr, MINKQ_ERROR_INVALID_ARGUMENT, "result NULL");
  const minkq_status st = minkq_scene_query_result(null_scene ? nullptr : s->handle, a.null_desc ? nullptr : &a.desc, r);
  expect("minkq_scene_query_result", st, m);
  if (st != MINKQ_SUCCESS) {
    if (r && minkq_result_count(r) != 0) failure("a failed query left a count in the result");
    return;
  }
  check_pairs("minkq_scene_query_result", minkq_result_pairs(r), minkq_result_count(r), queries_of(*s, a.kind),
              prims_of(*s, a.kind), a.kind == MINKQ_QUERY_EE, a.flags, minkq_result_digest(r));
}

void Session::scene_edges() {
  bool null_scene;
  SceneSlot* s = scene(&null_scene);
  const size_t ne = null_scene ? 0 : s->edges;
  size_t capacity = gen_.choice(3) == 0 ? size_t(gen_.choice(4)) : ne + size_t(gen_.choice(2));
  std::vector<int32_t> out(2 * capacity, -3);
  int32_t* data = capacity ? out.data() : nullptr;
  Misuse m;
  m.add(null_scene, MINKQ_ERROR_INVALID_ARGUMENT, "scene NULL");
  if (gen_.rarely()) {
    data = nullptr;
    capacity = 1 + capacity;
    m.add(true, MINKQ_ERROR_INVALID_ARGUMENT, "out_edges NULL with capacity");
  }
  const minkq_status st = minkq_scene_edges(null_scene ? nullptr : s->handle, data, capacity);
  expect("minkq_scene_edges", st, m, ne > capacity ? MINKQ_ERROR_CAPACITY : MINKQ_SUCCESS);
  if (st == MINKQ_SUCCESS)
    for (size_t i = 2 * ne; i < out.size(); ++i)
      if (out[i] != -3) failure("minkq_scene_edges wrote past the edges");
}

}  // namespace minkq::capi_fuzz
