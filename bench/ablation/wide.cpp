// minkq_ablation's wide-node study (wide.md, issue 8): 4- and 8-ary trees collapsed from the
// binary one (bench/studies/wide_bvh.h, not the library's tree).
#include <cstdio>
#include <functional>
#include <memory>
#include <vector>

#include "studies/wide_bvh.h"

#include "ablation/ablation.h"

namespace minkq::bench::ablation {
namespace {

// One mode over a wide tree's pair (triangles, edges): kind 0 = VT sphere, 1 = EE box,
// 2 = EE capsule_exact.
template <int W, bool kLanes>
Outcome run_wide(const WideTree<W> (&trees)[2], const VertexTriangleQueries& vt, const EdgeEdgeQueries& ee, int kind,
                 int32_t nv, int32_t ne, int reps) {
  auto go = [&](auto shape, const WideTree<W>& tree, const auto& queries, int32_t n) {
    using Shape = decltype(shape);
    return run_each(n, reps, [&](int32_t i, auto& emit, WorkCounts& work) {
      run_query_wide<W, kLanes, Shape>(tree, queries, i, emit, work);
    });
  };
  if (kind == 0) return go(SphereShape{}, trees[0], vt, nv);
  if (kind == 1) return go(BoxShape{}, trees[1], ee, ne);
  return go(CapsuleExactShape{}, trees[1], ee, ne);
}

}  // namespace

// Wide nodes (issue 8's untried lever; bench/studies/wide_bvh.h, not the library's tree). Each
// scene's two binary trees are built at the first frame with leaf ranges of 16 (the
// library's), 4 or 1, collapsed there to 4- and 8-ary nodes, and refit to the last frame (the
// wide nodes take the refit boxes), as a simulator's refit-only steps run them. VT sphere, EE
// box and EE capsule_exact at the scene's radius; the pairs of every variant checked equal to
// the binary tree's; variants timed round-robin (round_robin).
// Also appends to `bytes_read` a summary row per mode: node-record bytes read per query by the
// binary tree and by the leaf-16 wide trees (nodes / query x record size).
std::string compare_wide(const SceneFrames& sc, int repeats, bool& ok, std::string& bytes_read) {
  const FirstAndLast frames(sc, "wide");
  const Vec3 *v0 = frames.v0, *v = frames.v;
  const Triangle* t = frames.t;
  const Edge* e = frames.e;
  const float r = frames.r;
  const int32_t nv = frames.nv, nt = frames.nt, ne = frames.ne;
  const VertexTriangleQueries vt{v, t, frames.order.data(), r, kDropIncident};
  struct Trees {
    CpuTree binary[2];  // triangles, edges
    WideTree<4> wide4[2], wide4q[2];  // float child boxes, 8-bit quantized child boxes
    WideTree<8> wide8[2], wide8q[2];
  };
  const int32_t leaf_sizes[3] = {kLeafSize, 4, 1};
  std::vector<std::unique_ptr<Trees>> trees;
  for (const int32_t leaf : leaf_sizes) {
    Trees& x = *trees.emplace_back(std::make_unique<Trees>());
    x.binary[0].build(TriangleBoxes{v0, t}, nt, BuildConfig{leaf});
    x.binary[1].build(EdgeBoxes{v0, e}, ne, BuildConfig{leaf});
    for (int k = 0; k < 2; ++k) {
      x.wide4[k].collapse(x.binary[k]);
      x.wide8[k].collapse(x.binary[k]);
      x.wide4q[k].collapse(x.binary[k]);
      x.wide8q[k].collapse(x.binary[k]);
    }
    x.binary[0].refit(TriangleBoxes{v, t});
    x.binary[1].refit(EdgeBoxes{v, e});
    for (int k = 0; k < 2; ++k) {
      x.wide4[k].fill(x.binary[k]);
      x.wide8[k].fill(x.binary[k]);
      x.wide4q[k].fill(x.binary[k], true);
      x.wide8q[k].fill(x.binary[k], true);
    }
  }
  struct Variant {
    std::string label;
    size_t record_bytes;
    std::function<Outcome(int kind, int reps)> query;
  };
  std::vector<Variant> variants;
  auto bytes_label = [&](const std::string& what, size_t node_bytes) {
    char b[64];
    std::snprintf(b, sizeof b, ": %.1f B of nodes / triangle", double(node_bytes) / nt);
    return what + b;
  };
  {
    const Trees& x = *trees[0];
    Variant& binary = variants.emplace_back();
    binary.record_bytes = sizeof(BvhNode);
    binary.label = bytes_label("binary, leaf 16 (kept)", 64 * (x.binary[0].nodes().size() + x.binary[1].nodes().size()));
    binary.query = [&x, &vt, v, e, r, nv, ne](int kind, int reps) {
      const EdgeEdgeQueries ee{v, e, x.binary[1].sorted_prims().data(), r, kDropIncident};
      if (kind == 0) return run<SphereShape>(x.binary[0].view(), vt, nv, reps);
      if (kind == 1) return run<BoxShape>(x.binary[1].view(), ee, ne, reps);
      return run<CapsuleExactShape>(x.binary[1].view(), ee, ne, reps);
    };
  }
  // Quantized records (see WideTree::fill) would hold a float origin, 3 exponent bytes, a pad
  // byte and 8-bit planes instead of float boxes: 72 B per 4-wide node, 128 B per 8-wide.
  auto add_wide = [&](int width, size_t leaf_index, bool lanes, bool quantized) {
    const Trees& x = *trees[leaf_index];
    const size_t count = width == 4 ? x.wide4[0].nodes().size() + x.wide4[1].nodes().size()
                                    : x.wide8[0].nodes().size() + x.wide8[1].nodes().size();
    const size_t record = quantized ? (width == 4 ? 72 : 128) : (width == 4 ? sizeof(WideNode<4>) : sizeof(WideNode<8>));
    const std::string what = std::to_string(width) + "-wide, leaf " + std::to_string(leaf_sizes[leaf_index]) +
                             (quantized ? ", 8-bit child boxes" : "") +
                             (lanes ? ", tested in 4-float lanes" : ", tested one by one");
    Variant& wide = variants.emplace_back();
    wide.record_bytes = record;
    wide.label = bytes_label(what, count * record);
    wide.query = [&x, &vt, v, e, r, nv, ne, width, lanes, quantized](int kind, int reps) {
      const EdgeEdgeQueries ee{v, e, x.binary[1].sorted_prims().data(), r, kDropIncident};
      if (width == 8) return run_wide<8, true>(quantized ? x.wide8q : x.wide8, vt, ee, kind, nv, ne, reps);
      return lanes ? run_wide<4, true>(quantized ? x.wide4q : x.wide4, vt, ee, kind, nv, ne, reps)
                   : run_wide<4, false>(x.wide4, vt, ee, kind, nv, ne, reps);
    };
  };
  add_wide(4, 0, false, false);
  add_wide(4, 0, true, false);
  add_wide(4, 1, true, false);
  add_wide(4, 2, true, false);
  add_wide(8, 0, true, false);
  add_wide(8, 1, true, false);
  add_wide(8, 2, true, false);
  add_wide(4, 0, true, true);
  add_wide(4, 1, true, true);
  add_wide(8, 0, true, true);
  const std::vector<std::vector<Outcome>> got = round_robin(
      variants.size(), 3, 3 * repeats, [&](size_t i, int kind, int reps) { return variants[i].query(kind, reps); });
  std::string out;
  const char* kinds[3] = {"VT", "EE", "EE"};
  const char* modes[3] = {"sphere", "box", "capsule_exact"};
  for (int kind = 0; kind < 3; ++kind)
    for (size_t i = 0; i < variants.size(); ++i) {
      const Outcome& o = got[i][size_t(kind)];
      ok &= o.pairs == got[0][size_t(kind)].pairs;
      out += row(sc.name, kinds[kind], modes[kind], variants[i].label.c_str(), o, kind ? ne : nv, got[0][size_t(kind)]);
    }
  // Binary, then the leaf-16 wide trees: 4-wide float, 4-wide 8-bit, 8-wide float, 8-wide 8-bit.
  const size_t summarized[5] = {0, 2, 8, 5, 10};
  for (int kind = 0; kind < 3; ++kind) {
    bytes_read += "| " + sc.name + " | " + kinds[kind] + " | " + modes[kind] + " |";
    const double base = double(got[0][size_t(kind)].work.nodes_visited) * sizeof(BvhNode);
    for (const size_t i : summarized) {
      const double b = double(got[i][size_t(kind)].work.nodes_visited) * double(variants[i].record_bytes);
      bytes_read += " " + fmt(b / (kind ? ne : nv), 4) + (i ? " (" + fmt(b / base, 3) + "x)" : "") + " |";
    }
    bytes_read += " " + fmt(got[0][size_t(kind)].ms / got[8][size_t(kind)].ms, 3) + "x |\n";
  }
  return out;
}

}  // namespace minkq::bench::ablation
