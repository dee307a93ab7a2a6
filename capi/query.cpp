// The C ABI: scene queries (blocking, fused VT + EE, stream-ordered) and library-owned results.
#include "front_end.h"

using namespace minkq::capi;

namespace {

// A scene query's description, checked; `name` names it in messages ("query", "vt_query").
minkq::QueryRequest checked_scene_request(const minkq_scene* scene, const minkq_query_desc* query,
                                          const std::string& name) {
  require(query != nullptr, Status::kInvalidArgument, name + " is NULL");
  const int64_t kind = enum_value(query->kind), mode = enum_value(query->mode);
  require(kind >= MINKQ_QUERY_VT && kind <= MINKQ_QUERY_EV, Status::kInvalidArgument,
          name + "->kind is not a minkq_query_kind value");
  require(mode >= MINKQ_MODE_BOX && mode <= MINKQ_MODE_CAPSULE_EXACT, Status::kInvalidArgument,
          name + "->mode is not a minkq_mode value");
  require((query->flags & ~kKnownQueryFlags) == 0, Status::kInvalidArgument, name + "->flags has unknown bits");
  require_count_alone(query->flags, name);
  static const char* const kKindNames[] = {"VT", "EE", "VV", "EV"};
  static const uint32_t kKindFlags[] = {MINKQ_SCENE_VT, MINKQ_SCENE_EE, MINKQ_SCENE_VV, MINKQ_SCENE_EV};
  const std::string kind_name = kKindNames[kind];
  require(scene->flags & kKindFlags[kind], Status::kInvalidArgument,
          kind_name + " query on a scene created without MINKQ_SCENE_" + kind_name);
  const bool ee = kind == MINKQ_QUERY_EE;
  require(!ee || query->mode != MINKQ_MODE_SPHERE, Status::kInvalidArgument,
          "sphere mode needs point queries; use capsule_ray or capsule_exact for EE");
  require_radius(query->radius);
  if (scene->store->swept()) {
    require(!(query->flags & MINKQ_QUERY_LEAF_EXACT), Status::kUnsupported,
            name + "->flags asks for MINKQ_QUERY_LEAF_EXACT on swept positions: that needs a narrow phase "
                   "(the time of closest approach), which minkq leaves to the caller; query without it");
    require(!ee || query->mode == MINKQ_MODE_BOX, Status::kUnsupported,
            name + ": swept EE queries run box mode only (a moving edge sweeps no segment)");
  }
  uint32_t filters = 0;
  if (scene->flags & MINKQ_SCENE_DROP_INCIDENT) filters |= minkq::kDropIncident;
  if (query->flags & MINKQ_QUERY_LEAF_EXACT) filters |= minkq::kLeafExact;
  static const minkq::QueryKind kKinds[] = {minkq::QueryKind::kVertexTriangle, minkq::QueryKind::kEdgeEdge,
                                            minkq::QueryKind::kVertexVertex, minkq::QueryKind::kVertexEdge};
  return {kKinds[kind], static_cast<minkq::Mode>(query->mode), filters, query->radius, {}, {}};
}

// The two descriptions of a fused VT + EE call, checked (the scene too).
std::array<minkq::QueryRequest, 2> checked_vt_ee_requests(const minkq_scene* scene, const minkq_query_desc* vt_query,
                                                          const minkq_query_desc* ee_query) {
  require(scene != nullptr, Status::kInvalidArgument, "scene is NULL");
  const minkq::QueryRequest vt = checked_scene_request(scene, vt_query, "vt_query");
  const minkq::QueryRequest ee = checked_scene_request(scene, ee_query, "ee_query");
  require(vt_query->kind == MINKQ_QUERY_VT, Status::kInvalidArgument, "vt_query->kind is not MINKQ_QUERY_VT");
  require(ee_query->kind == MINKQ_QUERY_EE, Status::kInvalidArgument, "ee_query->kind is not MINKQ_QUERY_EE");
  return {vt, ee};
}

// The pairs a result makes room for when a query finds `count`: an eighth more (and 64), so that
// a count that grows a little from one query to the next, as the contacts of a moving mesh do
// from step to step, fits without growing the buffer and running the query a second time.
uint64_t result_room(uint64_t count) {
  const uint64_t limit = uint64_t(SIZE_MAX / (2 * sizeof(int32_t)));
  return count >= limit ? count : std::min(limit, count + count / 8 + 64);
}

// Runs query(infos), a call writing into the results' buffers, so that the results grow as
// needed: on CAPACITY each short buffer grows to result_room(its exact count) and the call runs
// again.
template <size_t N, class Query>
minkq_status query_into_results(const std::array<minkq_result*, N>& results, Query&& query) {
  std::array<minkq_query_info, N> info{};
  minkq_status status = query(info);
  if (status == MINKQ_ERROR_CAPACITY) {
    const minkq_status grown = guarded([&] {
      for (size_t k = 0; k < N; ++k)
        if (results[k]->pairs.size() / 2 < info[k].count) {
          results[k]->pairs.clear();  // nothing to keep: no copy of the old pairs
          results[k]->pairs.resize(size_t(result_room(info[k].count)) * 2);
        }
    });
    if (grown != MINKQ_SUCCESS) return grown;
    status = query(info);
  }
  for (size_t k = 0; k < N; ++k) {
    results[k]->count = status == MINKQ_SUCCESS ? info[k].count : 0;
    results[k]->digest = status == MINKQ_SUCCESS ? info[k].digest : 0;
    results[k]->stats = status == MINKQ_SUCCESS ? info[k].stats : minkq_query_stats{};
  }
  return status;
}

// A count-only query into a result keeps no pairs: the pairs of an earlier query go (their
// memory stays for the next one), so that minkq_result_pairs gives NULL.
void drop_pairs_if_counting(const minkq_query_desc* query, minkq_result* result) {
  if (query != nullptr && (query->flags & MINKQ_QUERY_COUNT)) result->pairs.clear();
}

// An asynchronous query's outputs, checked: pairs and count in the call's memory, flags the
// path supports, canonical order within the reservation. `prefix` names the query ("", "vt_").
minkq::PairOutput checked_async_output(const minkq_scene* scene, const minkq_query_desc* query, int32_t* out_pairs,
                                       size_t capacity, uint64_t* out_count, const std::string& prefix) {
  const minkq_device* device = scene->device;
  const std::string pairs = prefix.empty() ? "out_pairs" : prefix + "pairs";
  const std::string count = prefix.empty() ? "out_count" : prefix + "count";
  const std::string cap = prefix + "capacity";
  const std::string name = prefix.empty() ? "query" : prefix + "query";
  require((query->flags & (MINKQ_QUERY_DIGEST | MINKQ_QUERY_STATS)) == 0, Status::kUnsupported,
          name + "->flags asks for a digest or stats, which need a host read: asynchronous queries support "
                 "MINKQ_QUERY_LEAF_EXACT, MINKQ_QUERY_CANONICAL and MINKQ_QUERY_COUNT");
  require(out_count != nullptr, Status::kInvalidArgument, count + " is NULL");
  if (query->flags & MINKQ_QUERY_COUNT) {  // the count alone: no room for pairs, nothing to sort
    if (device->kind == MINKQ_BACKEND_CUDA) device->backend->check_device_pointer(out_count, count);
    return {nullptr, 0, static_cast<minkq::Memory>(async_memory(device)), false, out_count};
  }
  require_pair_capacity(out_pairs, capacity, pairs, cap);
  const bool canonical = (query->flags & MINKQ_QUERY_CANONICAL) != 0;
  const size_t reserved = scene->store->reservation().canonical_capacity;
  require(!canonical || capacity <= reserved, Status::kInvalidArgument,
          "canonical order for " + cap + " " + std::to_string(capacity) + " needs that many pairs reserved: " +
              "minkq_scene_reserve(scene, flags, " + std::to_string(capacity) + ") (reserved: " +
              std::to_string(reserved) + ")");
  if (device->kind == MINKQ_BACKEND_CUDA) {
    if (capacity > 0) device->backend->check_device_pointer(out_pairs, pairs);
    device->backend->check_device_pointer(out_count, count);
  }
  return {out_pairs, capacity, static_cast<minkq::Memory>(async_memory(device)), canonical, out_count};
}

}  // namespace

extern "C" {

minkq_status minkq_scene_query(minkq_scene* scene, const minkq_query_desc* query, int32_t* out_pairs,
                               size_t capacity, minkq_memory out_memory, minkq_query_info* info) {
  return guarded([&] {
    require(scene != nullptr, Status::kInvalidArgument, "scene is NULL");
    const minkq::QueryRequest request = checked_scene_request(scene, query, "query");
    run_and_report(scene->device, *scene->store, request, query->flags, out_pairs, capacity, out_memory, info);
  });
}

minkq_status minkq_scene_query_vt_ee(minkq_scene* scene, const minkq_query_desc* vt_query,
                                     const minkq_query_desc* ee_query, int32_t* vt_pairs, size_t vt_capacity,
                                     int32_t* ee_pairs, size_t ee_capacity, minkq_memory out_memory,
                                     minkq_query_info* vt_info, minkq_query_info* ee_info) {
  return guarded([&] {
    const auto [vt, ee] = checked_vt_ee_requests(scene, vt_query, ee_query);
    const minkq::PairOutput vt_out =
        checked_output(scene->device, vt_pairs, vt_capacity, out_memory, vt_query->flags, vt_info,
                       {"vt_pairs", "vt_capacity", "vt_info"});
    const minkq::PairOutput ee_out =
        checked_output(scene->device, ee_pairs, ee_capacity, out_memory, ee_query->flags, ee_info,
                       {"ee_pairs", "ee_capacity", "ee_info"});
    require(vt_info != ee_info, Status::kInvalidArgument, "vt_info and ee_info are the same struct");
    *vt_info = minkq_query_info{};
    *ee_info = minkq_query_info{};
    minkq::WorkCounts vt_work, ee_work;
    const std::array<uint64_t, 2> counts = scene->store->query_vt_ee(
        {vt, vt_out, (vt_query->flags & MINKQ_QUERY_STATS) ? &vt_work : nullptr},
        {ee, ee_out, (ee_query->flags & MINKQ_QUERY_STATS) ? &ee_work : nullptr});
    const bool vt_fits = report(scene->device, vt_out, vt_query->flags, counts[0], vt_work, vt_info);
    const bool ee_fits = report(scene->device, ee_out, ee_query->flags, counts[1], ee_work, ee_info);
    if (!vt_fits) fail(Status::kCapacity, "VT: " + capacity_message(counts[0], vt_capacity));
    if (!ee_fits) fail(Status::kCapacity, "EE: " + capacity_message(counts[1], ee_capacity));
  });
}

minkq_status minkq_scene_query_async(minkq_scene* scene, const minkq_query_desc* query, int32_t* out_pairs,
                                     size_t capacity, uint64_t* out_count, minkq_stream stream) {
  return guarded([&] {
    require(scene != nullptr, Status::kInvalidArgument, "scene is NULL");
    const minkq::QueryRequest request = checked_scene_request(scene, query, "query");
    const minkq::PairOutput out = checked_async_output(scene, query, out_pairs, capacity, out_count, "");
    scene->store->query_async(request, out, stream);
  });
}

minkq_status minkq_scene_query_vt_ee_async(minkq_scene* scene, const minkq_query_desc* vt_query,
                                           const minkq_query_desc* ee_query, int32_t* vt_pairs, size_t vt_capacity,
                                           uint64_t* vt_count, int32_t* ee_pairs, size_t ee_capacity,
                                           uint64_t* ee_count, minkq_stream stream) {
  return guarded([&] {
    const auto [vt, ee] = checked_vt_ee_requests(scene, vt_query, ee_query);  // checks scene first
    const minkq::PairOutput vt_out = checked_async_output(scene, vt_query, vt_pairs, vt_capacity, vt_count, "vt_");
    const minkq::PairOutput ee_out = checked_async_output(scene, ee_query, ee_pairs, ee_capacity, ee_count, "ee_");
    require(vt_count != ee_count, Status::kInvalidArgument, "vt_count and ee_count are the same pointer");
    scene->store->query_vt_ee_async(vt, vt_out, ee, ee_out, stream);
  });
}

minkq_status minkq_result_create(minkq_result** out_result) {
  return guarded([&] {
    require(out_result != nullptr, Status::kInvalidArgument, "out_result is NULL");
    *out_result = new minkq_result();
  });
}
void minkq_result_release(minkq_result* result) { delete result; }
uint64_t minkq_result_count(const minkq_result* result) { return result ? result->count : 0; }
const int32_t* minkq_result_pairs(const minkq_result* result) {
  // A count-only query keeps no pairs (drop_pairs_if_counting): its buffer holds fewer than its count.
  return result && result->count > 0 && result->pairs.size() / 2 >= result->count ? result->pairs.data() : nullptr;
}
uint64_t minkq_result_digest(const minkq_result* result) { return result ? result->digest : 0; }
minkq_query_stats minkq_result_stats(const minkq_result* result) { return result ? result->stats : minkq_query_stats{}; }

minkq_status minkq_scene_query_result(minkq_scene* scene, const minkq_query_desc* query, minkq_result* result) {
  if (result == nullptr) {
    last_error = "result is NULL";
    return MINKQ_ERROR_INVALID_ARGUMENT;
  }
  drop_pairs_if_counting(query, result);
  return query_into_results<1>({result}, [&](std::array<minkq_query_info, 1>& info) {
    return minkq_scene_query(scene, query, result->pairs.data(), result->pairs.size() / 2, MINKQ_MEMORY_HOST,
                             &info[0]);
  });
}

minkq_status minkq_scene_query_vt_ee_result(minkq_scene* scene, const minkq_query_desc* vt_query,
                                            const minkq_query_desc* ee_query, minkq_result* vt_result,
                                            minkq_result* ee_result) {
  if (vt_result == nullptr || ee_result == nullptr || vt_result == ee_result) {
    last_error = vt_result == nullptr   ? "vt_result is NULL"
                 : ee_result == nullptr ? "ee_result is NULL"
                                        : "vt_result and ee_result are the same result";
    return MINKQ_ERROR_INVALID_ARGUMENT;
  }
  drop_pairs_if_counting(vt_query, vt_result);
  drop_pairs_if_counting(ee_query, ee_result);
  return query_into_results<2>({vt_result, ee_result}, [&](std::array<minkq_query_info, 2>& info) {
    return minkq_scene_query_vt_ee(scene, vt_query, ee_query, vt_result->pairs.data(), vt_result->pairs.size() / 2,
                                   ee_result->pairs.data(), ee_result->pairs.size() / 2, MINKQ_MEMORY_HOST, &info[0],
                                   &info[1]);
  });
}

}  // extern "C"
