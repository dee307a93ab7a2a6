// minkq_mpi_bench: what distributing a mesh over MPI ranks costs, against the single-process
// scene in the same run (bench/mpi/run.sh runs it under mpirun -n 1, 2 and 4):
//   mpirun -n K minkq_mpi_bench [--size N | --mesh PATH] [--steps S] [--radius-factor F]
//                               [--motion M] [--partitions slab,morton,random] [--out FILE]
// The scene: a twisted sheet of N x N vertices (default 301) that twists further each step,
// or a mesh file whose vertices move by a growing wave; either way a vertex moves at most
// M x r a step (default 0.2), r = F x mean edge (0.25). For each partition, without a skin and
// with one of 2 r: create, then S steps of refit + VT + EE (box nodes, leaf-exact: the
// contacts) + handing the pairs back (a gather to rank 0). Each phase's time is the slowest
// rank's, the median over the steps; the query's phases come from minkq_mpi_rank_info (reach
// boxes, ghost layer, local trees, local query), with the bytes each rank sent. The union of
// the pairs is checked against the single-process query on the last step; the single-process
// scene's steps are timed on rank 0 alone, the other ranks asleep, so both use the same cores.
// Rank 0 writes a markdown table.
#include <mpi.h>

#include <algorithm>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "distributed.h"
#include "mpi_common.h"
#include "minkq.hpp"
#include "minkq_mpi.h"
#include "minkq_reference.h"

namespace {

namespace ref = minkq::reference;
namespace tools = minkq::mpi_tools;
using minkq::cxx::check;
using namespace minkq::mpi_bench;

int rank = 0, size = 1;

struct Row {
  std::string partition;
  double skin = 0, create = 0, refit = 0, reach = 0, ghosts = 0, trees = 0, query = 0, handback = 0, single = 0;
  double kb = 0, ghost_vertices = 0, ghost_edges = 0, neighbours = 0;  // per rank and step / averages
  uint64_t exchanges = 0, builds = 0, refits = 0;
  bool equal = true;
};

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  const Options opt = parse_options(argc, argv, Options{}, false);
  const int steps = opt.steps;
  minkq::cxx::Device device = minkq::cxx::open_device("cpu");
  const Scene sc = make_scene(opt);
  const Motion& motion = sc.motion;
  const ref::Mesh& first = sc.first;
  const float r = sc.r;
  const uint32_t flags = MINKQ_SCENE_VT | MINKQ_SCENE_EE | MINKQ_SCENE_DROP_INCIDENT;
  const minkq_query_desc queries[2] = {{MINKQ_QUERY_VT, MINKQ_MODE_BOX, MINKQ_QUERY_LEAF_EXACT, r},
                                       {MINKQ_QUERY_EE, MINKQ_MODE_BOX, MINKQ_QUERY_LEAF_EXACT, r}};

  // The single-process baseline: rank 0 alone, the others waiting.
  double single_ms = 0;
  std::vector<tools::GlobalPairs> single_pairs(2);  // VT, EE at the last step
  if (rank == 0) {
    minkq::cxx::Scene scene = minkq::cxx::new_mesh_scene(device.get(), first.xyz.data(), first.vertex_count(),
                                                         first.tris.data(), first.triangle_count(), flags);
    minkq::cxx::Result result = minkq::cxx::new_result();
    std::vector<double> times;
    for (int step = 1; step <= steps; ++step) {
      const ref::Mesh m = motion.at(step);
      const double t0 = now_ms();
      check(minkq_scene_refit(scene.get(), minkq::cxx::host_buffer(m.xyz.data(), m.vertex_count())), "refit");
      for (int q = 0; q < 2; ++q) {
        check(minkq_scene_query_result(scene.get(), &queries[q], result.get()), "query");
        if (step == steps) single_pairs[q] = result_pairs(result.get());
      }
      times.push_back(now_ms() - t0);
    }
    single_ms = median(times);
  }
  wait_for_rank_0();

  std::vector<Row> rows;
  minkq_mpi_result* result = nullptr;
  mpi_check(minkq_mpi_result_create(&result), "minkq_mpi_result_create");
  for (const tools::Partition kind : partition_list(opt.partitions)) {
    const tools::Owners owners = tools::partition(first.xyz, first.tris, size, kind, 1);
    const tools::Part part = tools::part_of(first.xyz, first.tris, owners, rank);
    const minkq_mpi_scene_desc desc = tools::desc_of(part, flags);
    for (double skin : {0.0, 2.0 * r}) {
      minkq_mpi_scene* scene = nullptr;
      MPI_Barrier(MPI_COMM_WORLD);
      double t0 = now_ms();
      mpi_check(minkq_mpi_scene_create(MPI_COMM_WORLD, device.get(), &desc, &scene), "minkq_mpi_scene_create");
      Row row;
      row.partition = tools::partition_name(kind), row.skin = skin, row.create = slowest(now_ms() - t0);
      row.single = single_ms;
      mpi_check(minkq_mpi_scene_set_skin(scene, skin), "minkq_mpi_scene_set_skin");
      std::vector<double> refit, reach, ghosts, trees, query, handback, kb;
      for (int step = 1; step <= steps; ++step) {
        const std::vector<float> xyz = tools::local_positions(motion.at(step).xyz, part);
        minkq_mpi_rank_info info{};
        minkq_mpi_scene_rank_info(scene, &info);
        const uint64_t bytes_before = info.bytes_sent;
        MPI_Barrier(MPI_COMM_WORLD);
        t0 = now_ms();
        mpi_check(minkq_mpi_scene_refit(scene, minkq_buffer{xyz.data(), 0, part.vertex_count(), MINKQ_MEMORY_HOST}),
                  "refit");
        refit.push_back(slowest(now_ms() - t0));
        double phases[5] = {0, 0, 0, 0, 0};  // reach, ghosts, trees, query, hand-back: this step's slowest
        for (int q = 0; q < 2; ++q) {
          MPI_Barrier(MPI_COMM_WORLD);
          mpi_check(minkq_mpi_scene_query(scene, &queries[q], result), "query");
          minkq_mpi_scene_rank_info(scene, &info);
          phases[0] += slowest(info.last_reach_ms), phases[1] += slowest(info.last_ghost_ms);
          phases[2] += slowest(info.last_trees_ms), phases[3] += slowest(info.last_query_ms);
          MPI_Barrier(MPI_COMM_WORLD);
          t0 = now_ms();
          const tools::GlobalPairs all = tools::gather_pairs(MPI_COMM_WORLD, result);
          phases[4] += slowest(now_ms() - t0);
          if (step == steps && rank == 0) row.equal &= all == single_pairs[q];
        }
        reach.push_back(phases[0]), ghosts.push_back(phases[1]), trees.push_back(phases[2]);
        query.push_back(phases[3]), handback.push_back(phases[4]);
        kb.push_back(slowest(double(info.bytes_sent - bytes_before) / 1024.0));
      }
      row.refit = median(refit), row.reach = median(reach), row.ghosts = median(ghosts), row.trees = median(trees);
      row.query = median(query), row.handback = median(handback), row.kb = median(kb);
      minkq_mpi_rank_info info{};
      minkq_mpi_scene_rank_info(scene, &info);
      double mine[3] = {double(info.ghost_vertices) / double(std::max<uint64_t>(info.owned_vertices, 1)),
                        double(info.ghost_edges) / double(std::max<uint64_t>(info.owned_edges, 1)),
                        double(info.neighbours)};
      double sum[3];
      MPI_Allreduce(mine, sum, 3, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
      row.ghost_vertices = sum[0] / size, row.ghost_edges = sum[1] / size, row.neighbours = sum[2] / size;
      uint64_t counts[3] = {info.local_builds, info.local_refits, info.ghost_exchanges}, total[3];
      MPI_Allreduce(counts, total, 3, MPI_UINT64_T, MPI_SUM, MPI_COMM_WORLD);
      row.builds = total[0], row.refits = total[1], row.exchanges = total[2] / uint64_t(size);
      rows.push_back(row);
      minkq_mpi_scene_release(scene);
    }
  }
  minkq_mpi_result_release(result);

  int failed = 0;
  if (rank == 0) {
    std::ostringstream md;
    char line[640];
    std::snprintf(line, sizeof line,
                  "### %d rank%s: %s (%zu triangles), r = %.3g x mean edge, %d steps of at most %.2g r, "
                  "leaf-exact VT + EE\n\n",
                  size, size > 1 ? "s" : "", sc.name.c_str(), first.triangle_count(), opt.factor, steps, opt.motion);
    md << line;
    md << "| partition | skin | create ms | step ms | over one process | refit | reach boxes | ghost layer | local "
          "trees | local query | hand-back | KiB sent / rank / step | ghost vertices / owned | ghost edges / owned | "
          "neighbours | layers chosen | local builds / refits | = one process |\n"
          "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const Row& w : rows) {
      const double step = w.refit + w.reach + w.ghosts + w.trees + w.query + w.handback;
      std::snprintf(line, sizeof line,
                    "| %s | %s | %.1f | %.1f | %.2fx | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.1f | %.3f | %.3f | "
                    "%.1f | %" PRIu64 " | %" PRIu64 " / %" PRIu64 " | %s |\n",
                    w.partition.c_str(), w.skin > 0 ? "2 r" : "0", w.create, step, step / w.single, w.refit, w.reach,
                    w.ghosts, w.trees, w.query, w.handback, w.kb, w.ghost_vertices, w.ghost_edges, w.neighbours,
                    w.exchanges, w.builds, w.refits, w.equal ? "yes" : "**NO**");
      md << line;
      failed |= !w.equal;
    }
    std::snprintf(line, sizeof line,
                  "\nOne process, the same scene and steps (refit + VT + EE): %.1f ms a step (median). Phase columns "
                  "in ms, VT and EE together.\n\n",
                  single_ms);
    md << line;
    std::fputs(md.str().c_str(), stdout);
    if (!opt.out.empty()) std::ofstream(opt.out, std::ios::app) << md.str();
  }
  MPI_Bcast(&failed, 1, MPI_INT, 0, MPI_COMM_WORLD);
  MPI_Finalize();
  return failed;
}
