// minkq_build_study: where a tree build's time goes, and the library's build (cpu/tree.h's
// CpuTree::build) beside the one it replaced (bench/studies/karras_build.h), in the same run,
// on the same threads. Per scene and tree (triangles, edges): both builds are first checked to
// give the same tree record for record (nodes, leaf order, leaf boxes, area cost); then each
// build, rebuilds of a tree that keeps its scratch, and each phase of the library's build are
// timed. Writes build.md.
//
// usage: minkq_build_study [--threads N] [--repeats N] [--quick] [--large] [--data DIR] [--out DIR]
//   --large adds the 1M-triangle twisted sheet; --quick: small scenes, 3 repeats, no file check.
#include <sys/resource.h>
#include <tbb/global_control.h>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "common.h"
#include "cpu/tree.h"
#include "scenes.h"
#include "study_options.h"
#include "studies/karras_build.h"
#include "studies/one_pass_build.h"

using namespace minkq;
using namespace minkq::bench;

namespace {

struct Row {
  std::string scene, tree;
  int32_t n = 0;
  size_t nodes = 0;
  double cost = 0;
  Timing retired, library, kept, boxes, sort, hierarchy, karras, refit, area, one_pass;
  bool one_pass_same = false, karras_same = false;
  double retired_faults = 0, library_faults = 0, kept_faults = 0;  // minor page faults per whole build
};

// Minor page faults of this process so far (first touches of fresh memory).
long minor_faults() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_minflt;
}

// Two arrays of the same records (std::vector or the library's HostVector), byte for byte.
template <class A, class B>
bool same_bytes(const A& a, const B& b) {
  static_assert(sizeof(a[0]) == sizeof(b[0]), "arrays of the same records");
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(a[0])) == 0);
}

// One tree of one scene; false when the two builds differ (the row then holds no times).
template <class Boxes>
bool study(const std::string& scene, const char* tree_name, Boxes boxes, int32_t n, int warmup, int repeats,
           std::vector<Row>& rows) {
  Row row;
  row.scene = scene;
  row.tree = tree_name;
  row.n = n;
  {
    RetiredTree old;
    build_retired(old, boxes, n);
    CpuTree now;
    now.build(boxes, n);
    std::vector<BoxGroup> groups(now.leaf_groups(), now.leaf_groups() + old.leaf_groups.size());
    if (!same_bytes(old.nodes, now.nodes()) || !same_bytes(old.sorted_prims, now.sorted_prims()) ||
        !same_bytes(old.leaf_groups, groups) || old.cost_at_build != now.cost_at_build()) {
      std::fprintf(stderr, "FAIL %s %s: the builds differ (nodes %d, leaf order %d, leaf boxes %d, area cost %d)\n",
                   scene.c_str(), tree_name, int(!same_bytes(old.nodes, now.nodes())),
                   int(!same_bytes(old.sorted_prims, now.sorted_prims())), int(!same_bytes(old.leaf_groups, groups)),
                   int(old.cost_at_build != now.cost_at_build()));
      for (size_t i = 0; i < std::min(old.nodes.size(), now.nodes().size()); ++i)
        if (std::memcmp(&old.nodes[i], &now.nodes()[i], sizeof(BvhNode)) != 0) {
          const BvhNode &a = old.nodes[i], &b = now.nodes()[i];
          std::fprintf(stderr, "  first differing node %zu: left %d/%d right %d/%d parent %d/%d split %d/%d box lo.x %a/%a\n", i,
                       a.left, b.left, a.right, b.right, a.parent, b.parent, a.split, b.split, double(a.left_box.lo.x),
                       double(b.left_box.lo.x));
          break;
        }
      return false;
    }
    row.nodes = now.nodes().size();
    row.cost = now.cost_at_build();
  }
  // Whole builds into fresh trees, round by round so that a slow spell of the shared machine
  // falls on both.
  // And rebuilds of one tree that keeps its scratch (CpuTree::reserve_build, what a scene
  // reserved with MINKQ_RESERVE_REBUILD does), checked equal to a fresh build first.
  std::vector<double> t_old, t_new, t_kept;
  long faults_old = 0, faults_new = 0, faults_kept = 0;
  CpuTree kept;
  kept.reserve_build(n);
  kept.build(boxes, n);
  {
    CpuTree now;
    now.build(boxes, n);
    kept.build(boxes, n);
    if (!same_bytes(kept.nodes(), now.nodes()) || kept.sorted_prims() != now.sorted_prims()) {
      std::fprintf(stderr, "FAIL %s %s: a rebuild with kept scratch differs from a fresh build\n", scene.c_str(),
                   tree_name);
      return false;
    }
  }
  for (int k = 0; k < warmup + repeats; ++k) {
    RetiredTree old;
    long f = minor_faults();
    double start = now_ms();
    build_retired(old, boxes, n);
    const double a = now_ms() - start;
    const long fa = minor_faults() - f;
    CpuTree now;
    f = minor_faults();
    start = now_ms();
    now.build(boxes, n);
    const double b = now_ms() - start;
    const long fb = minor_faults() - f;
    f = minor_faults();
    start = now_ms();
    kept.build(boxes, n);
    const double c = now_ms() - start;
    const long fc = minor_faults() - f;
    if (k >= warmup) {
      t_old.push_back(a), t_new.push_back(b), t_kept.push_back(c);
      faults_old += fa, faults_new += fb, faults_kept += fc;
    }
  }
  row.retired_faults = double(faults_old) / repeats;
  row.library_faults = double(faults_new) / repeats;
  row.kept_faults = double(faults_kept) / repeats;
  row.retired = summarize(t_old);
  row.library = summarize(t_new);
  row.kept = summarize(t_kept);
  // The library's phases, each alone (its inputs made untimed).
  HostVector<Box> element;
  HostVector<uint64_t> keys;
  HostVector<int32_t> order;
  Box centres{};
  row.boxes = measure(warmup, repeats, [&] { centres = element_boxes(boxes, n, element); });
  row.sort = measure(warmup, repeats, [&] { sort_by_morton(element, centres, keys, order); });
  HostVector<BvhNode> nodes;
  std::vector<BoxGroup> groups(size_t(box_group_count(n)));
  row.hierarchy = measure(warmup, repeats, [&] {
    build_nodes(keys.data(), n, kLeafSize, GivenBoxes{element.data()}, order.data(), nodes, groups.data());
  });
  CpuTree tree;
  tree.build(boxes, n);
  row.refit = measure(warmup, repeats, [&] { tree.refit(GivenBoxes{element.data()}); });
  row.area = measure(warmup, repeats, [&] {
    volatile double c = tree.area_cost();
    (void)c;
  });
  auto same_as_library = [&](const auto& built) {
    return same_bytes(built, tree.nodes()) &&
           std::memcmp(groups.data(), tree.leaf_groups(), groups.size() * sizeof(BoxGroup)) == 0;
  };
  // The hierarchy as the library built it before (and the CUDA build still does): every Karras
  // node, the scan, the records, then the refit.
  HostVector<BvhNode> karras;
  test::build_nodes_karras(keys.data(), n, element.data(), order.data(), kLeafSize, karras, groups.data());
  row.karras_same = same_as_library(karras);
  row.karras = measure(warmup, repeats, [&] {
    test::build_nodes_karras(keys.data(), n, element.data(), order.data(), kLeafSize, karras, groups.data());
  });
  // The one-pass study: hierarchy and boxes together, bottom-up.
  std::vector<BvhNode> one_pass;
  build_nodes_one_pass(keys.data(), n, element.data(), order.data(), kLeafSize, one_pass, groups.data());
  row.one_pass_same = same_as_library(one_pass);
  row.one_pass = measure(warmup, repeats, [&] {
    build_nodes_one_pass(keys.data(), n, element.data(), order.data(), kLeafSize, one_pass, groups.data());
  });
  rows.push_back(row);
  if (!row.karras_same)
    std::fprintf(stderr, "FAIL %s %s: Karras + refit differs from the library's nodes + boxes\n", scene.c_str(),
                 tree_name);
  return row.karras_same;
}

bool study_scene(const SceneFrames& sc, int warmup, int repeats, std::vector<Row>& rows) {
  const auto* v = reinterpret_cast<const Vec3*>(sc.frames[0].data());
  const auto* t = reinterpret_cast<const Triangle*>(sc.mesh.tris.data());
  const auto* e = reinterpret_cast<const Edge*>(sc.mesh.edges.data());
  std::fprintf(stderr, "%s: %d triangles\n", sc.name.c_str(), int(sc.mesh.triangle_count()));
  const bool a = study(sc.name, "triangles", TriangleBoxes{v, t}, int32_t(sc.mesh.triangle_count()), warmup, repeats, rows);
  const bool b = study(sc.name, "edges", EdgeBoxes{v, e}, int32_t(sc.mesh.edges.size() / 2), warmup, repeats, rows);
  return a && b;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    StudyOptions opt{MINKQ_BENCH_DATA_DIR, MINKQ_BENCH_RESULTS_DIR};
    if (!parse_study_options(argc, argv, "minkq_build_study", opt)) return 2;
    const std::string& out = opt.out;
    const int threads = opt.threads, repeats = opt.repeats;
    tbb::global_control control(tbb::global_control::max_allowed_parallelism, size_t(std::max(1, threads)));
    const int warmup = 2;
    const double load_start = load_average();
    std::vector<Row> rows;
    const bool ok = for_each_study_scene(opt, false, [&](const SceneFrames& sc) {
      return study_scene(sc, warmup, repeats, rows);
    });
    std::ostringstream o;
    o << "# Tree builds: the library's beside the one it replaced (issue 27)\n\n"
      << written_by(opt, "minkq_build_study", load_start)
      << "**retired** = the build before issue 27 (bench/studies/karras_build.h: the box functor evaluated in three "
      << "passes, a comparison sort of (key, id) pairs, a serial scan of the kept nodes); **library** = "
      << "`CpuTree::build` (each box evaluated once, a parallel radix sort, the kept nodes and their boxes top-down: "
      << "cpu/tree.h's TopDownBuild). Both give the same "
      << "tree, record for record (checked first: nodes, leaf order, leaf boxes, area cost). Whole builds run into "
      << "fresh trees, alternately, " << warmup << " untimed and " << repeats
      << " timed rounds; ms = median (range); speed-up = retired / library. The phase columns time each step of "
      << "the library's build alone (medians): element boxes and their centre bounds, Morton codes and the sort, "
      << "**nodes + boxes** (the kept node records with their boxes and the leaf groups, top-down), "
      << "then a refit of the built tree from the element boxes (what a refit costs; no longer part of a build) "
      << "and the area cost. Beside the nodes + boxes column, two other ways to the same records: **Karras + "
      << "refit** (bench/studies/karras_build.h: every Karras node, a parallel scan of the kept ones, the records, "
      << "then the refit: the library's build before the top-down one, and the CUDA build's steps) and "
      << "**one-pass** (bench/studies/one_pass_build.h, not kept: hierarchy and boxes together, bottom-up, "
      << "Apetrei 2014, as ArborX builds); **same**: Karras + refit / one-pass nodes and leaf boxes equal the "
      << "library's, byte for byte. **kept** = rebuilds of one tree that keeps its build scratch "
      << "(`CpuTree::reserve_build`, as a scene reserved with MINKQ_RESERVE_REBUILD does; checked equal to a fresh "
      << "build), in the same rounds; kept speed-up = retired / kept. **faults**: minor page faults per whole build "
      << "(getrusage), the first touches of memory the allocator had to map afresh.\n\n"
      << "| scene | tree | elements | nodes | area cost | retired ms | library ms | speed-up | kept ms | kept speed-up | "
         "faults retired / library / kept | boxes | sort | nodes + boxes | Karras + refit | one-pass | same | refit | "
         "area |\n"
         "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const Row& r : rows)
      o << "| " << r.scene << " | " << r.tree << " | " << r.n << " | " << r.nodes << " | " << fmt(r.cost, 5) << " | "
        << r.retired.text() << " | " << r.library.text() << " | " << fmt(r.retired.median / r.library.median, 3)
        << "x | " << r.kept.text() << " | " << fmt(r.retired.median / r.kept.median, 3) << "x | "
        << fmt(r.retired_faults, 4) << " / " << fmt(r.library_faults, 4) << " / " << fmt(r.kept_faults, 4) << " | "
        << fmt(r.boxes.median)
        << " | " << fmt(r.sort.median) << " | " << fmt(r.hierarchy.median) << " | " << fmt(r.karras.median) << " | "
        << fmt(r.one_pass.median) << " | " << (r.karras_same ? "yes" : "NO") << " / "
        << (r.one_pass_same ? "yes" : "NO") << " | " << fmt(r.refit.median) << " | " << fmt(r.area.median) << " |\n";
    const std::string file = out + "/build.md";
    std::ofstream(file) << o.str();
    std::fprintf(stderr, "%swrote %s\n", o.str().c_str(), file.c_str());
    if (!ok) {
      std::fprintf(stderr, "FAIL: a build differs from the retired one\n");
      return 1;
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "minkq_build_study: %s\n", e.what());
    return 1;
  }
}
