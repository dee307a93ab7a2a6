// minkq_ablation's tree study (trees.md, issue 8): Morton frames and the SAH build, refit from
// the first frame or rebuilt at the last.
#include <cstdio>
#include <vector>

#include "studies/trees.h"

#include "ablation/ablation.h"

namespace minkq::bench::ablation {

// Tree quality on the scenes' frame sequences (first and last frame): the library's Morton
// build refit from the first frame (what a simulator's refit-only steps run), the same
// rebuilt at the last frame (minkq_scene_rebuild), and the SAH build either way. Box mode,
// the scene's radius; growth = area cost over its value at build (minkq_scene_tree_growth),
// of the triangle tree for VT and of the edge tree for EE.
std::string compare_tree_builds(const SceneFrames& sc, int repeats, bool& ok) {
  const FirstAndLast frames(sc, "trees");
  const Vec3 *v0 = frames.v0, *v = frames.v;
  const Triangle* t = frames.t;
  const Edge* e = frames.e;
  const float r = frames.r;
  const int32_t nv = frames.nv, nt = frames.nt, ne = frames.ne;
  const VertexTriangleQueries vt{v, t, frames.order.data(), r, kDropIncident};
  enum Build { kPerAxis, kCubes, kSah };
  struct Variant {
    Build build;
    bool refit;
    CpuTree trees[2];  // triangles, edges (Morton builds)
    SahTree sah[2];    // the same (SAH build)
    double build_ms;
    BvhView view(int kind) const { return build == kSah ? sah[kind].view() : trees[kind].view(); }
    double growth_of(int kind) const {
      return build == kSah ? sah[kind].growth() : tree_growth_of(trees[kind]);
    }
  };
  std::vector<Variant> variants;
  for (const Build build : {kPerAxis, kCubes, kSah})
    for (const bool refit : {true, false}) {
      Variant& x = variants.emplace_back();
      x.build = build;
      x.refit = refit;
      const Vec3* at = refit ? v0 : v;
      x.build_ms = now_ms();
      if (build == kSah) {
        x.sah[0] = build_sah(TriangleBoxes{at, t}, nt);
        x.sah[1] = build_sah(EdgeBoxes{at, e}, ne);
      } else if (build == kCubes) {
        x.trees[0].build(TriangleBoxes{at, t}, nt);
        x.trees[1].build(EdgeBoxes{at, e}, ne);
      } else {
        build_per_axis(x.trees[0], TriangleBoxes{at, t}, nt);
        build_per_axis(x.trees[1], EdgeBoxes{at, e}, ne);
      }
      x.build_ms = now_ms() - x.build_ms;
      if (refit && build == kSah) {
        x.sah[0].refit(TriangleBoxes{v, t});
        x.sah[1].refit(EdgeBoxes{v, e});
      } else if (refit) {
        x.trees[0].refit(TriangleBoxes{v, t});
        x.trees[1].refit(EdgeBoxes{v, e});
      }
    }
  const std::vector<std::vector<Outcome>> got = round_robin(variants.size(), 2, 3 * repeats, [&](size_t i, int kind, int reps) {
    const Variant& x = variants[i];
    const EdgeEdgeQueries ee{v, e, x.view(1).sorted_prims, r, kDropIncident};
    return kind == 0 ? run<BoxShape>(x.view(0), vt, nv, reps) : run<BoxShape>(x.view(1), ee, ne, reps);
  });
  std::string out;
  for (size_t i = 0; i < variants.size(); ++i) {
    const Variant& x = variants[i];
    for (int kind = 0; kind < 2; ++kind) {
      ok &= got[i][size_t(kind)].pairs == got[0][size_t(kind)].pairs;
      char label[200];
      const char* builds[3] = {"Morton, cells per axis", "Morton, cubic cells", "SAH"};
      const char* marks[3][2] = {{"", " (before)"}, {"", " (kept)"}, {"", ""}};  // [build][refit]
      std::snprintf(label, sizeof label, "%s, %s%s: growth %.2f, build both %.1f ms", builds[x.build],
                    x.refit ? "built at frame 0, refit" : "rebuilt at the last frame", marks[x.build][x.refit],
                    x.growth_of(kind), x.build_ms);
      out += row(sc.name, kind ? "EE" : "VT", "box", label, got[i][size_t(kind)], kind ? ne : nv, got[0][size_t(kind)]);
    }
  }
  return out;
}

}  // namespace minkq::bench::ablation
