// arborx_mpi_bench: minkq_mpi beside ArborX's DistributedTree (issue 28), the same mesh split the
// same way over the same ranks, threads and steps (bench/peers/arborx/run_mpi.sh runs it under mpirun):
//   mpirun -n K arborx_mpi_bench [--size N | --mesh PATH] [--steps S] [--radius-factor F]
//                                [--motion M] [--partitions slab,morton,random] [--threads T]
//                                [--out FILE]
// The scene moves as minkq_mpi_bench's does (bench/mpi/mpi_common.h): a twisted sheet of N x N
// vertices twisting further, or a mesh under a growing wave, at most M x r a step, r = F x mean
// edge. Each rank owns the triangles and vertices the partition gives it (mpi/tools/partition.h)
// and each edge of the global numbering goes with its lowest-id triangle. Every step runs, in
// turn, the three contestants, each storing VT and EE box candidates (minkq's MINKQ_MODE_BOX,
// incident pairs dropped) on the ranks, in global ids:
//   - minkq refit: minkq_mpi_scene_refit + VT + EE (local trees refit, ghost layer kept or chosen
//     afresh: what a simulator's step runs);
//   - minkq rebuild: minkq_mpi_scene_rebuild + VT + EE (local trees built afresh);
//   - ArborX: a DistributedTree over each rank's owned triangles and one over its owned edges
//     (ArborX has no refit), then the owned vertices' boxes grown by r against the first and the
//     owned edges' grown boxes against the second. ArborX sends each query to every rank whose
//     bounds it meets, tests it there against the rank's tree (the incident and e < f filters run
//     there too) and brings the results back to the query's rank. Its query boxes are rounded
//     to decide exactly as minkq's float box test (bench/peers/arborx/arborx_peer.h), so the sets are
//     equal pair for pair; that is checked on the last step against the single-process minkq
//     scene, for both contestants.
// Each phase's time is the slowest rank's, the median over the steps; the contestants' order
// turns from step to step. Rank 0 writes a markdown table; exit 1 when a set differs. Both
// libraries run T threads per rank (default: the cores / K, at least 1).
#include <mpi.h>

#include <ArborX_DistributedTree.hpp>

#include <tbb/global_control.h>

#include <algorithm>
#include <chrono>
#include <cinttypes>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "arborx_peer.h"
#include "distributed.h"
#include "minkq.hpp"
#include "mpi_common.h"

namespace {

namespace tools = minkq::mpi_tools;
using namespace minkq::mpi_bench;
using peer::AxBox;
using peer::AxPoint;
using peer::AxValue;
using peer::Borrowed;
using peer::Exec;
using peer::Mem;
using peer::View;
using GlobalPairs = tools::GlobalPairs;
using DTree = ArborX::DistributedTree<Mem, AxValue>;

int rank = 0, size = 1;

// What a query carries to the ranks it is sent to: the query element's global id (and for an
// edge its vertices' ids, for the shared-vertex filter).
struct VtKey {
  int64_t v;
};
struct EeKey {
  int64_t e, a, b;
};
using VtPredicate = decltype(ArborX::attach(ArborX::intersects(AxBox{}), VtKey{}));
using EePredicate = decltype(ArborX::attach(ArborX::intersects(AxBox{}), EeKey{}));

// Run on the rank that owns the triangle or edge met: drop incident pairs, keep e < f, and give
// the element's global id back to the query's rank.
struct VtRemote {
  Borrowed<int64_t> tri_ids, corner_ids;  // 1 and 3 per owned triangle
  template <class Query, class Out>
  KOKKOS_FUNCTION void operator()(const Query& q, const AxValue& t, const Out& out) const {
    const int64_t v = ArborX::getData(q).v;
    const int64_t* c = &corner_ids(3 * size_t(t.index));
    if (c[0] != v && c[1] != v && c[2] != v) out(tri_ids(t.index));
  }
};
struct EeRemote {
  Borrowed<int64_t> edge_ids, end_ids;  // 1 and 2 per owned edge
  template <class Query, class Out>
  KOKKOS_FUNCTION void operator()(const Query& q, const AxValue& f, const Out& out) const {
    const EeKey k = ArborX::getData(q);
    const int64_t id = edge_ids(f.index), a = end_ids(2 * size_t(f.index)), b = end_ids(2 * size_t(f.index) + 1);
    if (id > k.e && a != k.a && a != k.b && b != k.a && b != k.b) out(id);
  }
};

// One rank's share for ArborX: owned triangles and edges over the rank's local vertices, with
// their global ids, and the owned vertices.
struct ArborxPart {
  std::vector<peer::Tri> tris;
  std::vector<peer::Seg> edges;
  std::vector<int64_t> tri_ids, corner_ids, edge_ids, end_ids;
  std::vector<int32_t> owned_vertices;  // local indices
  std::vector<int64_t> owned_vertex_ids;
};
ArborxPart arborx_part(const tools::Part& part, const GlobalEdges& g, size_t global_vertices) {
  ArborxPart a;
  std::vector<int32_t> local(global_vertices, -1);
  for (size_t v = 0; v < part.vertex_count(); ++v) {
    local[size_t(part.vertex_ids[v])] = int32_t(v);
    if (part.vertex_owned[v]) a.owned_vertices.push_back(int32_t(v)), a.owned_vertex_ids.push_back(part.vertex_ids[v]);
  }
  for (size_t t = 0; t < part.triangle_count(); ++t) {
    if (!part.triangle_owned[t]) continue;
    a.tris.push_back({{part.tris[3 * t], part.tris[3 * t + 1], part.tris[3 * t + 2]}});
    a.tri_ids.push_back(part.triangle_ids[t]);
    for (int k = 0; k < 3; ++k) a.corner_ids.push_back(part.vertex_ids[size_t(part.tris[3 * t + size_t(k)])]);
  }
  for (size_t e = 0; e < g.owner.size(); ++e) {
    if (g.owner[e] != rank) continue;
    const int32_t u = g.edges[2 * e], w = g.edges[2 * e + 1];  // an owned triangle's corners: local here
    a.edges.push_back({{local[size_t(u)], local[size_t(w)]}});
    a.edge_ids.push_back(int64_t(e));
    a.end_ids.push_back(u), a.end_ids.push_back(w);
  }
  return a;
}
template <class T>
Borrowed<T> borrow(const std::vector<T>& v) {
  return Borrowed<T>(v.data(), v.size());
}

// ArborX's step at the rank's local positions xyz (3 floats a vertex, AxPoint's layout): both
// trees built, both queries run; returns the phase times (build VT tree, build EE tree, VT, EE),
// each this rank's; the CSR results stay in the views.
struct ArborxResults {
  View<int> vt_offsets{"vt offsets", 0}, ee_offsets{"ee offsets", 0};
  View<int64_t> vt_values{"vt values", 0}, ee_values{"ee values", 0};
};
std::vector<double> arborx_step(const Exec& space, const ArborxPart& a, std::vector<float>& xyz, float r,
                                ArborxResults& out) {
  const peer::AxMesh m{decltype(peer::AxMesh::points)(reinterpret_cast<AxPoint*>(xyz.data()), xyz.size() / 3),
                       borrow(a.tris), borrow(a.edges)};
  std::vector<double> ms;
  double t0 = now_ms();
  DTree tri_tree(MPI_COMM_WORLD, space, ArborX::Experimental::attach_indices<int>(peer::triangle_boxes(space, m)));
  ms.push_back(now_ms() - t0);
  t0 = now_ms();
  DTree edge_tree(MPI_COMM_WORLD, space, ArborX::Experimental::attach_indices<int>(peer::edge_boxes(space, m)));
  ms.push_back(now_ms() - t0);
  t0 = now_ms();
  View<VtPredicate> vt(Kokkos::view_alloc(space, Kokkos::WithoutInitializing, "vt queries"), a.owned_vertices.size());
  const Borrowed<int32_t> owned = borrow(a.owned_vertices);
  const Borrowed<int64_t> owned_ids = borrow(a.owned_vertex_ids);
  Kokkos::parallel_for(
      "vt queries", Kokkos::RangePolicy<Exec>(space, 0, vt.extent(0)), KOKKOS_LAMBDA(int i) {
        const AxPoint p = m.points(owned(i));
        vt(i) = ArborX::attach(ArborX::intersects(peer::grown<true>(p, p, r)), VtKey{owned_ids(i)});
      });
  tri_tree.query(space, vt, VtRemote{borrow(a.tri_ids), borrow(a.corner_ids)}, out.vt_values, out.vt_offsets);
  ms.push_back(now_ms() - t0);
  t0 = now_ms();
  View<EePredicate> ee(Kokkos::view_alloc(space, Kokkos::WithoutInitializing, "ee queries"), a.edges.size());
  const Borrowed<int64_t> edge_ids = borrow(a.edge_ids), end_ids = borrow(a.end_ids);
  Kokkos::parallel_for(
      "ee queries", Kokkos::RangePolicy<Exec>(space, 0, ee.extent(0)), KOKKOS_LAMBDA(int i) {
        const peer::Seg s = m.edges(i);
        const AxPoint &p = m.points(s.v[0]), &q = m.points(s.v[1]);
        ee(i) = ArborX::attach(ArborX::intersects(peer::grown<true>(peer::pmin(p, q), peer::pmax(p, q), r)),
                               EeKey{edge_ids(i), end_ids(2 * i), end_ids(2 * i + 1)});
      });
  edge_tree.query(space, ee, EeRemote{edge_ids, end_ids}, out.ee_values, out.ee_offsets);
  ms.push_back(now_ms() - t0);
  return ms;
}
// The CSR results as pairs (query id, value), gathered on rank 0.
GlobalPairs arborx_pairs(const View<int>& offsets, const View<int64_t>& values, const std::vector<int64_t>& query_ids) {
  std::vector<int64_t> flat;
  flat.reserve(2 * values.extent(0));
  for (size_t q = 0; q + 1 < offsets.extent(0); ++q)
    for (int j = offsets(q); j < offsets(q + 1); ++j) flat.push_back(query_ids[q]), flat.push_back(values(j));
  return tools::gather_pairs(MPI_COMM_WORLD, flat.data(), flat.size() / 2);
}

struct Row {
  std::string partition;
  double refit = 0, refit_vt = 0, refit_ee = 0, rebuild = 0, rebuild_vt = 0, rebuild_ee = 0;
  double ax_tri = 0, ax_edge = 0, ax_vt = 0, ax_ee = 0;
  uint64_t vt_pairs = 0, ee_pairs = 0;
  bool minkq_equal = true, arborx_equal = true;
};

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  Options defaults;
  defaults.steps = 5;
  const Options opt = parse_options(argc, argv, defaults, true);
  const int steps = opt.steps;
  const int threads = opt.threads > 0 ? opt.threads : std::max(1, int(std::thread::hardware_concurrency()) / size);
  int failed = 0;
  {
    Kokkos::ScopeGuard kokkos(Kokkos::InitializationSettings().set_num_threads(threads).set_disable_warnings(true));
    tbb::global_control tbb_threads(tbb::global_control::max_allowed_parallelism, size_t(threads));
    const Exec space;
    if (space.concurrency() != threads) {
      std::fprintf(stderr, "rank %d: Kokkos runs %d threads, not %d\n", rank, space.concurrency(), threads);
      MPI_Abort(MPI_COMM_WORLD, 2);
    }
    minkq::cxx::Device device = minkq::cxx::open_device("cpu");
    const Scene sc = make_scene(opt);
    const Motion& motion = sc.motion;
    const ref::Mesh& first = sc.first;
    const float r = sc.r;
    const uint32_t flags = MINKQ_SCENE_VT | MINKQ_SCENE_EE | MINKQ_SCENE_DROP_INCIDENT;
    const minkq_query_desc queries[2] = {{MINKQ_QUERY_VT, MINKQ_MODE_BOX, 0, r}, {MINKQ_QUERY_EE, MINKQ_MODE_BOX, 0, r}};

    // The reference: the single-process scene's box candidates at the last step, on rank 0.
    std::vector<GlobalPairs> single(2);
    if (rank == 0) {
      const ref::Mesh m = motion.at(steps);
      minkq::cxx::Scene scene = minkq::cxx::new_mesh_scene(device.get(), m.xyz.data(), m.vertex_count(),
                                                           m.tris.data(), m.triangle_count(), flags);
      minkq::cxx::Result result = minkq::cxx::new_result();
      for (int q = 0; q < 2; ++q) {
        minkq::cxx::check(minkq_scene_query_result(scene.get(), &queries[q], result.get()), "query");
        single[q] = result_pairs(result.get());
      }
    }
    wait_for_rank_0();

    std::vector<Row> rows;
    minkq_mpi_result* result = nullptr;
    mpi_check(minkq_mpi_result_create(&result), "minkq_mpi_result_create");
    for (const tools::Partition kind : partition_list(opt.partitions)) {
      const tools::Owners owners = tools::partition(first.xyz, first.tris, size, kind, 1);
      const tools::Part part = tools::part_of(first.xyz, first.tris, owners, rank);
      const ArborxPart apart = arborx_part(part, global_edges(first.tris, owners), first.vertex_count());
      const minkq_mpi_scene_desc desc = tools::desc_of(part, flags);
      minkq_mpi_scene* scene = nullptr;
      mpi_check(minkq_mpi_scene_create(MPI_COMM_WORLD, device.get(), &desc, &scene), "minkq_mpi_scene_create");
      Row row;
      row.partition = tools::partition_name(kind);
      std::vector<std::vector<double>> ms(10);  // the Row's phases, in its order
      ArborxResults ax;
      for (int step = 1; step <= steps; ++step) {
        std::vector<float> xyz = tools::local_positions(motion.at(step).xyz, part);
        const minkq_buffer positions{xyz.data(), 0, part.vertex_count(), MINKQ_MEMORY_HOST};
        // minkq: update (refit or rebuild), VT, EE; phases 0-2 and 3-5.
        // Before each contestant, a few idle milliseconds in which the other runtime's workers
        // (TBB's, libgomp's) go to sleep, as arborx_bench's --gap-ms.
        auto gap = [] { std::this_thread::sleep_for(std::chrono::milliseconds(5)); };
        auto minkq_step = [&](bool rebuild, size_t phase) {
          gap();
          MPI_Barrier(MPI_COMM_WORLD);
          double t0 = now_ms();
          mpi_check(rebuild ? minkq_mpi_scene_rebuild(scene, positions) : minkq_mpi_scene_refit(scene, positions),
                    rebuild ? "rebuild" : "refit");
          ms[phase].push_back(slowest(now_ms() - t0));
          for (int q = 0; q < 2; ++q) {
            MPI_Barrier(MPI_COMM_WORLD);
            t0 = now_ms();
            mpi_check(minkq_mpi_scene_query(scene, &queries[q], result), "query");
            ms[phase + 1 + size_t(q)].push_back(slowest(now_ms() - t0));
            if (step == steps && !rebuild) {
              const GlobalPairs all = tools::gather_pairs(MPI_COMM_WORLD, result);
              if (rank == 0) row.minkq_equal &= all == single[size_t(q)];
            }
          }
        };
        auto arborx = [&] {
          gap();
          MPI_Barrier(MPI_COMM_WORLD);
          const std::vector<double> t = arborx_step(space, apart, xyz, r, ax);
          for (size_t k = 0; k < t.size(); ++k) ms[6 + k].push_back(slowest(t[k]));
        };
        // The order turns each step, so that neither library always runs first.
        if (step % 2) minkq_step(false, 0), arborx(), minkq_step(true, 3);
        else arborx(), minkq_step(true, 3), minkq_step(false, 0);
      }
      // The last step's sets: ArborX's (left in `ax` by that step) against the one process.
      const GlobalPairs vt = arborx_pairs(ax.vt_offsets, ax.vt_values, apart.owned_vertex_ids);
      const GlobalPairs ee = arborx_pairs(ax.ee_offsets, ax.ee_values, apart.edge_ids);
      if (rank == 0) {
        row.arborx_equal = vt == single[0] && ee == single[1];
        row.vt_pairs = single[0].size(), row.ee_pairs = single[1].size();
      }
      double* fields[10] = {&row.refit,   &row.refit_vt, &row.refit_ee, &row.rebuild, &row.rebuild_vt,
                            &row.rebuild_ee, &row.ax_tri, &row.ax_edge, &row.ax_vt,  &row.ax_ee};
      for (size_t k = 0; k < 10; ++k) *fields[k] = median(ms[k]);
      rows.push_back(row);
      minkq_mpi_scene_release(scene);
    }
    minkq_mpi_result_release(result);

    if (rank == 0) {
      std::ostringstream md;
      char line[800];
      std::snprintf(line, sizeof line,
                    "### %d rank%s x %d thread%s: %s (%zu triangles), r = %.3g x mean edge, %d steps of at most "
                    "%.2g r, box candidates (VT %" PRIu64 ", EE %" PRIu64 " pairs)\n\n",
                    size, size > 1 ? "s" : "", threads, threads > 1 ? "s" : "", sc.name.c_str(),
                    first.triangle_count(), opt.factor, steps, opt.motion, rows.empty() ? 0 : rows[0].vt_pairs,
                    rows.empty() ? 0 : rows[0].ee_pairs);
      md << line;
      md << "| partition | minkq refit step | ArborX step | ArborX / minkq refit | minkq rebuild step | ArborX / minkq "
            "rebuild | minkq refit + VT + EE | minkq rebuild + VT + EE | ArborX trees (triangles + edges) + VT + EE | "
            "sets = one process (minkq, ArborX) |\n|---|---|---|---|---|---|---|---|---|---|\n";
      for (const Row& w : rows) {
        const double refit = w.refit + w.refit_vt + w.refit_ee, rebuild = w.rebuild + w.rebuild_vt + w.rebuild_ee;
        const double ax = w.ax_tri + w.ax_edge + w.ax_vt + w.ax_ee;
        std::snprintf(line, sizeof line,
                      "| %s | %.1f | %.1f | **%.2fx** | %.1f | **%.2fx** | %.1f + %.1f + %.1f | %.1f + %.1f + %.1f | "
                      "(%.1f + %.1f) + %.1f + %.1f | %s, %s |\n",
                      w.partition.c_str(), refit, ax, ax / refit, rebuild, ax / rebuild, w.refit, w.refit_vt,
                      w.refit_ee, w.rebuild, w.rebuild_vt, w.rebuild_ee, w.ax_tri, w.ax_edge, w.ax_vt, w.ax_ee,
                      w.minkq_equal ? "yes" : "**NO**", w.arborx_equal ? "yes" : "**NO**");
        md << line;
        failed |= !w.minkq_equal || !w.arborx_equal;
      }
      md << "\n";
      std::fputs(md.str().c_str(), stdout);
      if (!opt.out.empty()) std::ofstream(opt.out, std::ios::app) << md.str();
    }
  }
  MPI_Bcast(&failed, 1, MPI_INT, 0, MPI_COMM_WORLD);
  MPI_Finalize();
  return failed;
}
