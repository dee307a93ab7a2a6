// The distributed queries under mpirun (ctest runs this with 2, 3 and 4 ranks):
//   test_mpi MESH_DIR
// For generated and real meshes, every partition kind, with and without triangle copies and
// with local orders shuffled, VT and EE in every mode, with and without incident pairs: the
// union of the ranks' pairs equals the single-process query's pairs, pair by pair, and no pair
// is reported twice; also after refits and rebuilds, and at scales 1e-3 and 1e3. Then the
// collective errors: the same status and message on every rank, and the scene's state kept.
// The random partitions and moves draw a fresh seed each run (printed; MINKQ_TEST_SEED=S
// replays one).
#include <mpi.h>

#include <algorithm>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "distributed.h"
#include "minkq.hpp"
#include "minkq_mpi.h"
#include "minkq_reference.h"

namespace {

namespace ref = minkq::reference;
namespace tools = minkq::mpi_tools;
using minkq::cxx::check;

int rank = 0, size = 1, failures = 0, checks = 0;
uint64_t seed = 0;
minkq_device* cpu = nullptr;  // the single-process reference's device, whatever the ranks use

// A check on this rank: reported with the rank and the case.
void expect(bool ok, const std::string& what) {
  ++checks;
  if (ok) return;
  ++failures;
  std::fprintf(stderr, "FAIL rank %d (seed %" PRIu64 "): %s\n", rank, seed, what.c_str());
}

// Every rank's status and message of a collective call must be the same; returns them.
void expect_same_everywhere(minkq_status status, const std::string& what) {
  int lo = int(status), hi = int(status);
  MPI_Allreduce(MPI_IN_PLACE, &lo, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  MPI_Allreduce(MPI_IN_PLACE, &hi, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  expect(lo == hi, what + ": the ranks returned different statuses");
  std::string message = minkq_mpi_last_error_message();
  int length = int(message.size());
  MPI_Bcast(&length, 1, MPI_INT, 0, MPI_COMM_WORLD);
  std::string root(size_t(length), '\0');
  if (rank == 0) root = message;
  MPI_Bcast(root.data(), length, MPI_CHAR, 0, MPI_COMM_WORLD);
  expect(root == message, what + ": the ranks' messages differ: '" + message + "' vs rank 0's '" + root + "'");
}

struct Scene {
  minkq_mpi_scene* s = nullptr;
  ~Scene() { minkq_mpi_scene_release(s); }
};
struct Result {
  minkq_mpi_result* r = nullptr;
  Result() { minkq_mpi_result_create(&r); }
  ~Result() { minkq_mpi_result_release(r); }
};

struct Query {
  minkq_query_kind kind;
  minkq_mode mode;
  uint32_t flags;
  const char* name;
};
const Query kQueries[] = {
    {MINKQ_QUERY_VT, MINKQ_MODE_BOX, 0, "VT box"},
    {MINKQ_QUERY_VT, MINKQ_MODE_SPHERE, 0, "VT sphere"},
    {MINKQ_QUERY_VT, MINKQ_MODE_CAPSULE_RAY, 0, "VT capsule_ray"},
    {MINKQ_QUERY_VT, MINKQ_MODE_CAPSULE_EXACT, 0, "VT capsule_exact"},
    {MINKQ_QUERY_VT, MINKQ_MODE_BOX, MINKQ_QUERY_LEAF_EXACT, "VT box+leaf_exact"},
    {MINKQ_QUERY_EE, MINKQ_MODE_BOX, 0, "EE box"},
    {MINKQ_QUERY_EE, MINKQ_MODE_CAPSULE_RAY, 0, "EE capsule_ray"},
    {MINKQ_QUERY_EE, MINKQ_MODE_CAPSULE_EXACT, 0, "EE capsule_exact"},
    {MINKQ_QUERY_EE, MINKQ_MODE_BOX, MINKQ_QUERY_LEAF_EXACT, "EE box+leaf_exact"},
};

// The single-process pairs of a query on the whole mesh (rank 0 only).
tools::GlobalPairs single_process(minkq_device* device, const ref::Mesh& m, uint32_t scene_flags, const Query& q,
                                  float r) {
  minkq::cxx::Scene scene =
      minkq::cxx::new_mesh_scene(device, m.xyz.data(), m.vertex_count(), m.tris.data(), m.triangle_count(), scene_flags);
  minkq::cxx::Result result = minkq::cxx::new_result();
  const minkq_query_desc d{q.kind, q.mode, q.flags | MINKQ_QUERY_CANONICAL, r};
  check(minkq_scene_query_result(scene.get(), &d, result.get()), "minkq_scene_query_result");
  const int32_t* p = minkq_result_pairs(result.get());
  tools::GlobalPairs out(minkq_result_count(result.get()));
  for (size_t i = 0; i < out.size(); ++i) out[i] = {p[2 * i], p[2 * i + 1]};
  return out;
}

// The distributed query against the single-process one, pair by pair, on rank 0.
void compare(minkq_mpi_scene* scene, const ref::Mesh& whole, uint32_t scene_flags, float r,
             const std::string& name) {
  Result result;
  for (const Query& q : kQueries) {
    const std::string what = name + ", " + q.name;
    const minkq_query_desc d{q.kind, q.mode, q.flags | MINKQ_QUERY_CANONICAL, r};
    const minkq_status status = minkq_mpi_scene_query(scene, &d, result.r);
    expect(status == MINKQ_SUCCESS, what + ": " + minkq_mpi_last_error_message());
    // This rank's pairs are sorted, and each is of an element it owns (checked on the union).
    const int64_t* p = minkq_mpi_result_pairs(result.r);
    const size_t n = minkq_mpi_result_count(result.r);
    bool sorted = true;
    for (size_t i = 1; i < n; ++i)
      sorted &= std::make_pair(p[2 * i - 2], p[2 * i - 1]) <= std::make_pair(p[2 * i], p[2 * i + 1]);
    expect(sorted, what + ": CANONICAL pairs not sorted");
    const tools::GlobalPairs all = tools::gather_pairs(MPI_COMM_WORLD, result.r);
    // The count-only query gives the same total.
    const minkq_query_desc c{q.kind, q.mode, q.flags | MINKQ_QUERY_COUNT, r};
    expect(minkq_mpi_scene_query(scene, &c, result.r) == MINKQ_SUCCESS, what + " COUNT: " + minkq_mpi_last_error_message());
    uint64_t counted = minkq_mpi_result_count(result.r), total = 0;
    expect(minkq_mpi_result_pairs(result.r) == nullptr, what + " COUNT kept pairs");
    MPI_Reduce(&counted, &total, 1, MPI_UINT64_T, MPI_SUM, 0, MPI_COMM_WORLD);
    if (rank != 0) continue;
    const tools::GlobalPairs want = single_process(cpu, whole, scene_flags, q, r);
    size_t twice = 0;
    for (size_t i = 1; i < all.size(); ++i) twice += all[i] == all[i - 1];
    expect(twice == 0, what + ": " + std::to_string(twice) + " pairs reported by two ranks");
    tools::GlobalPairs missing, extra;
    std::set_difference(want.begin(), want.end(), all.begin(), all.end(), std::back_inserter(missing));
    std::set_difference(all.begin(), all.end(), want.begin(), want.end(), std::back_inserter(extra));
    std::string example;
    if (!missing.empty())
      example = "; e.g. missing (" + std::to_string(missing[0].first) + ", " + std::to_string(missing[0].second) + ")";
    else if (!extra.empty())
      example = "; e.g. extra (" + std::to_string(extra[0].first) + ", " + std::to_string(extra[0].second) + ")";
    expect(missing.empty() && extra.empty(), what + ": " + std::to_string(missing.size()) + " missing and " +
                                                 std::to_string(extra.size()) + " extra of " +
                                                 std::to_string(want.size()) + example);
    expect(total == want.size(), what + ": COUNT gave " + std::to_string(total) + " of " + std::to_string(want.size()));
  }
}

minkq_status create(minkq_device* device, const tools::Part& part, uint32_t flags, Scene& scene) {
  const minkq_mpi_scene_desc desc = tools::desc_of(part, flags);
  return minkq_mpi_scene_create(MPI_COMM_WORLD, device, &desc, &scene.s);
}

minkq_buffer host(const std::vector<float>& xyz) { return {xyz.data(), 0, xyz.size() / 3, MINKQ_MEMORY_HOST}; }

void mesh_cases(minkq_device* device, const std::string& name, ref::Mesh mesh, double radius_factor, bool steps) {
  const float r = float(radius_factor * ref::mean_edge_length(mesh));
  for (tools::Partition kind : {tools::Partition::kSlab, tools::Partition::kMorton, tools::Partition::kRandom})
    for (int variant = 0; variant < 2; ++variant) {
      const bool copies = variant == 1, shuffle = variant == 1;
      const uint32_t flags = MINKQ_SCENE_VT | MINKQ_SCENE_EE | (variant == 0 ? MINKQ_SCENE_DROP_INCIDENT : 0);
      const std::string what = name + ", " + tools::partition_name(kind) + (copies ? ", copies, shuffled" : "") +
                               (variant == 0 ? ", incident dropped" : ", incident kept");
      const tools::Owners owners = tools::partition(mesh.xyz, mesh.tris, size, kind, seed);
      const tools::Part part = tools::part_of(mesh.xyz, mesh.tris, owners, rank, copies, shuffle, seed);
      Scene scene;
      const minkq_status status = create(device, part, flags, scene);
      expect_same_everywhere(status, what + ": create");
      expect(status == MINKQ_SUCCESS, what + ": create: " + minkq_mpi_last_error_message());
      if (status) continue;
      minkq_mpi_rank_info info{};
      minkq_mpi_scene_rank_info(scene.s, &info);
      expect(info.global_edges == mesh.edge_count(), what + ": " + std::to_string(info.global_edges) +
                                                         " global edges, not " + std::to_string(mesh.edge_count()));
      compare(scene.s, mesh, flags, r, what);
      minkq_mpi_scene_rank_info(scene.s, &info);
      expect(info.last_reach_ms >= 0 && info.last_ghost_ms >= 0 && info.last_trees_ms >= 0 && info.last_query_ms >= 0 &&
                 info.bytes_sent >= info.last_bytes_sent && (size > 1 || info.bytes_sent == 0),
             what + ": phase figures");
      if (!steps) continue;
      // Move: a fresh random wave each step, refit then rebuild; the whole mesh moves alike.
      std::mt19937_64 rng(seed + 17);
      for (int step = 0; step < 2; ++step) {
        ref::Mesh moved = mesh;
        const double amplitude = 3 * r * std::uniform_real_distribution<double>(0.5, 1.5)(rng);
        for (size_t v = 0; v < moved.vertex_count(); ++v)
          moved.xyz[3 * v + 2] += float(amplitude * std::sin(7.0 * moved.xyz[3 * v] + step));
        const std::vector<float> xyz = tools::local_positions(moved.xyz, part);
        const minkq_status moved_status =
            step == 0 ? minkq_mpi_scene_refit(scene.s, host(xyz)) : minkq_mpi_scene_rebuild(scene.s, host(xyz));
        expect(moved_status == MINKQ_SUCCESS, what + ": move: " + minkq_mpi_last_error_message());
        compare(scene.s, moved, flags, r, what + (step == 0 ? ", refit" : ", rebuild"));
        // The growth is every rank's largest, so the same on all of them; 1 right after builds.
        double growth = 0;
        expect_same_everywhere(minkq_mpi_scene_tree_growth(scene.s, &growth), what + ": growth");
        double lo = growth, hi = growth;
        MPI_Allreduce(MPI_IN_PLACE, &lo, 1, MPI_DOUBLE, MPI_MIN, MPI_COMM_WORLD);
        MPI_Allreduce(MPI_IN_PLACE, &hi, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
        expect(lo == hi && growth >= 1 && (step == 0 || growth == 1),
               what + ": growth " + std::to_string(growth) + " (ranks from " + std::to_string(lo) + " to " +
                   std::to_string(hi) + ")");
      }
    }
}

void expect_error(minkq_status got, minkq_status want, const std::string& fragment, const std::string& what) {
  expect_same_everywhere(got, what);
  const std::string message = minkq_mpi_last_error_message();
  expect(got == want, what + ": " + minkq_status_name(got) + " (" + message + "), not " + minkq_status_name(want));
  expect(message.find(fragment) != std::string::npos, what + ": message '" + message + "' lacks '" + fragment + "'");
}

// A skin keeps the ghost layer while the vertices move less than half of it: small steps
// reuse it (positions only), a larger one chooses it afresh; the pairs stay the single-process
// ones throughout. Stacked sheets moving towards each other make new pairs across the ranks.
void skin_cases(minkq_device* device) {
  const ref::Mesh mesh = ref::stacked_sheets(14, 3, 0.05);
  const float r = float(0.6 * ref::mean_edge_length(mesh));
  const double skin = 2.0 * r;
  for (tools::Partition kind : {tools::Partition::kSlab, tools::Partition::kRandom}) {
    const std::string what = std::string("skin, stacked sheets, ") + tools::partition_name(kind);
    const tools::Owners owners = tools::partition(mesh.xyz, mesh.tris, size, kind, seed);
    const tools::Part part = tools::part_of(mesh.xyz, mesh.tris, owners, rank, true, true, seed);
    const uint32_t flags = MINKQ_SCENE_VT | MINKQ_SCENE_EE | MINKQ_SCENE_DROP_INCIDENT;
    Scene scene;
    expect(create(device, part, flags, scene) == MINKQ_SUCCESS, what + ": " + minkq_mpi_last_error_message());
    if (!scene.s) continue;
    expect(minkq_mpi_scene_set_skin(scene.s, skin) == MINKQ_SUCCESS, what + ": set_skin");
    compare(scene.s, mesh, flags, r, what + ", step 0");
    minkq_mpi_rank_info before{}, after{};
    minkq_mpi_scene_rank_info(scene.s, &before);
    // Each step moves every vertex by 0.3 r at most (the layers towards each other, and
    // sideways): three steps stay within s / 2 = r, the fourth passes it.
    ref::Mesh moved = mesh;
    for (int step = 1; step <= 4; ++step) {
      moved = mesh;
      for (size_t v = 0; v < moved.vertex_count(); ++v) {
        const float layer = moved.xyz[3 * v + 2];
        moved.xyz[3 * v + 2] -= float(0.3 * r * step * (layer > 0 ? 1 : 0));
        moved.xyz[3 * v] += float(0.3 * r * step * std::sin(3.0 * v));
      }
      const std::vector<float> xyz = tools::local_positions(moved.xyz, part);
      expect(minkq_mpi_scene_refit(scene.s, host(xyz)) == MINKQ_SUCCESS, what + ": refit");
      compare(scene.s, moved, flags, r, what + ", step " + std::to_string(step));
      minkq_mpi_scene_rank_info(scene.s, &after);
      const uint64_t queries = 3 * 2 * std::size(kQueries);  // steps 1-3, each query with its count
      if (step == 3)  // every query of steps 1-3 kept its layer
        expect(after.ghost_updates - before.ghost_updates == queries && after.ghost_exchanges == before.ghost_exchanges,
               what + ": " + std::to_string(after.ghost_updates - before.ghost_updates) + " updates and " +
                   std::to_string(after.ghost_exchanges - before.ghost_exchanges) + " exchanges in 3 small steps");
    }
    expect(after.ghost_exchanges > before.ghost_exchanges, what + ": the fourth step kept the layer");
    // A different radius chooses the layer afresh.
    compare(scene.s, moved, flags, 1.5f * r, what + ", another radius");
  }
  Scene scene;
  const tools::Owners owners = tools::partition(mesh.xyz, mesh.tris, size, tools::Partition::kSlab, seed);
  expect(create(device, tools::part_of(mesh.xyz, mesh.tris, owners, rank), MINKQ_SCENE_VT, scene) == MINKQ_SUCCESS,
         "skin errors: create");
  expect_error(minkq_mpi_scene_set_skin(scene.s, rank == 0 ? -1.0 : 1.0), MINKQ_ERROR_INVALID_ARGUMENT,
               "rank 0: the skin -1", "a negative skin on rank 0");
  if (size > 1)
    expect_error(minkq_mpi_scene_set_skin(scene.s, rank == size - 1 ? 2.0 : 1.0), MINKQ_ERROR_INVALID_ARGUMENT,
                 "the skins differ between the ranks", "skins that differ");
  expect_error(minkq_mpi_scene_set_skin(scene.s, NAN), MINKQ_ERROR_NON_FINITE, "not finite", "a NaN skin");
}

// ---- Errors --------------------------------------------------------------------------------
void error_cases(minkq_device* device) {
  const ref::Mesh mesh = ref::twisted_sheet(12, 1.0);
  const tools::Owners owners = tools::partition(mesh.xyz, mesh.tris, size, tools::Partition::kSlab, seed);
  const tools::Part good = tools::part_of(mesh.xyz, mesh.tris, owners, rank, true);
  const int last = size - 1;
  const uint32_t flags = MINKQ_SCENE_VT | MINKQ_SCENE_EE | MINKQ_SCENE_DROP_INCIDENT;
  {  // a non-finite vertex on the last rank only
    tools::Part bad = good;
    if (rank == last) bad.xyz[3 * 2 + 1] = NAN;
    Scene s;
    expect_error(create(device, bad, flags, s), MINKQ_ERROR_NON_FINITE, "rank " + std::to_string(last) + ": vertex 2",
                 "NaN on the last rank");
    expect(s.s == nullptr, "a failed create returned a scene");
  }
  {  // an index out of range on rank 0
    tools::Part bad = good;
    if (rank == 0) bad.tris[1] = int32_t(bad.vertex_count());
    Scene s;
    expect_error(create(device, bad, flags, s), MINKQ_ERROR_INDEX_OUT_OF_RANGE, "rank 0: triangle 0 references",
                 "index out of range");
  }
  if (size > 1) {  // the last rank claims one of its copies: a vertex owned twice
    tools::Part bad = good;
    int changed = 0;
    for (size_t v = 0; v < bad.vertex_count() && !changed && rank == last; ++v)
      if (!bad.vertex_owned[v]) bad.vertex_owned[v] = 1, changed = 1;
    MPI_Allreduce(MPI_IN_PLACE, &changed, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    expect(changed, "the last rank has no copy to claim");
    Scene s;
    if (changed)
      expect_error(create(device, bad, flags, s), MINKQ_ERROR_INVALID_ARGUMENT,
                   "and by rank " + std::to_string(last), "a vertex owned twice");
  }
  {  // every holder of global vertex 0 gives it up: a vertex owned by none
    tools::Part bad = good;
    for (size_t v = 0; v < bad.vertex_count(); ++v)
      if (bad.vertex_ids[v] == 0) bad.vertex_owned[v] = 0;
    Scene s;
    expect_error(create(device, bad, flags, s), MINKQ_ERROR_INVALID_ARGUMENT, "global vertex 0 has a copy on",
                 "a vertex owned by none");
  }
  if (size > 1) {  // the last rank's copy of a triangle with another vertex than its owner's
    tools::Part bad = good;
    int changed = 0;
    for (size_t t = 0; t < bad.triangle_count() && !changed && rank == last; ++t)
      if (!bad.triangle_owned[t])
        for (int32_t v = 0; v < int32_t(bad.vertex_count()) && !changed; ++v)
          if (v != bad.tris[3 * t] && v != bad.tris[3 * t + 1] && v != bad.tris[3 * t + 2]) bad.tris[3 * t] = v, changed = 1;
    MPI_Allreduce(MPI_IN_PLACE, &changed, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    expect(changed, "the last rank has no triangle copy to alter");
    Scene s;
    if (changed)
      expect_error(create(device, bad, flags, s), MINKQ_ERROR_INVALID_ARGUMENT, "on its owner",
                   "a triangle copy with other vertices");
  }
  if (size > 1) {  // flags that differ between ranks
    Scene s;
    expect_error(create(device, good, rank == last ? uint32_t(MINKQ_SCENE_VT) : flags, s), MINKQ_ERROR_INVALID_ARGUMENT,
                 "differ between the ranks", "flags differ");
  }
  // A scene whose moves fail keeps its state; a bad query fails everywhere.
  Scene scene;
  expect(create(device, good, flags, scene) == MINKQ_SUCCESS, std::string("create: ") + minkq_mpi_last_error_message());
  if (!scene.s) return;
  const float r = float(0.5 * ref::mean_edge_length(mesh));
  compare(scene.s, mesh, flags, r, "before failed moves");
  std::vector<float> xyz = tools::local_positions(mesh.xyz, good);
  for (float& x : xyz) x *= 2;
  if (rank == last) xyz[3 * 1] = INFINITY;
  expect_error(minkq_mpi_scene_refit(scene.s, host(xyz)), MINKQ_ERROR_NON_FINITE,
               "rank " + std::to_string(last) + ": vertex 1", "a refit with an infinity on the last rank");
  std::vector<float> fewer = tools::local_positions(mesh.xyz, good);
  if (rank == 0) fewer.resize(fewer.size() - 3);
  expect_error(minkq_mpi_scene_rebuild(scene.s, host(fewer)), MINKQ_ERROR_INVALID_ARGUMENT,
               "rank 0: minkq_mpi_scene_rebuild with", "a rebuild with a vertex short on rank 0");
  if (minkq_device_backend(device) == MINKQ_BACKEND_CPU) {
    minkq_buffer on_device = host(fewer.size() == xyz.size() ? fewer : xyz);
    on_device.memory = rank == 0 ? MINKQ_MEMORY_DEVICE : MINKQ_MEMORY_HOST;
    expect_error(minkq_mpi_scene_refit(scene.s, on_device), MINKQ_ERROR_INVALID_ARGUMENT,
                 "rank 0: vertices is device memory (MINKQ_MEMORY_DEVICE) but the rank's device",
                 "device memory on a CPU rank");
  }
  compare(scene.s, mesh, flags, r, "after failed moves");
  Result result;
  const minkq_query_desc digest{MINKQ_QUERY_EE, MINKQ_MODE_BOX, MINKQ_QUERY_DIGEST, r};
  expect_error(minkq_mpi_scene_query(scene.s, &digest, result.r), MINKQ_ERROR_UNSUPPORTED, "MINKQ_QUERY_DIGEST",
               "a digest query");
  const minkq_query_desc sphere{MINKQ_QUERY_EE, MINKQ_MODE_SPHERE, 0, r};
  expect_error(minkq_mpi_scene_query(scene.s, &sphere, result.r), MINKQ_ERROR_INVALID_ARGUMENT, "sphere",
               "an EE sphere query");
  const minkq_query_desc negative{MINKQ_QUERY_VT, MINKQ_MODE_BOX, 0, rank == 0 ? -1.0f : r};
  expect_error(minkq_mpi_scene_query(scene.s, &negative, result.r), MINKQ_ERROR_INVALID_ARGUMENT,
               "rank 0: query->radius is negative", "a negative radius on rank 0");
  expect(minkq_mpi_result_count(result.r) == 0, "a failed query left pairs");
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  if (argc != 2) {
    if (rank == 0) std::fprintf(stderr, "usage: mpirun -n K test_mpi MESH_DIR\n");
    MPI_Finalize();
    return 2;
  }
  const char* fixed = std::getenv("MINKQ_TEST_SEED");
  seed = fixed ? std::strtoull(fixed, nullptr, 10) : std::random_device{}();
  MPI_Bcast(&seed, 1, MPI_UINT64_T, 0, MPI_COMM_WORLD);
  if (rank == 0) std::printf("test_mpi: %d ranks, seed %" PRIu64 " (MINKQ_TEST_SEED replays it)\n", size, seed);
  try {
    // MINKQ_TEST_DEVICE=cuda runs the ranks' trees on the GPU (ctest's gpu-labelled run),
    // against the CPU's single-process pairs; it skips (77) where there is no GPU.
    const char* spec = std::getenv("MINKQ_TEST_DEVICE");
    const std::string device_spec = spec && *spec ? spec : "cpu";
    if (device_spec.rfind("cuda", 0) == 0 && minkq_cuda_device_count() == 0) {
      if (rank == 0) std::printf("test_mpi: skipped: MINKQ_TEST_DEVICE=%s but no CUDA device\n", spec);
      MPI_Finalize();
      return 77;
    }
    minkq::cxx::Device cpu_device = minkq::cxx::open_device("cpu");
    cpu = cpu_device.get();
    minkq::cxx::Device device = minkq::cxx::open_device(device_spec);
    if (rank == 0) std::printf("test_mpi: the ranks' device: %s\n", minkq_device_name(device.get()));
    const std::string dir = argv[1];
    mesh_cases(device.get(), "twisted sheet 24", ref::twisted_sheet(24, 2.0), 0.5, true);
    for (double scale : {1e-3, 1e3}) {
      ref::Mesh m = ref::twisted_sheet(16, 2.0);
      ref::transform(m, scale, 3 * scale);
      mesh_cases(device.get(), "twisted sheet 16 x" + std::to_string(scale), m, 0.5, false);
    }
    mesh_cases(device.get(), "stacked sheets", ref::stacked_sheets(12, 3, 0.02), 1.0, false);
    mesh_cases(device.get(), "random soup", ref::random_soup(300, seed, 1.0), 0.3, false);
    mesh_cases(device.get(), "bear.obj", ref::load_mesh(dir + "/newton/bear.obj"), 0.5, false);
    skin_cases(device.get());
    error_cases(device.get());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "FAIL rank %d: %s\n", rank, e.what());
    MPI_Abort(MPI_COMM_WORLD, 3);
  }
  int total = 0;
  MPI_Allreduce(&failures, &total, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
  if (rank == 0) std::printf("test_mpi: %d checks on rank 0, %d failures over %d ranks\n", checks, total, size);
  MPI_Finalize();
  return total ? 1 : 0;
}
