// minkq_stability's runs: each case's oracle contacts (long double), then every mode of kModes
// on every backend through the C API, each candidate set compared with the oracle (false
// negatives), measured against the mode's bound (bounds.cpp) and, for scaled cases, with the
// unscaled case's set; one Row per case, backend and mode for main.cpp's tables.
#include <cstdio>

#include "minkq/queries.h"
#include "stability/stability.h"

namespace minkq::bench::stability {
namespace {

struct ModeSpec {
  minkq_query_kind kind;
  const char* name;
  minkq_mode mode;
  uint32_t flags;
  Metric metric;
};
const ModeSpec kModes[] = {
    {MINKQ_QUERY_VT, "box", MINKQ_MODE_BOX, 0, Metric::kBox},
    {MINKQ_QUERY_VT, "sphere", MINKQ_MODE_SPHERE, 0, Metric::kSphere},
    {MINKQ_QUERY_VT, "leaf_exact", MINKQ_MODE_SPHERE, MINKQ_QUERY_LEAF_EXACT, Metric::kLeaf},
    {MINKQ_QUERY_EE, "box", MINKQ_MODE_BOX, 0, Metric::kBox},
    {MINKQ_QUERY_EE, "capsule_ray", MINKQ_MODE_CAPSULE_RAY, 0, Metric::kRay},
    {MINKQ_QUERY_EE, "capsule_exact", MINKQ_MODE_CAPSULE_EXACT, 0, Metric::kCapsuleExact},
    {MINKQ_QUERY_EE, "leaf_exact", MINKQ_MODE_CAPSULE_EXACT, MINKQ_QUERY_LEAF_EXACT, Metric::kLeaf},
};

}  // namespace

void Runner::run(const Case& c) {
  std::fprintf(stderr, "[%s] %s: %zu V, %zu T, %zu E, r = %.9g, load %.2f\n", c.group.c_str(), c.name.c_str(), c.mesh.vertex_count(),
               c.mesh.triangle_count(), c.mesh.edge_count(), double(c.r), load_average());
  const PairSet vt_truth = to_set(ref::vt_contacts(c.mesh, c.r, true));
  const PairSet ee_truth = to_set(ref::ee_contacts(c.mesh, c.r, true));
  truths[c.name] = {vt_truth, ee_truth};
  for (const std::string& backend : backends) {
    Device dev = open_device(backend);
    minkq_scene_desc desc{};
    desc.flags = MINKQ_SCENE_VT | MINKQ_SCENE_EE | MINKQ_SCENE_DROP_INCIDENT;
    desc.vertices = {c.mesh.xyz.data(), 12, c.mesh.vertex_count(), MINKQ_MEMORY_HOST};
    desc.triangles = {c.mesh.tris.data(), 12, c.mesh.triangle_count(), MINKQ_MEMORY_HOST};
    desc.edges = {c.mesh.edges.data(), 8, c.mesh.edge_count(), MINKQ_MEMORY_HOST};
    minkq_scene* raw = nullptr;
    check(minkq_scene_create(dev.get(), &desc, &raw), "minkq_scene_create");
    Scene scene(raw);
    Result result = new_result();
    PairSet vt_box, ee_box;
    std::vector<Row> case_rows;
    for (const ModeSpec& m : kModes) {
      const minkq_query_desc q{m.kind, m.mode, m.flags, c.r};
      check(minkq_scene_query_result(scene.get(), &q, result.get()), "minkq_scene_query_result");
      const PairSet got = to_set(minkq_result_pairs(result.get()), minkq_result_count(result.get()));
      const bool vt = m.kind == MINKQ_QUERY_VT;
      if (m.mode == MINKQ_MODE_BOX) (vt ? vt_box : ee_box) = got;
      Row row;
      row.group = c.group, row.name = c.name, row.backend = backend, row.kind = vt ? "VT" : "EE", row.mode = m.name, row.r = c.r;
      const PairSet& truth = vt ? vt_truth : ee_truth;
      row.candidates = got.size(), row.truth = truth.size(), row.fn = missing(truth, got);
      for (uint64_t pr : got) {
        const minkq::Pair pair = minkq::unpack_pair(pr);
        measure_excess(c.mesh, vt, pair.first, pair.second, LD(c.r), m.metric, row.ex);
      }
      false_negatives += row.fn;
      over_bound += row.ex.over;
      const std::string key = backend + "/" + row.kind + "/" + m.name;
      if (!c.compare_to.empty()) {
        const PairSet& other = sets[c.compare_to][key];
        const uint64_t diff = missing(other, got) + missing(got, other);
        row.same_as = diff == 0 ? "yes" : "no (" + std::to_string(diff) + " differ)";
      }
      sets[c.name][key] = got;
      case_rows.push_back(row);
    }
    const std::string nf = non_finite(c.mesh, c.r, vt_box, ee_box).text();
    for (Row& r : case_rows) {
      r.non_finite = nf;
      if (r.ex.over) {
        over_cases.push_back(c.name + " " + r.kind + " " + r.mode + (nf == "0" ? " (no non-finite intermediate: a bug)" : " (after overflow to Inf)"));
        if (nf == "0") over_bound_unexplained += r.ex.over;
      }
    }
    rows.insert(rows.end(), case_rows.begin(), case_rows.end());
  }
}

}  // namespace minkq::bench::stability
