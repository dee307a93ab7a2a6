// minkq_ablation: what each traversal habit of issue 8 buys, measured in one run on the same
// trees: the library's traversal (core/include/minkq) against the variant it replaced, with
// the work counters (the same on every backend) and CPU time (median of repeats, all
// threads). Variants:
//   VT   queries in vertex id order         vs  in vertex Morton order (kept)
//   leaf ranges of 1 (the binary tree), 2, 4, 8, 16, 32 (kept) or 64 primitives: VT sphere, EE box
//        and EE capsule_exact on each
//   EE   every edge queries the whole tree  vs  each pair met once: a query reaches only the
//        and keeps f > e (each pair met        leaves after its own (kept; queries in leaf
//        twice)                                order, or in edge id order), and a finer test
//                                              also runs the other way round at the leaf
//   node tests: the mode's test at every node  vs  the box test inside the tree and the mode's
//        test at primitive boxes only (kept); at the scene's radius, at 8 r, and on 3-D-spread
//        user boxes
//   box test: the r-padded box, rounded outward  vs  the float gap <= r (kept; symmetric, so
//        EE needs it one way only)
//   trees: Morton codes over cells stretched per axis (before)  vs  cubic cells (kept); each
//        built at the first frame and refit to the last (a simulator's refit-only steps) and
//        rebuilt at the last frame (minkq_scene_rebuild), and a binned SAH build (not kept)
//        either way; with each tree's growth (minkq_scene_tree_growth)
//   VT + EE: two minkq_scene_query calls  vs  one minkq_scene_query_vt_ee call (through the C
//        API, on the CPU or with --backend cuda)
// Both variants of a kind must return the same pairs (checked), except the two box tests
// (different roundings at the boundary: their counts are shown). Writes
// bench/results/ablation.md and (the trees) bench/results/trees.md; see bench/README.md. Each
// study lives in its own file of bench/ablation/ (ablation.h lists them); this one writes
// their tables.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

#include "ablation/ablation.h"
#include "studies/wide_bvh.h"

using namespace minkq;
using namespace minkq::bench;
using namespace minkq::bench::ablation;

int main(int argc, char** argv) {
  try {
    std::string data = MINKQ_BENCH_DATA_DIR, out = MINKQ_BENCH_RESULTS_DIR;
    int repeats = 5;
    double scale = 0;  // reference sizes
    std::string sections = "all";  // or "traversal" (ablation.md), "trees" (trees.md), "wide" (wide.md), "policies" (policies.md), "contacts" (contacts.md), "fused" (fused.md)
    std::string backend = "cpu";   // the device of the C API studies (fused)
    for (int i = 1; i < argc; ++i) {
      const std::string a = argv[i];
      if (a == "--quick") repeats = 1;
      else if (a == "--out" && i + 1 < argc) out = argv[++i];
      else if (a == "--data" && i + 1 < argc) data = argv[++i];
      else if (a == "--triangles" && i + 1 < argc) scale = std::stod(argv[++i]);
      else if (a == "--backend" && i + 1 < argc) backend = argv[++i];
      else if (a == "--only" && i + 1 < argc &&
               (std::string(argv[i + 1]) == "traversal" || std::string(argv[i + 1]) == "trees" ||
                std::string(argv[i + 1]) == "wide" || std::string(argv[i + 1]) == "policies" ||
                std::string(argv[i + 1]) == "contacts" || std::string(argv[i + 1]) == "fused"))
        sections = argv[++i];
      else {
        std::fprintf(stderr,
                     "usage: minkq_ablation [--quick] [--out DIR] [--data DIR] [--triangles N] [--backend cpu|cuda] "
                     "[--only traversal|trees|wide|policies|contacts|fused]\n");
        return 2;
      }
    }
    const std::string table_head =
        "| scene | kind | mode | variant | nodes / query | node tests / query | primitive tests / query | pairs | ms | "
        "speed |\n|---|---|---|---|---|---|---|---|---|---|\n";
    const std::string timing = "ms = median of " + std::to_string(repeats) + " runs after a warm-up; speed = 'before' ms / "
                               "this ms, measured in this run. Written by `minkq_ablation`" +
                               std::string(repeats == 1 ? " --quick" : "") + ".\n\n";
    bool ok = true;
    std::filesystem::create_directories(out);
    auto write = [&out](const std::string& name, const std::string& text) {
      std::ofstream f(out + "/" + name);
      f << text;
      if (!f) throw std::runtime_error("cannot write " + out + "/" + name);
      std::fprintf(stderr, "wrote %s/%s\n", out.c_str(), name.c_str());
    };
    if (sections == "all" || sections == "traversal") {
      std::ostringstream o;
      o << "# Traversal ablation (issue 8)\n\nMachine: " << machine_line("cpu (core traversal, TBB)")
        << ". Load average (1 min) at start " << fmt(load_average(), 3) << ". Last frame of each scene, r = the scene's "
        << "radius, incident pairs dropped, CPU backend traversal on all threads; counts per query; " << timing
        << table_head;
      for (const std::string& name : {std::string("twist_target"), std::string("cloth_twist"), std::string("cloth_hanging"),
                                      std::string("softbody_gift")})
        o << compare_scene(make_scene(name, scale, 2, data), repeats, ok);
      for (const RealMesh& m : available_real_meshes(data))
        if (m.name == "unisex_shirt" || m.name == "multilayer_drape") o << compare_scene(load_real_scene(m, data), repeats, ok);
      for (const double hr : {0.01, 1.0}) o << compare_fine_nodes_spread(200000, hr, repeats, ok);
      o << "\nLoad average at end " << fmt(load_average(), 3) << ".\n";
      write("ablation.md", o.str());
    }
    if (sections == "all" || sections == "trees") {
      std::ostringstream o;
      o << "# Tree quality: refit, rebuild, SAH (issue 8)\n\nMachine: " << machine_line("cpu (core traversal, TBB)")
        << ". Load average (1 min) at start " << fmt(load_average(), 3) << ". Every procedural scene's first and last "
        << "frame, r = the scene's radius, box mode, incident pairs dropped, CPU backend traversal on all threads; the "
        << "pairs of every variant checked equal. 'before': Morton trees over cells stretched per axis (the usual LBVH "
        << "frame, the library's until this table), built at the first frame and refit to the last, as a simulator's "
        << "refit-only steps run them; 'kept': the same over cubic cells (the library's). 'build both' is the "
        << "time to build the scene's two trees (the Morton build on all threads, the SAH study on one); growth = the "
        << "tree's area cost over its value at its build (minkq_scene_tree_growth). Counts per query; the variants "
        << "run round-robin, " << 3 * repeats << " rounds (each round one warm-up and one timed run of every query "
        << "batch); ms = the median of the timed runs; speed = 'before' ms / this ms. Written by `minkq_ablation`"
        << (repeats == 1 ? " --quick" : "") << ".\n\n"
        << table_head;
      for (const std::string& name : procedural_scene_names())
        o << compare_tree_builds(make_scene(name, scale, 2, data), repeats, ok);
      o << compare_tree_builds(make_scene("twist_target", scale, 2, data), repeats, ok);
      o << "\nLoad average at end " << fmt(load_average(), 3) << ".\n";
      write("trees.md", o.str());
    }
    if (sections == "all" || sections == "wide") {
      std::ostringstream o;
      o << "# Wide nodes: 4- and 8-ary trees collapsed from the binary one (issue 8)\n\nMachine: "
        << machine_line("cpu (core traversal, TBB)") << ". Load average (1 min) at start " << fmt(load_average(), 3)
        << ". A study (bench/studies/wide_bvh.h), not the library's tree. Every procedural scene and the twisted sheet; each "
        << "scene's binary trees built at its first frame (leaf ranges of 16, the library's, or of 4 or 1), collapsed "
        << "there to W-ary nodes (the child with the largest box area opened until W children; child boxes stored "
        << "by axis, " << sizeof(WideNode<4>) << " B per 4-wide node, " << sizeof(WideNode<8>) << " B per 8-wide), "
        << "and refit to the last frame, as a simulator's refit-only steps run them; leaf ranges, leaf order and leaf "
        << "scans unchanged. r = the scene's radius, incident pairs dropped, CPU traversal on all threads; the pairs of "
        << "every variant checked equal to the binary tree's. nodes = node records read (a wide record is two or four "
        << "64-byte lines); node tests = child and leaf boxes tested (a 4-lane test counts its non-empty lanes). "
        << "'4-float lanes': the box test (box_gap_within) on 4 children at once with GCC vector extensions (SSE2 "
        << "here; the same float operations as the scalar test, so the same answers). Counts per query; variants run "
        << "round-robin, " << 3 * repeats << " rounds; ms = median of the timed runs; speed = the binary tree's ms / this "
        << "ms. Written by `minkq_ablation --only wide`" << (repeats == 1 ? " --quick" : "") << ".\n\n"
        << table_head;
      std::string bytes_read;
      for (const std::string& name : procedural_scene_names())
        o << compare_wide(make_scene(name, scale, 2, data), repeats, ok, bytes_read);
      o << compare_wide(make_scene("twist_target", scale, 2, data), repeats, ok, bytes_read);
      o << "\n## Node-record bytes read per query\n\nFrom the table above: nodes / query x record size (binary 64 B; "
        << "4-wide float " << sizeof(WideNode<4>) << " B, 8-bit 72 B; 8-wide float " << sizeof(WideNode<8>)
        << " B, 8-bit 128 B), leaf ranges of 16; in brackets the ratio to the binary tree. Leaf boxes scanned (24 B "
        << "each) come on top and are the same for all. A GPU traversal is bound by these dependent reads; the CPU "
        << "speed of the 4-wide 8-bit tree (its boxes stored decoded, so not its real cost) is the last column.\n\n"
        << "| scene | kind | mode | binary | 4-wide | 4-wide 8-bit | 8-wide | 8-wide 8-bit | CPU speed, 4-wide 8-bit |\n"
        << "|---|---|---|---|---|---|---|---|---|\n"
        << bytes_read;
      o << "\nLoad average at end " << fmt(load_average(), 3) << ".\n";
      write("wide.md", o.str());
    }
    if (sections == "all" || sections == "policies") {
      constexpr int kFrames = 21;
      std::ostringstream o;
      o << "# Rebuild policies end to end (issue 8)\n\nMachine: " << machine_line("cpu") << ". Load average (1 min) at "
        << "start " << fmt(load_average(), 3) << ". Every procedural scene and the twisted sheet over " << kFrames
        << " frames of its motion: the scene created at frame 0 (not timed), then per step the update to the next frame "
        << "(minkq_scene_refit, or minkq_scene_rebuild where the policy says, then minkq_scene_tree_growth) and the VT "
        << "and EE queries (box mode, r = the scene's radius, incident pairs dropped, into reused results), through "
        << "the C API on the CPU device (all threads). A growth policy reads the growth after each step and rebuilds at "
        << "the next. Every policy's pairs checked equal at every step (digests); nodes per query from a separate "
        << "untimed MINKQ_QUERY_STATS pass, averaged over the steps; growth max = the largest growth read. The policies' "
        << "whole sequences run round-robin, " << repeats << " rounds; ms = median over the rounds of the sequence's "
        << "sum; speed = 'refit every step' total / this total. Written by `minkq_ablation --only policies`"
        << (repeats == 1 ? " --quick" : "") << ".\n\n"
        << "| scene | steps | policy | rebuilds | growth max | VT nodes / query | EE nodes / query | update ms | query ms | "
           "total ms | speed |\n|---|---|---|---|---|---|---|---|---|---|---|\n";
      for (const std::string& name : procedural_scene_names())
        o << compare_policies(make_scene(name, scale, kFrames, data), repeats, ok);
      o << compare_policies(make_scene("twist_target", scale, kFrames, data), repeats, ok);
      o << "\nLoad average at end " << fmt(load_average(), 3) << ".\n";
      write("policies.md", o.str());
    }
    if (sections == "all" || sections == "contacts") {
      std::ostringstream o;
      o << "# Contacts: node test and leaf screen under the leaf distance test (issue 8)\n\nMachine: "
        << machine_line("cpu (core traversal, TBB)") << ". Load average (1 min) at start " << fmt(load_average(), 3)
        << ". Contacts are the output of MINKQ_QUERY_LEAF_EXACT: every pair within r by the double-precision distance "
        << "test at the leaves. Four ways to them on the library's trees at each scene's last frame (r = the scene's "
        << "radius, incident pairs dropped, all threads): the finer node mode (sphere for VT, capsule_exact for EE) or "
        << "the box test in the tree and at the primitive boxes, and at the leaves the full distance test alone or behind "
        << "the separation screen (the gap along the axis joining the two elements' centres: predicates.h's "
        << "segments_apart for EE, the same idea for VT in bench/ablation/contacts.cpp). All four "
        << "return the same pairs (checked). Counts per query; the variants run round-robin, " << 3 * repeats
        << " rounds; ms = the median; speed = 'before' ms / this ms, in the same run. Written by `minkq_ablation --only "
        << "contacts`" << (repeats == 1 ? " --quick" : "") << ".\n\n"
        << table_head;
      for (const std::string& name : procedural_scene_names()) o << compare_contacts(make_scene(name, scale, 2, data), repeats, ok);
      o << compare_contacts(make_scene("twist_target", scale, 2, data), repeats, ok);
      for (const RealMesh& m : available_real_meshes(data))
        if (m.name == "unisex_shirt" || m.name == "multilayer_drape" || m.name == "rod-twist3036")
          o << compare_contacts(load_real_scene(m, data), repeats, ok);
      o << "\nLoad average at end " << fmt(load_average(), 3) << ".\n";
      write("contacts.md", o.str());
    }
    if (sections == "all" || sections == "fused") {
      Device device = open_device(backend.c_str());
      const std::string file = backend == "cpu" ? "fused.md" : "fused_" + backend.substr(0, backend.find(':')) + ".md";
      std::ostringstream o;
      o << "# One pass for VT and EE (issue 8)\n\nMachine: " << machine_line(minkq_device_name(device.get()))
        << ". Load average (1 min) at start " << fmt(load_average(), 3) << ". Each scene created at its first frame "
        << "and refit to its last, r = the scene's radius, incident pairs dropped, box mode; one step's VT and EE "
        << "queries through the C API into reused results: two minkq_scene_query_result calls against one "
        << "minkq_scene_query_vt_ee_result call (one parallel loop over both query sets on the CPU; one kernel launch "
        << "and one count readback on CUDA), for the box candidates and for the contacts (leaf_exact). Pairs checked "
        << "equal by digest. The variants run round-robin, " << 3 * repeats << " rounds after a warm-up; ms = the "
        << "median; speed = two calls' ms / this ms, in the same run. Written by `minkq_ablation --only fused"
        << (backend == "cpu" ? "" : " --backend " + backend) << "`" << (repeats == 1 ? " --quick" : "") << ".\n\n"
        << "| scene | triangles | output | variant | VT pairs | EE pairs | ms | speed |\n|---|---|---|---|---|---|---|---|\n";
      for (const std::string& name : procedural_scene_names())
        o << compare_fused(make_scene(name, scale, 2, data), device.get(), 3 * repeats, ok);
      o << compare_fused(make_scene("twist_target", scale, 2, data), device.get(), 3 * repeats, ok);
      for (const RealMesh& m : available_real_meshes(data))
        if (m.name == "unisex_shirt" || m.name == "multilayer_drape")
          o << compare_fused(load_real_scene(m, data), device.get(), 3 * repeats, ok);
      o << compare_fused(make_scene("twist_target", 1e6, 2, data), device.get(), 3 * repeats, ok);
      o << "\nLoad average at end " << fmt(load_average(), 3) << ".\n";
      write(file, o.str());
    }
    if (!ok) {
      std::fprintf(stderr, "FAIL: a variant returned different pairs\n");
      return 1;
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "minkq_ablation: %s\n", e.what());
    return 3;
  }
}
