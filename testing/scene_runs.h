// Running minkq through the C API: every mode's query on a scene or a bvh, the pair-buffer
// contract checked on each output (range, order, duplicates, canonical order, digest, the three
// ways of passing output buffers, nothing written past the count), and the devices to run on.
// Part of the scene checks (scene_checks.h includes every part).
#pragma once

#include <xxhash.h>

#include "minkq.hpp"
#include "scene_definitions.h"

namespace minkq::fuzz {

// ---- Running minkq through the C API -------------------------------------------------------

// Self-test of the harness (MINKQ_FUZZ_INJECT=1 in the fuzzer): drops one leaf-exact VT pair
// from minkq's answer, which every scene with a VT contact must then report.
inline bool& inject_fault() {
  static bool inject = false;
  return inject;
}

inline std::string status_text(minkq_status status) {
  return std::string(minkq_status_name(status)) + " (" + minkq_last_error_message() + ")";
}

// Checks a query's raw output and returns it sorted. `variant` picks canonical/digest flags
// and how the buffer is passed: exact capacity after a counting call, a library-owned result,
// or a larger buffer whose tail must stay untouched.
template <class Call>
Pairs checked_pairs(Call&& call, uint32_t flags, uint32_t variant, int32_t num_queries, int32_t num_prims,
                    bool ordered, Report& report, const std::string& what, minkq_result* result) {
  const bool canonical = (variant & 1) != 0, digest = (variant & 2) != 0;
  flags |= (canonical ? uint32_t(MINKQ_QUERY_CANONICAL) : 0u) | (digest ? uint32_t(MINKQ_QUERY_DIGEST) : 0u);
  std::vector<int32_t> raw;
  minkq_query_info info{};
  const int path = int((variant >> 2) % 3);
  minkq_status status = MINKQ_SUCCESS;
  if (path == 1 && result != nullptr) {
    status = call(flags, nullptr, size_t(0), &info, result);
    if (status == MINKQ_SUCCESS) {
      info.count = minkq_result_count(result);
      info.digest = minkq_result_digest(result);
      const int32_t* p = minkq_result_pairs(result);
      raw.assign(p, p + 2 * info.count);
    }
  } else {
    status = call(flags, nullptr, size_t(0), &info, nullptr);
    if (status == MINKQ_ERROR_CAPACITY) {
      const size_t count = size_t(info.count), spare = path == 2 ? 3 : 0;
      raw.assign(2 * (count + spare), -7);
      status = call(flags, raw.data(), count + spare, &info, nullptr);
      if (status == MINKQ_SUCCESS && info.count != count)
        report.fail(what + ": count " + std::to_string(info.count) + " differs from the counting call's " +
                    std::to_string(count));
      for (size_t i = 2 * size_t(info.count); i < raw.size(); ++i)
        if (raw[i] != -7) {
          report.fail(what + ": written past the reported count");
          break;
        }
      raw.resize(2 * std::min(size_t(info.count), count + spare));
    } else if (status == MINKQ_SUCCESS && info.count != 0) {
      report.fail(what + ": capacity 0 succeeded with count " + std::to_string(info.count));
    }
  }
  if (status != MINKQ_SUCCESS) {
    report.fail(what + ": " + status_text(status));
    return {};
  }
  Pairs pairs(raw.size() / 2);
  for (size_t i = 0; i < pairs.size(); ++i) pairs[i] = {raw[2 * i], raw[2 * i + 1]};
  for (const auto& [q, p] : pairs)
    if (q < 0 || q >= num_queries || p < 0 || p >= num_prims || (ordered && !(q < p))) {
      report.fail(what + ": pair (" + std::to_string(q) + "," + std::to_string(p) + ") out of range or order");
      break;
    }
  if (canonical && !std::is_sorted(pairs.begin(), pairs.end())) report.fail(what + ": CANONICAL output not sorted");
  if (digest && info.digest != XXH64(raw.data(), raw.size() * sizeof(int32_t), 0))
    report.fail(what + ": digest differs from XXH64 of the canonical pairs");
  std::sort(pairs.begin(), pairs.end());
  if (std::adjacent_find(pairs.begin(), pairs.end()) != pairs.end()) report.fail(what + ": duplicate pairs");
  return pairs;
}

inline MeshSets minkq_mesh_sets(minkq_scene* scene, const MeshGeometry& g, float r, uint32_t variant, Report& report,
                                Stats& stats, const std::string& tag, minkq_result* result) {
  MeshSets sets;
  int k = 0;
  for (int kind = 0; kind < 2; ++kind)
    for (int mode = 0; mode < 4; ++mode)
      for (int leaf = 0; leaf < 2; ++leaf) {
        if (kind == 1 && !ee_mode(mode)) continue;
        const minkq_query_kind query_kind = kind == 0 ? MINKQ_QUERY_VT : MINKQ_QUERY_EE;
        auto call = [&](uint32_t flags, int32_t* out, size_t capacity, minkq_query_info* info, minkq_result* res) {
          const minkq_query_desc desc{query_kind, minkq_mode(mode), flags, r};
          return res ? minkq_scene_query_result(scene, &desc, res)
                     : minkq_scene_query(scene, &desc, out, capacity, MINKQ_MEMORY_HOST, info);
        };
        const std::string what = tag + (kind ? " EE " : " VT ") + mode_name(mode) + (leaf ? "+leaf_exact" : "");
        const int index = k++;
        const uint32_t v = (variant >> (2 * index)) ^ uint32_t(index * 5);  // a different variant per query
        Pairs pairs = checked_pairs(call, leaf ? uint32_t(MINKQ_QUERY_LEAF_EXACT) : 0u, v, kind ? g.ne() : g.nv(),
                                    kind ? g.ne() : g.nt(), kind == 1, report, what, result);
        stats.queries++;
        (kind ? sets.ee : sets.vt)[mode][leaf] = std::move(pairs);
      }
  return sets;
}

// The queries a swept scene runs (every VT mode, EE box; minkq.h, "Swept positions"), checked
// like every other query's output.
inline SweptSets minkq_swept_sets(minkq_scene* scene, const MeshGeometry& g, float r, uint32_t variant, Report& report,
                                  Stats& stats, const std::string& tag, minkq_result* result) {
  SweptSets sets;
  for (int k = 0; k < 5; ++k) {
    const bool vt = k < 4;
    const int mode = vt ? k : int(MINKQ_MODE_BOX);
    auto call = [&](uint32_t flags, int32_t* out, size_t capacity, minkq_query_info* info, minkq_result* res) {
      const minkq_query_desc desc{vt ? MINKQ_QUERY_VT : MINKQ_QUERY_EE, minkq_mode(mode), flags, r};
      return res ? minkq_scene_query_result(scene, &desc, res)
                 : minkq_scene_query(scene, &desc, out, capacity, MINKQ_MEMORY_HOST, info);
    };
    const std::string what = tag + (vt ? " VT " : " EE ") + mode_name(mode);
    const uint32_t v = (variant >> (5 * k + 1)) ^ (variant << (31 - k)) ^ uint32_t(k * 3);  // a variant per query
    Pairs pairs = checked_pairs(call, 0u, v, vt ? g.nv() : g.ne(), vt ? g.nt() : g.ne(), !vt, report, what, result);
    stats.queries++;
    (vt ? sets.vt[mode] : sets.ee_box) = std::move(pairs);
  }
  return sets;
}

// What a swept scene refuses (minkq.h): MINKQ_QUERY_LEAF_EXACT in every mode, and EE modes other
// than box; each must answer MINKQ_ERROR_UNSUPPORTED.
inline void check_swept_refusals(minkq_scene* scene, float r, Report& report, const std::string& tag) {
  struct Refused {
    minkq_query_kind kind;
    minkq_mode mode;
    uint32_t flags;
  };
  const uint32_t leaf = MINKQ_QUERY_LEAF_EXACT;
  const Refused refused[] = {{MINKQ_QUERY_VT, MINKQ_MODE_BOX, leaf},          {MINKQ_QUERY_VT, MINKQ_MODE_SPHERE, leaf},
                             {MINKQ_QUERY_VT, MINKQ_MODE_CAPSULE_RAY, leaf},  {MINKQ_QUERY_VT, MINKQ_MODE_CAPSULE_EXACT, leaf},
                             {MINKQ_QUERY_EE, MINKQ_MODE_BOX, leaf},          {MINKQ_QUERY_EE, MINKQ_MODE_CAPSULE_RAY, 0},
                             {MINKQ_QUERY_EE, MINKQ_MODE_CAPSULE_EXACT, 0},   {MINKQ_QUERY_EE, MINKQ_MODE_CAPSULE_EXACT, leaf}};
  for (const Refused& q : refused) {
    const minkq_query_desc desc{q.kind, q.mode, q.flags | uint32_t(MINKQ_QUERY_CANONICAL), r};
    minkq_query_info info{};
    const minkq_status status = minkq_scene_query(scene, &desc, nullptr, 0, MINKQ_MEMORY_HOST, &info);
    if (status != MINKQ_ERROR_UNSUPPORTED)
      report.fail(tag + " swept " + (q.kind == MINKQ_QUERY_VT ? "VT " : "EE ") + mode_name(q.mode) +
                  (q.flags ? "+leaf_exact" : "") + ": " + status_text(status) + ", not MINKQ_ERROR_UNSUPPORTED");
  }
}

inline BoxSets minkq_box_sets(minkq_bvh* bvh, const BoxScene& s, uint32_t variant, Report& report, Stats& stats,
                              const std::string& tag, int32_t num_boxes) {
  BoxSets sets;
  const size_t nq = s.first.size() / 3;
  for (int mode = 0; mode < 4; ++mode) {
    if (!box_scene_mode(s.shape, mode)) continue;
    auto call = [&](uint32_t flags, int32_t* out, size_t capacity, minkq_query_info* info, minkq_result*) {
      const minkq_bvh_query_desc desc{s.shape, minkq_mode(mode), flags, s.r,
                                      {s.first.data(), 0, nq, MINKQ_MEMORY_HOST},
                                      {s.second.empty() ? nullptr : s.second.data(), 0, s.second.size() / 3,
                                       MINKQ_MEMORY_HOST}};
      return minkq_bvh_query(bvh, &desc, out, capacity, MINKQ_MEMORY_HOST, info);
    };
    sets.by_mode[mode] = checked_pairs(call, 0u, (variant >> (3 * mode)) & 0x1f, int32_t(nq), num_boxes, false,
                                       report, tag + " " + mode_name(mode), nullptr);
    stats.queries++;
  }
  return sets;
}

// The CPU device plus, where CUDA devices exist, each of them; empty if the CPU one fails.
inline std::vector<cxx::Device> open_devices() {
  std::vector<cxx::Device> devices;
  minkq_device* cpu = nullptr;
  if (minkq_device_create("cpu", &cpu) != MINKQ_SUCCESS) return devices;
  devices.emplace_back(cpu);
  for (int i = 0; i < minkq_cuda_device_count(); ++i) {
    minkq_device* gpu = nullptr;
    const std::string spec = "cuda:" + std::to_string(i);
    if (minkq_device_create(spec.c_str(), &gpu) == MINKQ_SUCCESS) devices.emplace_back(gpu);
  }
  return devices;
}

}  // namespace minkq::fuzz
