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
#include <chrono>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
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
// The slowest rank's value.
double slowest(double ms) {
  double all = 0;
  MPI_Allreduce(&ms, &all, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  return all;
}
// The other ranks wait for rank 0's one-process timing asleep (polling every millisecond), not
// in a barrier that spins on the cores rank 0 is timing with.
void wait_for_rank_0() {
  int token = 0;
  if (rank == 0) {
    for (int p = 1; p < size; ++p) MPI_Send(&token, 1, MPI_INT, p, 99, MPI_COMM_WORLD);
    return;
  }
  MPI_Request request;
  MPI_Irecv(&token, 1, MPI_INT, 0, 99, MPI_COMM_WORLD, &request);
  for (int done = 0; !done;) {
    MPI_Test(&request, &done, MPI_STATUS_IGNORE);
    if (!done) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
}

void mpi_check(minkq_status s, const char* call) {
  if (s != MINKQ_SUCCESS) {
    std::fprintf(stderr, "rank %d: %s failed: %s\n", rank, call, minkq_mpi_last_error_message());
    MPI_Abort(MPI_COMM_WORLD, 3);
  }
}

// The scene at step k: the sheet twisted further, or the mesh moved by a wave.
struct Motion {
  int n = 0;          // sheet size, or 0 for the mesh
  ref::Mesh mesh;     // the mesh at step 0
  double per_step = 0;
  ref::Mesh at(int step) const {
    if (n) return ref::twisted_sheet(n, 3.0 + per_step * step);
    ref::Mesh m = mesh;
    for (size_t v = 0; v < m.vertex_count(); ++v)
      m.xyz[3 * v + 2] += float(per_step * step * std::sin(0.37 * double(v)));
    return m;
  }
};
double displacement(const ref::Mesh& a, const ref::Mesh& b) {
  double d = 0;
  for (size_t i = 0; i < a.xyz.size(); ++i) d = std::max(d, std::fabs(double(a.xyz[i]) - double(b.xyz[i])));
  return d;
}

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
  int n = 301, steps = 10;
  double factor = 0.25, motion_factor = 0.2;
  std::string out, mesh_path, partitions = "slab,morton,random";
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string a = argv[i];
    if (a == "--size") n = std::atoi(argv[i + 1]);
    else if (a == "--mesh") mesh_path = argv[i + 1];
    else if (a == "--steps") steps = std::atoi(argv[i + 1]);
    else if (a == "--radius-factor") factor = std::atof(argv[i + 1]);
    else if (a == "--motion") motion_factor = std::atof(argv[i + 1]);
    else if (a == "--partitions") partitions = argv[i + 1];
    else if (a == "--out") out = argv[i + 1];
  }
  minkq::cxx::Device device = minkq::cxx::open_device("cpu");
  Motion motion;
  if (mesh_path.empty()) motion.n = n;
  else motion.mesh = ref::load_mesh(mesh_path);
  const ref::Mesh first = motion.at(0);
  const float r = float(factor * ref::mean_edge_length(first));
  // Scale a probe step so that a step moves a vertex M x r at most.
  motion.per_step = motion.n ? 1e-3 : double(r);
  motion.per_step *= motion_factor * r / displacement(first, motion.at(1));
  const std::string scene_name = motion.n ? "twisted sheet " + std::to_string(n) + "x" + std::to_string(n)
                                          : mesh_path.substr(mesh_path.find_last_of('/') + 1);
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
  wait_for_rank_0();

  std::vector<Row> rows;
  minkq_mpi_result* result = nullptr;
  mpi_check(minkq_mpi_result_create(&result), "minkq_mpi_result_create");
  for (size_t at = 0; at < partitions.size();) {
    const size_t comma = std::min(partitions.find(',', at), partitions.size());
    const tools::Partition kind = tools::parse_partition(partitions.substr(at, comma - at));
    at = comma + 1;
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
      std::vector<float> xyz(part.xyz.size());
      for (int step = 1; step <= steps; ++step) {
        const ref::Mesh m = motion.at(step);
        for (size_t v = 0; v < part.vertex_count(); ++v)
          std::memcpy(&xyz[3 * v], &m.xyz[3 * size_t(part.vertex_ids[v])], 12);
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
                  size, size > 1 ? "s" : "", scene_name.c_str(), first.triangle_count(), factor, steps, motion_factor);
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
    if (!out.empty()) std::ofstream(out, std::ios::app) << md.str();
  }
  MPI_Bcast(&failed, 1, MPI_INT, 0, MPI_COMM_WORLD);
  MPI_Finalize();
  return failed;
}
