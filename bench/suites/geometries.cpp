// minkq_bench's geometries suite (geometries.md): scenes of many geometries (issue 53) against
// their baselines, same process, same threads, same run.
//  - Cloth on a body: a 50 x 50 cloth (4,802 triangles, the size of Newton's square cloth) cut
//    into the top tenth of Newton's bunny, sinking a little each frame; the bunny static at 1x,
//    4x and 16x its triangles (midpoint subdivision); r = 0.5 x the cloth's mean edge. A step moves
//    the cloth and finds the cross pairs (VT both ways, EE) in box mode: minkq with two geometries
//    (the cloth refit alone, the body never touched), the two meshes concatenated in one minkq scene
//    (refit whole, query whole, keep the cross pairs: the way without geometries), and Embree's
//    rtcCollide of the cloth's and the body's element scenes (peers/embree.h; the cloth's
//    three scenes refit, or rebuilt: both rows). A leaf_exact row for minkq's two ways.
//  - Batched worlds: W copies of a 32 x 32 cloth at the same place, each twisted its own way, self
//    pairs (VT, EE, incident dropped, box mode): one scene of W worlds (refit all, query) against
//    one scene per world in a loop, and (W <= 16) the copies concatenated with the cross-world pairs
//    dropped.
// Checked: every way's pairs are the same set, in the geometries' global numbering.
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include "peers/embree.h"
#include "suites/suites.h"

namespace minkq::bench::suites {
namespace {

using Pairs = PairSet;

// The two meshes of the cloth-on-body scene and the cloth's frames.
struct ClothOnBody {
  ref::Mesh cloth, body;
  std::vector<std::vector<float>> frames;  // the cloth's positions per frame
  float r;
};

ClothOnBody cloth_on_body(const std::string& data, int subdivisions, int frames) {
  ClothOnBody s;
  s.body = ref::load_mesh(mesh_path("newton/bunny.obj", data));
  for (int k = 0; k < subdivisions; ++k) s.body = subdivide(s.body);
  Box b = Box::empty();
  for (size_t v = 0; v < s.body.vertex_count(); ++v)
    b = box_expand(b, Vec3{s.body.xyz[3 * v], s.body.xyz[3 * v + 1], s.body.xyz[3 * v + 2]});
  s.cloth = ref::grid_sheet(50);
  const float height = b.hi.y - b.lo.y, cx = 0.5f * (b.lo.x + b.hi.x), cz = 0.5f * (b.lo.z + b.hi.z);
  const float wx = 0.8f * (b.hi.x - b.lo.x), wz = 0.8f * (b.hi.z - b.lo.z);
  for (int k = 0; k < frames; ++k) {
    std::vector<float> xyz(s.cloth.xyz.size());
    for (size_t v = 0; v < s.cloth.vertex_count(); ++v) {
      const float u = s.cloth.xyz[3 * v], w = s.cloth.xyz[3 * v + 1];
      xyz[3 * v] = cx + (u - 0.5f) * wx;
      xyz[3 * v + 1] = b.hi.y - height * (0.1f + 0.005f * float(k)) + 0.01f * height * std::sin(6.0f * u + float(k));
      xyz[3 * v + 2] = cz + (w - 0.5f) * wz;
    }
    s.frames.push_back(xyz);
  }
  s.cloth.xyz = s.frames[0];
  s.cloth.edges = ref::derive_edges(s.cloth.tris);
  s.body.edges = ref::derive_edges(s.body.tris);
  s.r = float(0.5 * ref::mean_edge_length(s.cloth));
  return s;
}

minkq_geometry_desc geometry_of(const ref::Mesh& mesh, const std::vector<float>& xyz, uint32_t flags) {
  minkq_geometry_desc d;
  minkq_geometry_desc_init(&d);
  d.flags = flags;
  d.vertices = host_buffer(xyz.data(), xyz.size() / 3, 12);
  d.triangles = host_buffer(mesh.tris.data(), mesh.triangle_count(), 12);
  return d;
}

Scene create_geometries(minkq_device* device, const std::vector<minkq_geometry_desc>& descs) {
  minkq_scene* scene = nullptr;
  check(minkq_scene_create_geometries(device, descs.data(), descs.size(), &scene), "minkq_scene_create_geometries");
  return Scene(scene);
}

Pairs shifted(const Pairs& pairs, uint64_t first, uint64_t second, bool swap = false) {
  Pairs out;
  for (uint64_t p : pairs) {
    const uint64_t a = (p >> 32) + first, b = (p & 0xffffffffu) + second;
    out.push_back(swap ? (b << 32 | a) : (a << 32 | b));
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::string cloth_rows(const SuiteRun& run, int subdivisions, bool& ok) {
  const ClothOnBody s = cloth_on_body(run.data, subdivisions, 4);
  const size_t cv = s.cloth.vertex_count(), ct = s.cloth.triangle_count(), ce = s.cloth.edge_count();
  std::fprintf(stderr, "cloth on body x%d: cloth %zu T, body %zu T, r = %.4g\n", 1 << (2 * subdivisions), ct,
               s.body.triangle_count(), double(s.r));
  // minkq, two geometries: the cloth moves, the body is static; cross pairs only.
  Scene two = create_geometries(run.device, {geometry_of(s.cloth, s.frames[0], 0),
                                             geometry_of(s.body, s.body.xyz, MINKQ_GEOMETRY_STATIC)});
  // minkq, one mesh of both (the cloth's vertices, triangles and edges first).
  ref::Mesh both = s.cloth;
  for (float x : s.body.xyz) both.xyz.push_back(x);
  for (int32_t v : s.body.tris) both.tris.push_back(v + int32_t(cv));
  Scene one = create_scene(run.device, both.xyz, both.tris, MINKQ_SCENE_VT | MINKQ_SCENE_EE);
  // Embree: the body's scenes once, the cloth's per step.
  EmbreeBoxes body_vertices(false), body_triangles(false), body_edges(false);
  using Side = EmbreeBoxes::Side;
  body_vertices.set(s.body.xyz, {}, 1, s.r, Side::query);
  body_triangles.set(s.body.xyz, s.body.tris, 3, s.r, Side::tree);
  body_edges.set(s.body.xyz, s.body.edges, 2, s.r, Side::tree);
  Result vt = new_result(), ee = new_result();
  std::vector<float> all = both.xyz;
  int frame = 0;
  auto next_frame = [&] { frame = (frame + 1) % int(s.frames.size()); };
  Pairs got_vt, got_ee;
  auto geometries_step = [&](uint32_t flags) {
    check(minkq_scene_geometry_refit(two.get(), 0, host_buffer(s.frames[frame].data(), cv, 12)), "geometry_refit");
    query(two.get(), MINKQ_QUERY_VT, MINKQ_MODE_BOX, flags, s.r, vt.get());
    query(two.get(), MINKQ_QUERY_EE, MINKQ_MODE_BOX, flags, s.r, ee.get());
    got_vt = pairs_of(vt.get());
    got_ee = pairs_of(ee.get());
  };
  Pairs cat_vt, cat_ee;
  auto concatenated_step = [&](uint32_t flags) {
    std::copy(s.frames[frame].begin(), s.frames[frame].end(), all.begin());
    check(minkq_scene_refit(one.get(), host_buffer(all.data(), all.size() / 3, 12)), "minkq_scene_refit");
    query(one.get(), MINKQ_QUERY_VT, MINKQ_MODE_BOX, flags, s.r, vt.get());
    query(one.get(), MINKQ_QUERY_EE, MINKQ_MODE_BOX, flags, s.r, ee.get());
    cat_vt.clear();
    cat_ee.clear();
    const int32_t* p = minkq_result_pairs(vt.get());
    for (uint64_t i = 0; i < minkq_result_count(vt.get()); ++i)
      if ((size_t(p[2 * i]) < cv) != (size_t(p[2 * i + 1]) < ct)) cat_vt.push_back(pack(p[2 * i], p[2 * i + 1]));
    p = minkq_result_pairs(ee.get());
    for (uint64_t i = 0; i < minkq_result_count(ee.get()); ++i)
      if ((size_t(p[2 * i]) < ce) != (size_t(p[2 * i + 1]) < ce)) cat_ee.push_back(pack(p[2 * i], p[2 * i + 1]));
    std::sort(cat_vt.begin(), cat_vt.end());
    std::sort(cat_ee.begin(), cat_ee.end());
  };
  Pairs em_vt, em_ee, reverse;
  auto embree_step = [&](EmbreeBoxes& cv_s, EmbreeBoxes& ct_s, EmbreeBoxes& ce_s) {
    cv_s.set(s.frames[frame], {}, 1, s.r, Side::query);
    ct_s.set(s.frames[frame], s.cloth.tris, 3, s.r, Side::tree);
    ce_s.set(s.frames[frame], s.cloth.edges, 2, s.r, Side::query);
    embree_collide(cv_s, body_triangles, em_vt, false, false);  // shifted() sorts
    embree_collide(body_vertices, ct_s, reverse, false, false);
    em_vt = shifted(em_vt, 0, ct);
    reverse = shifted(reverse, cv, 0);
    em_vt.insert(em_vt.end(), reverse.begin(), reverse.end());
    std::sort(em_vt.begin(), em_vt.end());
    embree_collide(ce_s, body_edges, em_ee, false, false);
    em_ee = shifted(em_ee, 0, ce);
  };
  EmbreeBoxes refit_v(true), refit_t(true), refit_e(true), build_v(false), build_t(false), build_e(false);
  std::string out;
  const std::string size = "x" + std::to_string(1 << (2 * subdivisions)) + " (" + std::to_string(s.body.triangle_count()) + " T)";
  for (uint32_t flags : {0u, uint32_t(MINKQ_QUERY_LEAF_EXACT)}) {
    const char* mode = flags ? "box + leaf_exact" : "box";
    const Timing mine = measure(1, run.repeats, [&] { geometries_step(flags); }, next_frame);
    const Timing cat = measure(1, run.repeats, [&] { concatenated_step(flags); }, next_frame);
    // The same frame for the check: the last one each ran.
    frame = 0;
    geometries_step(flags);
    concatenated_step(flags);
    if (got_vt != cat_vt || got_ee != cat_ee) {
      std::fprintf(stderr, "FAIL cloth on body %s %s: geometries %zu VT %zu EE, concatenated %zu VT %zu EE\n",
                   size.c_str(), mode, got_vt.size(), got_ee.size(), cat_vt.size(), cat_ee.size());
      ok = false;
    }
    auto row = [&](const char* way, const Timing& t) {
      out += "| " + size + " | " + mode + " | " + way + " | " + t.text(4) + " | " + fmt(t.median / mine.median, 3) +
             "x | " + std::to_string(got_vt.size()) + " | " + std::to_string(got_ee.size()) + " |\n";
    };
    row("minkq, two geometries (cloth refit)", mine);
    row("minkq, one concatenated mesh, filtered", cat);
    if (flags) continue;
    const Timing refit = measure(1, run.repeats, [&] { embree_step(refit_v, refit_t, refit_e); }, next_frame);
    const Timing build = measure(1, run.repeats, [&] { embree_step(build_v, build_t, build_e); }, next_frame);
    frame = 0;
    embree_step(refit_v, refit_t, refit_e);
    if (em_vt != got_vt || em_ee != got_ee) {
      std::fprintf(stderr, "FAIL cloth on body %s: Embree %zu VT %zu EE, minkq %zu VT %zu EE\n", size.c_str(),
                   em_vt.size(), em_ee.size(), got_vt.size(), got_ee.size());
      ok = false;
    }
    row("Embree rtcCollide, cloth refit", refit);
    row("Embree rtcCollide, cloth rebuilt", build);
  }
  return out;
}

std::string world_rows(const SuiteRun& run, int worlds, bool& ok) {
  const int n = 32;
  const ref::Mesh sheet = ref::grid_sheet(n);
  std::vector<std::vector<float>> frame_sets[2];  // per frame, per world
  for (int k = 0; k < 2; ++k)
    for (int w = 0; w < worlds; ++w)
      frame_sets[k].push_back(ref::twisted_sheet(n, 0.25 + 0.5 * w / worlds + 0.05 * k).xyz);
  const float r = float(0.5 * ref::mean_edge_length(ref::twisted_sheet(n, 0.25)));
  const size_t nv = sheet.vertex_count(), nt = sheet.triangle_count();
  std::fprintf(stderr, "worlds: %d x %zu T, r = %.4g\n", worlds, nt, double(r));
  std::vector<minkq_geometry_desc> descs;
  for (int w = 0; w < worlds; ++w) {
    descs.push_back(geometry_of(sheet, frame_sets[0][size_t(w)], MINKQ_GEOMETRY_SELF | MINKQ_GEOMETRY_DROP_INCIDENT));
    descs.back().world = w;
  }
  Scene batched = create_geometries(run.device, descs);
  std::vector<Scene> loop;
  for (int w = 0; w < worlds; ++w) loop.push_back(create_scene(run.device, frame_sets[0][size_t(w)], sheet.tris));
  std::vector<float> all[2];
  std::vector<int32_t> all_tris;
  for (int k = 0; k < 2; ++k)
    for (int w = 0; w < worlds; ++w) all[k].insert(all[k].end(), frame_sets[k][size_t(w)].begin(), frame_sets[k][size_t(w)].end());
  for (int w = 0; w < worlds; ++w)
    for (int32_t v : sheet.tris) all_tris.push_back(v + int32_t(size_t(w) * nv));
  const bool concatenate = worlds <= 16;
  Scene one = concatenate ? create_scene(run.device, all[0], all_tris) : Scene();
  Result vt = new_result(), ee = new_result();
  int frame = 0;
  auto next_frame = [&] { frame ^= 1; };
  size_t ne = 0;
  {
    size_t first = 0;
    check(minkq_scene_geometry_range(batched.get(), 0, MINKQ_ELEMENT_EDGE, &first, &ne), "geometry_range");
  }
  Pairs b_vt, b_ee, l_vt, l_ee, c_vt, c_ee;
  auto batched_step = [&] {
    check(minkq_scene_refit(batched.get(), host_buffer(all[frame].data(), all[frame].size() / 3, 12)), "refit");
    query(batched.get(), MINKQ_QUERY_VT, MINKQ_MODE_BOX, 0, r, vt.get());
    b_vt = pairs_of(vt.get());
    query(batched.get(), MINKQ_QUERY_EE, MINKQ_MODE_BOX, 0, r, ee.get());
    b_ee = pairs_of(ee.get());
  };
  auto loop_step = [&] {
    l_vt.clear();
    l_ee.clear();
    for (int w = 0; w < worlds; ++w) {
      check(minkq_scene_refit(loop[size_t(w)].get(), host_buffer(frame_sets[frame][size_t(w)].data(), nv, 12)), "refit");
      query(loop[size_t(w)].get(), MINKQ_QUERY_VT, MINKQ_MODE_BOX, 0, r, vt.get());
      const Pairs v = shifted(pairs_of(vt.get()), size_t(w) * nv, size_t(w) * nt);
      l_vt.insert(l_vt.end(), v.begin(), v.end());
      query(loop[size_t(w)].get(), MINKQ_QUERY_EE, MINKQ_MODE_BOX, 0, r, ee.get());
      const Pairs e = shifted(pairs_of(ee.get()), size_t(w) * ne, size_t(w) * ne);
      l_ee.insert(l_ee.end(), e.begin(), e.end());
    }
  };
  auto concatenated_step = [&] {
    check(minkq_scene_refit(one.get(), host_buffer(all[frame].data(), all[frame].size() / 3, 12)), "refit");
    query(one.get(), MINKQ_QUERY_VT, MINKQ_MODE_BOX, 0, r, vt.get());
    c_vt.clear();
    c_ee.clear();
    const int32_t* p = minkq_result_pairs(vt.get());
    for (uint64_t i = 0; i < minkq_result_count(vt.get()); ++i)
      if (size_t(p[2 * i]) / nv == size_t(p[2 * i + 1]) / nt) c_vt.push_back(pack(p[2 * i], p[2 * i + 1]));
    query(one.get(), MINKQ_QUERY_EE, MINKQ_MODE_BOX, 0, r, ee.get());
    p = minkq_result_pairs(ee.get());
    for (uint64_t i = 0; i < minkq_result_count(ee.get()); ++i)
      if (size_t(p[2 * i]) / ne == size_t(p[2 * i + 1]) / ne) c_ee.push_back(pack(p[2 * i], p[2 * i + 1]));
    std::sort(c_vt.begin(), c_vt.end());
    std::sort(c_ee.begin(), c_ee.end());
  };
  const Timing mine = measure(1, run.repeats, batched_step, next_frame);
  const Timing looped = measure(1, run.repeats, loop_step, next_frame);
  frame = 0;
  batched_step();
  loop_step();
  std::sort(l_vt.begin(), l_vt.end());
  std::sort(l_ee.begin(), l_ee.end());
  if (b_vt != l_vt || b_ee != l_ee) {
    std::fprintf(stderr, "FAIL worlds %d: batched %zu VT %zu EE, loop %zu VT %zu EE\n", worlds, b_vt.size(), b_ee.size(),
                 l_vt.size(), l_ee.size());
    ok = false;
  }
  std::string out;
  auto row = [&](const char* way, const Timing& t) {
    out += "| " + std::to_string(worlds) + " | " + way + " | " + t.text(4) + " | " + fmt(t.median / mine.median, 3) +
           "x | " + std::to_string(b_vt.size()) + " | " + std::to_string(b_ee.size()) + " |\n";
  };
  row("minkq, one scene of the worlds", mine);
  row("minkq, one scene per world, in a loop", looped);
  if (concatenate) {
    const Timing cat = measure(1, run.repeats, concatenated_step, next_frame);
    frame = 0;
    concatenated_step();
    if (c_vt != b_vt || c_ee != b_ee) {
      std::fprintf(stderr, "FAIL worlds %d: concatenated %zu VT %zu EE\n", worlds, c_vt.size(), c_ee.size());
      ok = false;
    }
    row("minkq, worlds concatenated, cross-world pairs dropped", cat);
  }
  return out;
}

}  // namespace

std::string geometries_report(const SuiteRun& run, bool& ok) {
  std::ostringstream o;
  o << "# Scenes of many geometries (issue 53)\n\nMachine: " << run.machine << ". Load average (1 min) at start "
    << fmt(load_average(), 3) << ". Device: " << minkq_device_name(run.device) << ". One warm-up and " << run.repeats
    << " timed steps per row (ms: median and range), frames cycling; '/ geometries' = this ms over the first row of "
    << "its group, in the same run. Pairs checked equal across the ways of each group. Written " << utc_now() << " by "
    << run.by << ".\n\n## Cloth on a body\n\nA 50 x 50 cloth cut into the top of Newton's bunny, the bunny static at "
    << "1x, 4x and 16x its triangles; a step moves the cloth and finds the cross pairs (VT both ways, EE), "
    << "r = 0.5 x the cloth's mean edge.\n\n| body | mode | way | step ms | / geometries | VT pairs | EE pairs |\n"
    << "|---|---|---|---|---|---|---|\n";
  for (int subdivisions = 0; subdivisions <= (run.quick ? 0 : 2); ++subdivisions) o << cloth_rows(run, subdivisions, ok);
  o << "\n## Batched worlds\n\nW copies of a 32 x 32 cloth at the same place, each twisted its own way; a step "
    << "refits them all and finds their self pairs (VT and EE, incident dropped, box mode), r = 0.5 x the mean "
    << "edge.\n\n| W | way | step ms | / one scene | VT pairs | EE pairs |\n|---|---|---|---|---|---|\n";
  for (int worlds : run.quick ? std::vector<int>{4} : std::vector<int>{16, 256, 1024}) o << world_rows(run, worlds, ok);
  o << "\nLoad average at end " << fmt(load_average(), 3) << ".\n";
  return o.str();
}

}  // namespace minkq::bench::suites
