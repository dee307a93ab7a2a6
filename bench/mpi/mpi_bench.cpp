// minkq_mpi_bench: what distributing a mesh over MPI ranks costs, against the single-process
// scene in the same run (bench/mpi/run.sh runs it under mpirun -n 1, 2 and 4):
//   mpirun -n K minkq_mpi_bench [--size N] [--steps S] [--radius-factor F] [--motion M] [--out FILE]
// A twisted sheet of N x N vertices (default 301) that twists further each step, so that its
// vertices move at most M x r a step (default 0.2), r = F x mean edge (0.25). For each
// partition (slab, morton, random), without a skin and with one of 2 r: create, then S steps
// of refit + VT + EE (box nodes, leaf-exact: the contacts), timing each phase on every rank
// (the step's time is the slowest rank's); the ghost layer (vertices and edges received, as a
// share of the rank's own), neighbours, how often the ghost layer was chosen afresh, and how
// often the local trees were refit or built. The union
// of the pairs is checked against the single-process query (rank 0) on the first and last
// steps; the single-process scene's steps are timed on rank 0 alone, with the other ranks
// waiting, so both use the same cores. Rank 0 writes a markdown table.
#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
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

int rank = 0, size = 1;

double now_ms() {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch()).count();
}
double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}
// The slowest rank's time of a phase.
double slowest(double ms) {
  double all = 0;
  MPI_Allreduce(&ms, &all, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  return all;
}
void mpi_check(minkq_status s, const char* call) {
  if (s != MINKQ_SUCCESS) {
    std::fprintf(stderr, "rank %d: %s failed: %s\n", rank, call, minkq_mpi_last_error_message());
    MPI_Abort(MPI_COMM_WORLD, 3);
  }
}

// The sheet at step k: twisted further about its long axis as k grows, by `turns` a step.
double turns_per_step = 0.0;
ref::Mesh sheet_at(int n, int step) { return ref::twisted_sheet(n, 3.0 + turns_per_step * step); }

// The farthest a vertex moves on an axis from sheet a to sheet b.
double displacement(const ref::Mesh& a, const ref::Mesh& b) {
  double d = 0;
  for (size_t i = 0; i < a.xyz.size(); ++i) d = std::max(d, std::fabs(double(a.xyz[i]) - double(b.xyz[i])));
  return d;
}

struct Row {
  std::string partition;
  double skin;
  double create_ms, refit_ms, vt_ms, ee_ms, single_step_ms;
  double ghost_vertices, ghost_edges, neighbours;  // averages over ranks
  uint64_t exchanges, builds, refits, vt_pairs, ee_pairs;
  bool equal;
};

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  int n = 301, steps = 10;
  double factor = 0.25, motion = 0.2;
  std::string out;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--size") n = std::atoi(argv[i + 1]);
    else if (a == "--steps") steps = std::atoi(argv[i + 1]);
    else if (a == "--radius-factor") factor = std::atof(argv[i + 1]);
    else if (a == "--motion") motion = std::atof(argv[i + 1]);
    else if (a == "--out") out = argv[i + 1];
  }
  minkq::cxx::Device device = minkq::cxx::open_device("cpu");
  const ref::Mesh first = sheet_at(n, 0);
  const float r = float(factor * ref::mean_edge_length(first));
  // Twist per step: linear enough over a small twist to scale one probe's displacement.
  turns_per_step = 1e-3;
  turns_per_step *= motion * r / displacement(first, sheet_at(n, 1));
  const uint32_t flags = MINKQ_SCENE_VT | MINKQ_SCENE_EE | MINKQ_SCENE_DROP_INCIDENT;
  const minkq_query_desc vt{MINKQ_QUERY_VT, MINKQ_MODE_BOX, MINKQ_QUERY_LEAF_EXACT, r};
  const minkq_query_desc ee{MINKQ_QUERY_EE, MINKQ_MODE_BOX, MINKQ_QUERY_LEAF_EXACT, r};

  // The single-process baseline: rank 0 alone, the others waiting.
  double single_ms = 0;
  std::vector<tools::GlobalPairs> single_pairs(2);  // VT, EE at the last step
  if (rank == 0) {
    minkq::cxx::Scene scene = minkq::cxx::new_mesh_scene(device.get(), first.xyz.data(), first.vertex_count(),
                                                         first.tris.data(), first.triangle_count(), flags);
    minkq::cxx::Result result = minkq::cxx::new_result();
    std::vector<double> times;
    for (int step = 1; step <= steps; ++step) {
      const ref::Mesh m = sheet_at(n, step);
      const double t0 = now_ms();
      check(minkq_scene_refit(scene.get(), minkq::cxx::host_buffer(m.xyz.data(), m.vertex_count())), "refit");
      for (int q = 0; q < 2; ++q) {
        const minkq_query_desc d = q == 0 ? vt : ee;
        check(minkq_scene_query_result(scene.get(), &d, result.get()), "query");
        if (step == steps) {
          const int32_t* p = minkq_result_pairs(result.get());
          for (size_t i = 0; i < minkq_result_count(result.get()); ++i) single_pairs[q].push_back({p[2 * i], p[2 * i + 1]});
          std::sort(single_pairs[q].begin(), single_pairs[q].end());
        }
      }
      times.push_back(now_ms() - t0);
    }
    single_ms = median(times);
  }
  MPI_Barrier(MPI_COMM_WORLD);

  std::vector<Row> rows;
  minkq_mpi_result* result = nullptr;
  mpi_check(minkq_mpi_result_create(&result), "minkq_mpi_result_create");
  for (tools::Partition kind : {tools::Partition::kSlab, tools::Partition::kMorton, tools::Partition::kRandom})
   for (double skin : {0.0, 2.0 * r}) {
    const tools::Owners owners = tools::partition(first.xyz, first.tris, size, kind, 1);
    const tools::Part part = tools::part_of(first.xyz, first.tris, owners, rank);
    const minkq_mpi_scene_desc desc = tools::desc_of(part, flags);
    minkq_mpi_scene* scene = nullptr;
    MPI_Barrier(MPI_COMM_WORLD);
    double t0 = now_ms();
    mpi_check(minkq_mpi_scene_create(MPI_COMM_WORLD, device.get(), &desc, &scene), "minkq_mpi_scene_create");
    Row row{tools::partition_name(kind), skin, slowest(now_ms() - t0), 0, 0, 0, single_ms, 0, 0, 0, 0, 0, 0, 0, 0, true};
    mpi_check(minkq_mpi_scene_set_skin(scene, skin), "minkq_mpi_scene_set_skin");
    std::vector<double> refit, vts, ees;
    std::vector<float> xyz(part.xyz.size());
    for (int step = 1; step <= steps; ++step) {
      const ref::Mesh m = sheet_at(n, step);
      for (size_t v = 0; v < part.vertex_count(); ++v)
        std::memcpy(&xyz[3 * v], &m.xyz[3 * size_t(part.vertex_ids[v])], 12);
      MPI_Barrier(MPI_COMM_WORLD);
      t0 = now_ms();
      mpi_check(minkq_mpi_scene_refit(scene, minkq_buffer{xyz.data(), 0, part.vertex_count(), MINKQ_MEMORY_HOST}),
                "refit");
      refit.push_back(slowest(now_ms() - t0));
      for (int q = 0; q < 2; ++q) {
        MPI_Barrier(MPI_COMM_WORLD);
        t0 = now_ms();
        mpi_check(minkq_mpi_scene_query(scene, q == 0 ? &vt : &ee, result), "query");
        (q == 0 ? vts : ees).push_back(slowest(now_ms() - t0));
        if (step == steps) {
          const tools::GlobalPairs all = tools::gather_pairs(MPI_COMM_WORLD, result);
          if (rank == 0) row.equal &= all == single_pairs[q];
          (q == 0 ? row.vt_pairs : row.ee_pairs) = all.size();
        }
      }
    }
    row.refit_ms = median(refit), row.vt_ms = median(vts), row.ee_ms = median(ees);
    minkq_mpi_rank_info info{};
    minkq_mpi_scene_rank_info(scene, &info);
    double mine[3] = {double(info.ghost_vertices) / double(std::max<uint64_t>(info.owned_vertices, 1)),
                      double(info.ghost_edges) / double(std::max<uint64_t>(info.owned_edges, 1)), double(info.neighbours)};
    double sum[3];
    MPI_Allreduce(mine, sum, 3, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
    row.ghost_vertices = sum[0] / size, row.ghost_edges = sum[1] / size, row.neighbours = sum[2] / size;
    uint64_t counts[3] = {info.local_builds, info.local_refits, info.ghost_exchanges}, total[3];
    MPI_Allreduce(counts, total, 3, MPI_UINT64_T, MPI_SUM, MPI_COMM_WORLD);
    row.builds = total[0], row.refits = total[1], row.exchanges = total[2] / uint64_t(size);
    rows.push_back(row);
    minkq_mpi_scene_release(scene);
  }
  minkq_mpi_result_release(result);

  int failed = 0;
  if (rank == 0) {
    std::ostringstream md;
    char line[512];
    std::snprintf(line, sizeof line,
                  "### %d rank%s: twisted sheet %dx%d (%zu triangles), r = %.3g x mean edge, %d steps of %.2g r, leaf-exact VT + EE\n\n",
                  size, size > 1 ? "s" : "", n, n, first.triangle_count(), factor, steps, motion);
    md << line;
    md << "| partition | skin | create ms | step ms (refit + VT + EE) | over one process | refit ms | VT ms | EE ms | "
          "ghost vertices / owned | ghost edges / owned | neighbours | layers chosen | local builds / refits | VT pairs | "
          "EE pairs | = one process |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const Row& w : rows) {
      const double step = w.refit_ms + w.vt_ms + w.ee_ms;
      std::snprintf(line, sizeof line,
                    "| %s | %s | %.1f | %.1f | %.2fx | %.2f | %.1f | %.1f | %.3f | %.3f | %.1f | %" PRIu64 " | %" PRIu64
                    " / %" PRIu64 " | %" PRIu64 " | %" PRIu64 " | %s |\n",
                    w.partition.c_str(), w.skin > 0 ? "2 r" : "0", w.create_ms, step, step / w.single_step_ms,
                    w.refit_ms, w.vt_ms, w.ee_ms, w.ghost_vertices, w.ghost_edges, w.neighbours, w.exchanges, w.builds,
                    w.refits, w.vt_pairs, w.ee_pairs,
                    w.equal ? "yes" : "**NO**");
      md << line;
      failed |= !w.equal;
    }
    std::snprintf(line, sizeof line, "\nOne process, the same scene and steps: %.1f ms a step (median).\n\n", single_ms);
    md << line;
    std::fputs(md.str().c_str(), stdout);
    if (!out.empty()) std::ofstream(out, std::ios::app) << md.str();
  }
  MPI_Bcast(&failed, 1, MPI_INT, 0, MPI_COMM_WORLD);
  MPI_Finalize();
  return failed;
}
