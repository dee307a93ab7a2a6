// The checks the differential fuzzer runs on one decoded scene, shared with the regression
// tests (tests/test_fuzz_regressions.cpp): every mode through the C API, against
//   - the mode's definition applied to every primitive (brute force, minkq's own shape tests),
//   - an independent traversal computing the same definition (the Embree reference, fuzz only),
//   - the long-double contact oracle of testing/oracle (zero false negatives, leaf-exact
//     extras within r + 2^-19 * S),
//   - the containment chain, the pair-buffer contract (canonical order, digest, no duplicates,
//     nothing written past the count) and refit == fresh build,
//   - every further device (CUDA, where one exists) giving the same sets.
// Failures are collected in a Report, never thrown, so a caller can print the scene first.
#pragma once

#include <xxhash.h>

#include <algorithm>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "minkq.h"
#include "minkq.hpp"
#include "minkq/queries.h"
#include "minkq_reference.h"

namespace minkq::fuzz {

using Pairs = std::vector<std::pair<int32_t, int32_t>>;
using LD = long double;

// ---- Scenes -----------------------------------------------------------------------------------

// A mesh scene: VT and EE queries at radius r, then (if `moved` is not empty) a refit to the
// moved positions and the same checks again.
struct MeshScene {
  std::vector<float> xyz;      // 3 per vertex
  std::vector<int32_t> tris;   // 3 per triangle
  std::vector<int32_t> edges;  // 2 per edge; empty: minkq derives them from the triangles
  float r = 0.0f;
  bool drop_incident = false;
  std::vector<float> moved;  // empty, or new positions for every vertex
  uint32_t variant = 0;      // how the pair buffers are passed (see run_query)
  std::string label;         // which generator made it
};

// A BVH over user boxes queried by spheres (first), capsules (first-second) or boxes.
struct BoxScene {
  std::vector<float> boxes;  // 6 per box: lo xyz, hi xyz
  minkq_shape shape = MINKQ_SHAPE_SPHERE;
  std::vector<float> first, second;  // 3 per query; second empty for spheres
  float r = 0.0f;
  std::vector<float> moved;  // empty, or new boxes (same count) for a refit check
  uint32_t variant = 0;
  std::string label;
};

// ---- Reports ------------------------------------------------------------------------------------

class Report {
 public:
  void fail(const std::string& what) {
    if (failures_.size() < 12) failures_.push_back(what);
    ++count_;
  }
  bool ok() const { return count_ == 0; }
  size_t count() const { return count_; }
  std::string text() const {
    std::string out;
    for (const std::string& f : failures_) out += "  FAIL " + f + "\n";
    if (count_ > failures_.size()) out += "  ... " + std::to_string(count_ - failures_.size()) + " more\n";
    return out;
  }

 private:
  std::vector<std::string> failures_;
  size_t count_ = 0;
};

struct Stats {
  uint64_t mesh_scenes = 0;     // mesh scenes checked (every mode, both kinds)
  uint64_t refit_scenes = 0;    // of which also checked after a refit
  uint64_t box_scenes = 0;      // user-box BVH scenes checked
  uint64_t queries = 0;         // minkq queries run
  uint64_t independent = 0;     // candidate sets compared with the independent traversal
  uint64_t pairs = 0;           // candidate pairs compared
  uint64_t true_contacts = 0;   // oracle contacts found
};

// ---- Printing a scene as C++ (hex floats: exact) ----------------------------------------------

inline std::string fmt_g(double v) {
  char text[48];
  std::snprintf(text, sizeof text, "%.9g", v);
  return text;
}

inline std::string hex_float(float v) {
  char text[48];
  std::snprintf(text, sizeof text, "%af", double(v));
  return text;
}

template <class T, class Format>
std::string list(const std::vector<T>& values, Format format, size_t per_line) {
  std::string out = "{";
  for (size_t i = 0; i < values.size(); ++i) {
    if (i) out += (i % per_line == 0) ? ",\n    " : ", ";
    out += format(values[i]);
  }
  return out + "}";
}
inline std::string float_list(const std::vector<float>& v) { return list(v, hex_float, 3); }
inline std::string int_list(const std::vector<int32_t>& v) {
  return list(v, [](int32_t i) { return std::to_string(i); }, 24);
}

// The scene as a C++ snippet to paste into tests/test_fuzz_regressions.cpp.
inline std::string describe(const MeshScene& s) {
  std::string out = "// " + s.label + ": " + std::to_string(s.xyz.size() / 3) + " vertices, " +
                    std::to_string(s.tris.size() / 3) + " triangles, " +
                    (s.edges.empty() ? std::string("derived edges") : std::to_string(s.edges.size() / 2) + " edges") +
                    "\nfuzz::MeshScene s;\n";
  out += "s.xyz = " + float_list(s.xyz) + ";\n";
  out += "s.tris = " + int_list(s.tris) + ";\n";
  if (!s.edges.empty()) out += "s.edges = " + int_list(s.edges) + ";\n";
  out += "s.r = " + hex_float(s.r) + ";  // " + fmt_g(s.r) + "\n";
  out += std::string("s.drop_incident = ") + (s.drop_incident ? "true" : "false") + ";\n";
  if (!s.moved.empty()) out += "s.moved = " + float_list(s.moved) + ";\n";
  out += "s.variant = " + std::to_string(s.variant) + ";\n";
  return out;
}

inline std::string describe(const BoxScene& s) {
  static const char* shapes[] = {"MINKQ_SHAPE_SPHERE", "MINKQ_SHAPE_CAPSULE", "MINKQ_SHAPE_BOX"};
  std::string out = "// " + s.label + ": " + std::to_string(s.boxes.size() / 6) + " boxes, " +
                    std::to_string(s.first.size() / 3) + " queries\nfuzz::BoxScene s;\n";
  out += "s.boxes = " + list(s.boxes, hex_float, 6) + ";\n";
  out += std::string("s.shape = ") + shapes[int(s.shape) % 3] + ";\n";
  out += "s.first = " + float_list(s.first) + ";\n";
  if (!s.second.empty()) out += "s.second = " + float_list(s.second) + ";\n";
  out += "s.r = " + hex_float(s.r) + ";  // " + fmt_g(s.r) + "\n";
  if (!s.moved.empty()) out += "s.moved = " + list(s.moved, hex_float, 6) + ";\n";
  out += "s.variant = " + std::to_string(s.variant) + ";\n";
  return out;
}

inline std::string show(const Pairs& pairs, size_t max = 6) {
  std::string out;
  for (size_t i = 0; i < pairs.size() && i < max; ++i)
    out += "(" + std::to_string(pairs[i].first) + "," + std::to_string(pairs[i].second) + ") ";
  if (pairs.size() > max) out += "... (" + std::to_string(pairs.size()) + ")";
  return out;
}

inline Pairs minus(const Pairs& a, const Pairs& b) {
  Pairs out;
  std::set_difference(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(out));
  return out;
}

inline void expect_equal(Report& report, const Pairs& got, const Pairs& want, const std::string& what) {
  if (got == want) return;
  report.fail(what + ": " + std::to_string(got.size()) + " vs " + std::to_string(want.size()) +
              " pairs; only in the first: " + show(minus(got, want)) + "; only in the second: " + show(minus(want, got)));
}

inline void expect_subset(Report& report, const Pairs& small, const Pairs& large, const std::string& what) {
  const Pairs outside = minus(small, large);
  if (!outside.empty()) report.fail(what + ": " + std::to_string(outside.size()) + " pairs outside: " + show(outside));
}

// ---- Modes --------------------------------------------------------------------------------------

inline const char* mode_name(int mode) {
  static const char* names[] = {"box", "sphere", "capsule_ray", "capsule_exact"};
  return mode >= 0 && mode < 4 ? names[mode] : "?";
}

// The shape that minkq.h defines for a mode: points are zero-length capsules, so for points
// capsule_ray is the box test and capsule_exact the sphere test. (Written here independently
// of the backend's own mapping, which this checks.)
template <class Fn>
void shape_of_mode(int mode, bool points, Fn&& fn) {
  switch (mode) {
    case MINKQ_MODE_BOX: fn(BoxShape{}); return;
    case MINKQ_MODE_SPHERE: fn(SphereShape{}); return;
    case MINKQ_MODE_CAPSULE_RAY:
      if (points) fn(BoxShape{}); else fn(CapsuleRayShape{});
      return;
    default:
      if (points) fn(SphereShape{}); else fn(CapsuleExactShape{});
      return;
  }
}

// The candidate set a mode defines: the shape's node test applied to every primitive box,
// AND the leaf filter; EE (the edges against themselves) over the pairs q < p only.
template <class Shape, class Queries, class Boxes>
Pairs definition_set(const Queries& queries, int32_t num_queries, const Boxes& boxes, int32_t num_prims) {
  Pairs out;
  for (int32_t q = 0; q < num_queries; ++q) {
    const Shape shape = Shape::from(queries.geometry(q));
    for (int32_t p = std::is_same<Queries, EdgeEdgeQueries>::value ? q + 1 : 0; p < num_prims; ++p)
      if (shape.overlaps(boxes(p)) && queries.template accept<Shape>(q, p)) out.push_back({q, p});
  }
  return out;
}

// The geometry of a mesh scene in the core's types.
struct MeshGeometry {
  std::vector<Vec3> vertices;
  std::vector<Triangle> triangles;
  std::vector<Edge> edges;
  MeshGeometry(const std::vector<float>& xyz, const std::vector<int32_t>& tris, const std::vector<int32_t>& edge_ids)
      : vertices(xyz.size() / 3), triangles(tris.size() / 3), edges(edge_ids.size() / 2) {
    if (!xyz.empty()) std::memcpy(vertices.data(), xyz.data(), vertices.size() * sizeof(Vec3));
    if (!tris.empty()) std::memcpy(triangles.data(), tris.data(), triangles.size() * sizeof(Triangle));
    if (!edge_ids.empty()) std::memcpy(edges.data(), edge_ids.data(), edges.size() * sizeof(Edge));
  }
  int32_t nv() const { return int32_t(vertices.size()); }
  int32_t nt() const { return int32_t(triangles.size()); }
  int32_t ne() const { return int32_t(edges.size()); }
  VertexTriangleQueries vt(float r, uint32_t filters) const {
    return {vertices.data(), triangles.data(), nullptr, r, filters};
  }
  EdgeEdgeQueries ee(float r, uint32_t filters) const { return {vertices.data(), edges.data(), nullptr, r, filters}; }
  TriangleBoxes triangle_boxes() const { return {vertices.data(), triangles.data()}; }
  EdgeBoxes edge_boxes() const { return {vertices.data(), edges.data()}; }
};

// Candidate sets of a mesh scene: [mode][leaf_exact]; EE has no sphere mode (index 1 unused).
struct MeshSets {
  Pairs vt[4][2];
  Pairs ee[4][2];
};
inline bool ee_mode(int mode) { return mode != MINKQ_MODE_SPHERE; }

// Sets of a user-box scene: [mode]; the modes a shape allows (see minkq_shape).
struct BoxSets {
  Pairs by_mode[4];
};
inline bool box_scene_mode(minkq_shape shape, int mode) {
  if (shape == MINKQ_SHAPE_BOX) return mode == MINKQ_MODE_BOX;
  if (shape == MINKQ_SHAPE_CAPSULE) return mode != MINKQ_MODE_SPHERE;
  return true;
}

// The user-box scene in the core's types.
struct BoxGeometry {
  std::vector<Box> boxes;
  std::vector<Vec3> first, second;
  BoxGeometry(const std::vector<float>& b, const std::vector<float>& f, const std::vector<float>& s)
      : boxes(b.size() / 6), first(f.size() / 3), second(s.size() / 3) {
    if (!b.empty()) std::memcpy(boxes.data(), b.data(), boxes.size() * sizeof(Box));
    if (!f.empty()) std::memcpy(first.data(), f.data(), first.size() * sizeof(Vec3));
    if (!s.empty()) std::memcpy(second.data(), s.data(), second.size() * sizeof(Vec3));
  }
  UserQueries queries(float r) const { return {first.data(), second.empty() ? nullptr : second.data(), r}; }
  GivenBoxes given_boxes() const { return {boxes.data()}; }
  int32_t nq() const { return int32_t(first.size()); }
  int32_t nb() const { return int32_t(boxes.size()); }
};

// An independent traversal computing the sets of the same definitions (the Embree reference).
// `moved` says the positions changed since the previous call for the same scene (a refit).
class IndependentSets {
 public:
  virtual ~IndependentSets() = default;
  // False where the independent traversal cannot take the input (Embree drops huge coordinates).
  virtual bool accepts(const std::vector<float>& coordinates, float r) const = 0;
  virtual MeshSets mesh_sets(const MeshGeometry& g, float r, uint32_t filters, bool moved) = 0;
  virtual BoxSets box_sets(const BoxGeometry& g, minkq_shape shape, float r, bool moved) = 0;
  virtual void reset() = 0;  // release what the previous scene left
};

inline MeshSets definition_sets(const MeshGeometry& g, float r, uint32_t filters) {
  MeshSets sets;
  for (int leaf = 0; leaf < 2; ++leaf) {
    const uint32_t f = filters | (leaf ? kLeafExact : 0u);
    for (int mode = 0; mode < 4; ++mode) {
      shape_of_mode(mode, true, [&](auto shape) {
        sets.vt[mode][leaf] = definition_set<decltype(shape)>(g.vt(r, f), g.nv(), g.triangle_boxes(), g.nt());
      });
      if (ee_mode(mode))
        shape_of_mode(mode, false, [&](auto shape) {
          sets.ee[mode][leaf] = definition_set<decltype(shape)>(g.ee(r, f), g.ne(), g.edge_boxes(), g.ne());
        });
    }
  }
  return sets;
}

inline BoxSets definition_sets(const BoxGeometry& g, minkq_shape shape, float r) {
  BoxSets sets;
  for (int mode = 0; mode < 4; ++mode)
    if (box_scene_mode(shape, mode))
      shape_of_mode(mode, shape == MINKQ_SHAPE_SPHERE, [&](auto s) {
        sets.by_mode[mode] = definition_set<decltype(s)>(g.queries(r), g.nq(), g.given_boxes(), g.nb());
      });
  return sets;
}

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

// ---- The oracle's side ----------------------------------------------------------------------

inline void point_of(const std::vector<float>& xyz, int32_t v, double out[3]) {
  for (int k = 0; k < 3; ++k) out[k] = xyz[3 * size_t(v) + k];
}

// Largest distance between the points of a pair (the S of the leaf-exact bound, as in tests/).
inline LD pair_scale(const double (*points)[3], int n) {
  LD s = 0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      const LD dx = LD(points[i][0]) - points[j][0], dy = LD(points[i][1]) - points[j][1],
               dz = LD(points[i][2]) - points[j][2];
      s = std::max(s, std::sqrt(dx * dx + dy * dy + dz * dz));
    }
  return s;
}

// Leaf-exact pairs beyond the true contacts must lie within r + 2^-19 * S: whether the extra
// (a, b), at oracle distance d between its points p, does; a failure is reported.
inline bool extra_within_bound(Report& report, int32_t a, int32_t b, LD d, const double (*p)[3], float r,
                               const std::string& what) {
  const LD bound = LD(r) + std::ldexp(pair_scale(p, 4), -19);
  if (d <= bound) return true;
  char text[160];
  std::snprintf(text, sizeof text, ": leaf-exact extra (%d,%d) at distance %.9Lg beyond r + 2^-19 S = %.9Lg", a, b, d,
                bound);
  report.fail(what + text);
  return false;
}

inline void check_vt_extras(Report& report, const Pairs& extras, const std::vector<float>& xyz,
                            const std::vector<int32_t>& tris, float r, const std::string& what) {
  for (const auto& [v, t] : extras) {
    double p[4][3];
    point_of(xyz, v, p[0]);
    for (int k = 0; k < 3; ++k) point_of(xyz, tris[3 * size_t(t) + k], p[k + 1]);
    if (!extra_within_bound(report, v, t, reference::point_triangle_distance(p[0], p[1], p[2], p[3]), p, r, what)) return;
  }
}

inline void check_ee_extras(Report& report, const Pairs& extras, const std::vector<float>& xyz,
                            const std::vector<int32_t>& edges, float r, const std::string& what) {
  for (const auto& [e, f] : extras) {
    double p[4][3];
    point_of(xyz, edges[2 * size_t(e)], p[0]);
    point_of(xyz, edges[2 * size_t(e) + 1], p[1]);
    point_of(xyz, edges[2 * size_t(f)], p[2]);
    point_of(xyz, edges[2 * size_t(f) + 1], p[3]);
    if (!extra_within_bound(report, e, f, reference::segment_segment_distance(p[0], p[1], p[2], p[3]), p, r, what))
      return;
  }
}

// Point-box and segment-box distances in long double, for user-box queries. The segment case
// minimises the convex piecewise quadratic exactly: between consecutive face crossings the set
// of axes outside the box is fixed and the minimiser is closed-form.
inline LD excess_ld(LD x, LD lo, LD hi) { return x < lo ? lo - x : (x > hi ? x - hi : 0); }
inline LD point_box_distance_ld(const float* p, const Box& b) {
  const float lo[3] = {b.lo.x, b.lo.y, b.lo.z}, hi[3] = {b.hi.x, b.hi.y, b.hi.z};
  LD d2 = 0;
  for (int k = 0; k < 3; ++k) {
    const LD e = excess_ld(p[k], lo[k], hi[k]);
    d2 += e * e;
  }
  return std::sqrt(d2);
}
inline LD segment_box_distance_ld(const float* a, const float* b, const Box& box) {
  const float lo[3] = {box.lo.x, box.lo.y, box.lo.z}, hi[3] = {box.hi.x, box.hi.y, box.hi.z};
  LD d[3], o[3];
  for (int k = 0; k < 3; ++k) o[k] = a[k], d[k] = LD(b[k]) - LD(a[k]);
  auto dist2 = [&](LD t) {
    LD s = 0;
    for (int k = 0; k < 3; ++k) {
      const LD e = excess_ld(o[k] + t * d[k], lo[k], hi[k]);
      s += e * e;
    }
    return s;
  };
  std::vector<LD> ts = {0, 1};
  for (int k = 0; k < 3; ++k)
    if (d[k] != 0)
      for (LD face : {LD(lo[k]), LD(hi[k])}) {
        const LD t = (face - o[k]) / d[k];
        if (t > 0 && t < 1) ts.push_back(t);
      }
  std::sort(ts.begin(), ts.end());
  LD best = std::min(dist2(0), dist2(1));
  for (size_t i = 0; i + 1 < ts.size(); ++i) {
    const LD t0 = ts[i], t1 = ts[i + 1], mid = (t0 + t1) / 2;
    LD num = 0, den = 0;
    for (int k = 0; k < 3; ++k) {
      const LD x = o[k] + mid * d[k];
      if (x < lo[k] || x > hi[k]) {
        const LD face = x < lo[k] ? lo[k] : hi[k];
        num -= (o[k] - face) * d[k];
        den += d[k] * d[k];
      }
    }
    const LD t = den > 0 ? std::min(std::max(num / den, t0), t1) : t0;
    best = std::min({best, dist2(t), dist2(t0), dist2(t1)});
  }
  return std::sqrt(best);
}

// ---- The checks ---------------------------------------------------------------------------------

inline void check_chain(Report& report, const MeshSets& m, const std::string& tag) {
  // VT: true <= leaf_exact <= sphere <= box; capsule modes on points are box and sphere.
  expect_subset(report, m.vt[MINKQ_MODE_SPHERE][1], m.vt[MINKQ_MODE_SPHERE][0], tag + " VT leaf_exact <= sphere");
  expect_subset(report, m.vt[MINKQ_MODE_SPHERE][0], m.vt[MINKQ_MODE_BOX][0], tag + " VT sphere <= box");
  expect_subset(report, m.vt[MINKQ_MODE_BOX][1], m.vt[MINKQ_MODE_BOX][0], tag + " VT box+leaf <= box");
  expect_subset(report, m.vt[MINKQ_MODE_SPHERE][1], m.vt[MINKQ_MODE_BOX][1], tag + " VT sphere+leaf <= box+leaf");
  for (int leaf = 0; leaf < 2; ++leaf) {
    expect_equal(report, m.vt[MINKQ_MODE_CAPSULE_RAY][leaf], m.vt[MINKQ_MODE_BOX][leaf], tag + " VT capsule_ray == box");
    expect_equal(report, m.vt[MINKQ_MODE_CAPSULE_EXACT][leaf], m.vt[MINKQ_MODE_SPHERE][leaf],
                 tag + " VT capsule_exact == sphere");
  }
  // EE: true <= leaf_exact <= capsule_exact <= capsule_ray <= box.
  expect_subset(report, m.ee[MINKQ_MODE_CAPSULE_EXACT][1], m.ee[MINKQ_MODE_CAPSULE_EXACT][0],
                tag + " EE leaf_exact <= capsule_exact");
  expect_subset(report, m.ee[MINKQ_MODE_CAPSULE_EXACT][0], m.ee[MINKQ_MODE_CAPSULE_RAY][0],
                tag + " EE capsule_exact <= capsule_ray");
  expect_subset(report, m.ee[MINKQ_MODE_CAPSULE_RAY][0], m.ee[MINKQ_MODE_BOX][0], tag + " EE capsule_ray <= box");
  expect_subset(report, m.ee[MINKQ_MODE_CAPSULE_EXACT][1], m.ee[MINKQ_MODE_CAPSULE_RAY][1],
                tag + " EE exact+leaf <= ray+leaf");
  expect_subset(report, m.ee[MINKQ_MODE_CAPSULE_RAY][1], m.ee[MINKQ_MODE_BOX][1], tag + " EE ray+leaf <= box+leaf");
  for (int mode : {0, 2, 3})
    expect_subset(report, m.ee[mode][1], m.ee[mode][0], tag + " EE " + mode_name(mode) + "+leaf <= " + mode_name(mode));
}

inline void compare_sets(Report& report, const MeshSets& got, const MeshSets& want, const std::string& tag,
                         Stats* stats) {
  for (int mode = 0; mode < 4; ++mode)
    for (int leaf = 0; leaf < 2; ++leaf) {
      const std::string suffix = std::string(mode_name(mode)) + (leaf ? "+leaf_exact" : "");
      expect_equal(report, got.vt[mode][leaf], want.vt[mode][leaf], tag + " VT " + suffix);
      if (ee_mode(mode)) expect_equal(report, got.ee[mode][leaf], want.ee[mode][leaf], tag + " EE " + suffix);
      if (stats) stats->pairs += got.vt[mode][leaf].size() + got.ee[mode][leaf].size();
    }
}

// Every check of one set of positions of a mesh scene whose minkq handle is `scene`.
inline MeshSets check_mesh_positions(minkq_scene* scene, const MeshScene& s, const std::vector<float>& xyz,
                                     const std::vector<int32_t>& edges, IndependentSets* independent, bool moved,
                                     Report& report, Stats& stats, const std::string& tag, minkq_result* result) {
  const MeshGeometry g(xyz, s.tris, edges);
  const uint32_t filters = s.drop_incident ? kDropIncident : 0u;
  MeshSets got = minkq_mesh_sets(scene, g, s.r, s.variant, report, stats, tag, result);
  if (inject_fault() && !got.vt[MINKQ_MODE_SPHERE][1].empty()) got.vt[MINKQ_MODE_SPHERE][1].pop_back();

  // Traversal finds exactly the definition, computed by brute force...
  compare_sets(report, got, definition_sets(g, s.r, filters), tag + " minkq vs definition", &stats);
  // ...and by the independent traversal.
  if (independent && independent->accepts(xyz, s.r)) {
    compare_sets(report, got, independent->mesh_sets(g, s.r, filters, moved), tag + " minkq vs Embree", nullptr);
    stats.independent += 14;
  }
  check_chain(report, got, tag);

  // Zero false negatives against the long-double oracle; leaf-exact extras within the bound.
  reference::Mesh mesh;
  mesh.xyz = xyz;
  mesh.tris = s.tris;
  mesh.edges = edges;
  // The oracle's grid-accelerated sets (its prefilter is conservative: padded double boxes),
  // checked against its all-pairs sets on one scene in eight and on every small scene.
  const Pairs vt_true = reference::vt_contacts(mesh, s.r, s.drop_incident);
  const Pairs ee_true = reference::ee_contacts(mesh, s.r, s.drop_incident);
  if ((s.variant >> 29) == 0 || g.ne() <= 24) {
    expect_equal(report, vt_true, reference::vt_contacts_brute(mesh, s.r, s.drop_incident), tag + " VT oracle grid vs brute");
    expect_equal(report, ee_true, reference::ee_contacts_brute(mesh, s.r, s.drop_incident), tag + " EE oracle grid vs brute");
  }
  stats.true_contacts += vt_true.size() + ee_true.size();
  for (int mode = 0; mode < 4; ++mode)
    for (int leaf = 0; leaf < 2; ++leaf) {
      const std::string suffix = std::string(mode_name(mode)) + (leaf ? "+leaf_exact" : "");
      expect_subset(report, vt_true, got.vt[mode][leaf], tag + " VT false negatives in " + suffix);
      if (ee_mode(mode)) expect_subset(report, ee_true, got.ee[mode][leaf], tag + " EE false negatives in " + suffix);
    }
  check_vt_extras(report, minus(got.vt[MINKQ_MODE_SPHERE][1], vt_true), xyz, s.tris, s.r, tag + " VT");
  check_vt_extras(report, minus(got.vt[MINKQ_MODE_BOX][1], vt_true), xyz, s.tris, s.r, tag + " VT box");
  check_ee_extras(report, minus(got.ee[MINKQ_MODE_CAPSULE_EXACT][1], ee_true), xyz, edges, s.r, tag + " EE");
  check_ee_extras(report, minus(got.ee[MINKQ_MODE_BOX][1], ee_true), xyz, edges, s.r, tag + " EE box");
  return got;
}

// The whole mesh-scene check on devices[0] (the CPU), then the same sets on every further device.
inline void check_mesh_scene(const std::vector<cxx::Device>& devices, const MeshScene& s,
                             IndependentSets* independent, Report& report, Stats& stats) {
  const uint32_t flags = MINKQ_SCENE_VT | MINKQ_SCENE_EE | (s.drop_incident ? uint32_t(MINKQ_SCENE_DROP_INCIDENT) : 0u);
  // A scene of the given positions on a device; empty (and reported) where creation fails.
  auto create = [&](const cxx::Device& device, const std::vector<float>& xyz) {
    minkq_scene_desc desc{};
    desc.flags = flags;
    desc.vertices = {xyz.empty() ? nullptr : xyz.data(), 0, xyz.size() / 3, MINKQ_MEMORY_HOST};
    desc.triangles = {s.tris.empty() ? nullptr : s.tris.data(), 0, s.tris.size() / 3, MINKQ_MEMORY_HOST};
    desc.edges = {s.edges.empty() ? nullptr : s.edges.data(), 0, s.edges.size() / 2, MINKQ_MEMORY_HOST};
    minkq_scene* out = nullptr;
    const minkq_status status = minkq_scene_create(device.get(), &desc, &out);
    if (status != MINKQ_SUCCESS)
      report.fail(std::string("minkq_scene_create on ") + minkq_device_name(device.get()) + ": " + status_text(status));
    return cxx::Scene(out);
  };
  const cxx::Scene scene = create(devices[0], s.xyz);
  if (!scene) return;
  minkq_result* raw_result = nullptr;
  if (minkq_result_create(&raw_result) != MINKQ_SUCCESS) report.fail("minkq_result_create");
  const cxx::Result result(raw_result);

  // The edge numbering: given edges as they are, else every distinct triangle edge, sorted.
  std::vector<int32_t> edges(2 * minkq_scene_edge_count(scene.get()));
  if (minkq_scene_edges(scene.get(), edges.data(), edges.size() / 2) != MINKQ_SUCCESS) report.fail("minkq_scene_edges");
  if (edges != (s.edges.empty() ? reference::derive_edges(s.tris) : s.edges))
    report.fail("minkq_scene_edges: not the documented edge list");

  const MeshSets before =
      check_mesh_positions(scene.get(), s, s.xyz, edges, independent, false, report, stats, "", result.get());
  MeshSets after;
  const bool refit = !s.moved.empty();
  if (refit) {
    const minkq_status status =
        minkq_scene_refit(scene.get(), {s.moved.data(), 0, s.moved.size() / 3, MINKQ_MEMORY_HOST});
    if (status != MINKQ_SUCCESS) {
      report.fail("minkq_scene_refit: " + status_text(status));
    } else {
      after = check_mesh_positions(scene.get(), s, s.moved, edges, independent, true, report, stats, "[refit]",
                                   result.get());
      double growth = -1.0;
      if (minkq_scene_tree_growth(scene.get(), &growth) != MINKQ_SUCCESS || !(growth >= 0.0))
        report.fail("minkq_scene_tree_growth after a refit: " + std::to_string(growth));
      // A refitted tree keeps its old topology but must give the sets of a fresh build, and so
      // must a scene built at the old positions and rebuilt at the new (all are compared with
      // the definition above, so this runs on one refit in four for each).
      const uint32_t twin = (s.variant >> 27) % 4;
      const cxx::Scene fresh = twin < 2 ? create(devices[0], twin == 0 ? s.moved : s.xyz) : cxx::Scene();
      if (fresh) {
        const char* label = twin == 0 ? "[refit] vs fresh build" : "[refit] vs rebuild";
        if (twin == 1) {
          const minkq_status rebuilt =
              minkq_scene_rebuild(fresh.get(), {s.moved.data(), 0, s.moved.size() / 3, MINKQ_MEMORY_HOST});
          if (rebuilt != MINKQ_SUCCESS) report.fail("minkq_scene_rebuild: " + status_text(rebuilt));
          if (minkq_scene_tree_growth(fresh.get(), &growth) != MINKQ_SUCCESS || growth != 1.0)
            report.fail("minkq_scene_tree_growth after a rebuild: " + std::to_string(growth) + ", not 1");
        }
        Stats scratch;
        const MeshGeometry g(s.moved, s.tris, edges);
        compare_sets(report, after, minkq_mesh_sets(fresh.get(), g, s.r, ~s.variant, report, scratch, label, nullptr),
                     label, nullptr);
      }
      stats.refit_scenes++;
    }
  }
  // Every further device gives exactly the CPU's sets (the backends are bit-identical).
  for (size_t d = 1; d < devices.size(); ++d) {
    const std::string name = minkq_device_name(devices[d].get());
    const cxx::Scene other = create(devices[d], s.xyz);
    if (!other) continue;
    Stats scratch;
    compare_sets(report, minkq_mesh_sets(other.get(), MeshGeometry(s.xyz, s.tris, edges), s.r, s.variant, report,
                                         scratch, name, nullptr),
                 before, name + " vs cpu", nullptr);
    if (refit &&
        minkq_scene_refit(other.get(), {s.moved.data(), 0, s.moved.size() / 3, MINKQ_MEMORY_HOST}) == MINKQ_SUCCESS)
      compare_sets(report, minkq_mesh_sets(other.get(), MeshGeometry(s.moved, s.tris, edges), s.r, s.variant, report,
                                           scratch, name + " [refit]", nullptr),
                   after, name + " [refit] vs cpu", nullptr);
  }
  stats.mesh_scenes++;
}

// User-box scenes: sets equal the definition (brute force and independent), the chain holds,
// every exact overlap is found, and sphere / capsule_exact extras stay within the node tests'
// stated bounds (predicates.h).
inline void check_box_positions(minkq_bvh* bvh, const BoxScene& s, const std::vector<float>& boxes,
                                IndependentSets* independent, bool moved, Report& report, Stats& stats,
                                const std::string& tag, BoxSets* out) {
  const BoxGeometry g(boxes, s.first, s.second);
  const BoxSets got = minkq_box_sets(bvh, s, s.variant, report, stats, tag, g.nb());
  const BoxSets want = definition_sets(g, s.shape, s.r);
  BoxSets other;
  const bool compare_independent = independent && independent->accepts(boxes, s.r) && independent->accepts(s.first, s.r) &&
                                   independent->accepts(s.second, s.r);
  if (compare_independent) {
    other = independent->box_sets(g, s.shape, s.r, moved);
    stats.independent++;
  }
  for (int mode = 0; mode < 4; ++mode) {
    if (!box_scene_mode(s.shape, mode)) continue;
    expect_equal(report, got.by_mode[mode], want.by_mode[mode], tag + " minkq vs definition " + mode_name(mode));
    if (compare_independent)
      expect_equal(report, got.by_mode[mode], other.by_mode[mode], tag + " minkq vs Embree " + mode_name(mode));
    stats.pairs += got.by_mode[mode].size();
  }
  // The chain, and the exact overlaps (long double) inside the finest set.
  const int finest = s.shape == MINKQ_SHAPE_BOX ? MINKQ_MODE_BOX
                                                : (s.shape == MINKQ_SHAPE_SPHERE ? MINKQ_MODE_SPHERE : MINKQ_MODE_CAPSULE_EXACT);
  if (s.shape == MINKQ_SHAPE_SPHERE) {
    expect_subset(report, got.by_mode[MINKQ_MODE_SPHERE], got.by_mode[MINKQ_MODE_BOX], tag + " sphere <= box");
    expect_equal(report, got.by_mode[MINKQ_MODE_CAPSULE_RAY], got.by_mode[MINKQ_MODE_BOX], tag + " capsule_ray == box");
    expect_equal(report, got.by_mode[MINKQ_MODE_CAPSULE_EXACT], got.by_mode[MINKQ_MODE_SPHERE],
                 tag + " capsule_exact == sphere");
  } else if (s.shape == MINKQ_SHAPE_CAPSULE) {
    expect_subset(report, got.by_mode[MINKQ_MODE_CAPSULE_EXACT], got.by_mode[MINKQ_MODE_CAPSULE_RAY],
                  tag + " capsule_exact <= capsule_ray");
    expect_subset(report, got.by_mode[MINKQ_MODE_CAPSULE_RAY], got.by_mode[MINKQ_MODE_BOX], tag + " capsule_ray <= box");
  }
  Pairs exact;
  const LD r = s.r;
  for (int32_t q = 0; q < g.nq(); ++q)
    for (int32_t b = 0; b < g.nb(); ++b) {
      const float* a = &s.first[3 * size_t(q)];
      const Box& box = g.boxes[b];
      bool hit;
      if (s.shape == MINKQ_SHAPE_SPHERE) {
        hit = point_box_distance_ld(a, box) <= r;
      } else if (s.shape == MINKQ_SHAPE_CAPSULE) {
        hit = segment_box_distance_ld(a, &s.second[3 * size_t(q)], box) <= r;
      } else {  // the box spanned by first and second, grown by r, against the box
        const float* c = &s.second[3 * size_t(q)];
        const float blo[3] = {box.lo.x, box.lo.y, box.lo.z}, bhi[3] = {box.hi.x, box.hi.y, box.hi.z};
        hit = true;
        for (int k = 0; k < 3; ++k)
          hit = hit && LD(std::min(a[k], c[k])) - r <= bhi[k] && blo[k] <= LD(std::max(a[k], c[k])) + r;
      }
      if (hit) exact.push_back({q, b});
    }
  stats.true_contacts += exact.size();
  expect_subset(report, exact, got.by_mode[finest], tag + std::string(" false negatives in ") + mode_name(finest));
  // Node tests accept nothing beyond their stated bounds: sphere r * (1 + 2^-17) (plus
  // underflow, < 1e-21 absolute); capsule_exact r + 2^-16 * (r + |d|_1) (2^-17 threshold plus
  // the 2^-18 distance error, each doubled for safety) plus the same underflow allowance.
  // These are rounding bounds: they hold where the tests' float squares are finite. Beyond
  // that (|x| or r >= 2^62) an overflowing square or difference makes a test accept ("unknown
  // means may overlap", predicates.h), which the containment checks above still cover.
  LD magnitude = std::fabs(LD(s.r));
  for (const std::vector<float>* list : {&boxes, &s.first, &s.second})
    for (float x : *list) magnitude = std::max(magnitude, std::fabs(LD(x)));
  if (s.shape != MINKQ_SHAPE_BOX && magnitude < std::ldexp(LD(1), 62))
    for (const auto& [q, b] : got.by_mode[finest]) {
      const float* a = &s.first[3 * size_t(q)];
      LD d, bound;
      if (s.shape == MINKQ_SHAPE_SPHERE) {
        d = point_box_distance_ld(a, g.boxes[b]);
        bound = r * (1 + std::ldexp(LD(1), -17)) + 1e-21L;
      } else {
        const float* c = &s.second[3 * size_t(q)];
        d = segment_box_distance_ld(a, c, g.boxes[b]);
        const LD length1 = std::fabs(LD(c[0]) - a[0]) + std::fabs(LD(c[1]) - a[1]) + std::fabs(LD(c[2]) - a[2]);
        bound = r + std::ldexp(LD(1), -16) * (r + length1) + 1e-21L;
      }
      if (!(d <= bound)) {
        char text[200];
        std::snprintf(text, sizeof text, " %s accepts (%d,%d) at distance %.9Lg beyond its bound %.9Lg", mode_name(finest),
                      q, b, d, bound);
        report.fail(tag + text);
        break;
      }
    }
  if (out) *out = got;
}

inline void check_box_scene(const std::vector<cxx::Device>& devices, const BoxScene& s, IndependentSets* independent,
                            Report& report, Stats& stats) {
  // A BVH of the scene's boxes on a device; empty (and reported) where creation fails.
  auto create = [&](const cxx::Device& device) {
    minkq_bvh* out = nullptr;
    const minkq_status status =
        minkq_bvh_create(device.get(), {s.boxes.data(), 0, s.boxes.size() / 6, MINKQ_MEMORY_HOST}, &out);
    if (status != MINKQ_SUCCESS) report.fail("minkq_bvh_create: " + status_text(status));
    return cxx::Bvh(out);
  };
  const cxx::Bvh bvh = create(devices[0]);
  if (!bvh) return;
  BoxSets before, after;
  check_box_positions(bvh.get(), s, s.boxes, independent, false, report, stats, "", &before);
  const bool refit = !s.moved.empty();
  if (refit) {
    // Every check of the moved boxes, after a refit or (one scene in four) a rebuild.
    const bool rebuild = (s.variant >> 29) % 4 == 0;
    const minkq_buffer moved{s.moved.data(), 0, s.moved.size() / 6, MINKQ_MEMORY_HOST};
    const minkq_status status = rebuild ? minkq_bvh_rebuild(bvh.get(), moved) : minkq_bvh_refit(bvh.get(), moved);
    double growth = -1.0;
    if (status != MINKQ_SUCCESS) {
      report.fail(std::string(rebuild ? "minkq_bvh_rebuild: " : "minkq_bvh_refit: ") + status_text(status));
    } else {
      check_box_positions(bvh.get(), s, s.moved, independent, true, report, stats, rebuild ? "[rebuild]" : "[refit]",
                          &after);
      if (minkq_bvh_tree_growth(bvh.get(), &growth) != MINKQ_SUCCESS || !(rebuild ? growth == 1.0 : growth >= 0.0))
        report.fail("minkq_bvh_tree_growth: " + std::to_string(growth));
    }
  }
  for (size_t d = 1; d < devices.size(); ++d) {
    const std::string name = minkq_device_name(devices[d].get());
    const cxx::Bvh other = create(devices[d]);
    if (!other) continue;
    Stats scratch;
    const BoxSets sets = minkq_box_sets(other.get(), s, s.variant, report, scratch, name, int32_t(s.boxes.size() / 6));
    for (int mode = 0; mode < 4; ++mode)
      expect_equal(report, sets.by_mode[mode], before.by_mode[mode], name + " vs cpu " + mode_name(mode));
    if (refit &&
        minkq_bvh_refit(other.get(), {s.moved.data(), 0, s.moved.size() / 6, MINKQ_MEMORY_HOST}) == MINKQ_SUCCESS) {
      const BoxSets moved = minkq_box_sets(other.get(), s, s.variant, report, scratch, name, int32_t(s.boxes.size() / 6));
      for (int mode = 0; mode < 4; ++mode)
        expect_equal(report, moved.by_mode[mode], after.by_mode[mode], name + " [refit] vs cpu " + mode_name(mode));
    }
  }
  stats.box_scenes++;
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
