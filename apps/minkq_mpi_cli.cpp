// minkq-mpi: the distributed query of a mesh file, for checking and for users.
//   mpirun -n K minkq-mpi query MESH --radius R [--mode M] [--leaf-exact] --partition slab|morton|random [--seed S]
// Every rank loads the mesh and takes its part; rank 0 prints the lines `minkq query` prints
// (the digests of the global pair sets, in the single-process numbering) and each rank's
// figures.
#include <mpi.h>

#include <cinttypes>
#include <cstdio>
#include <memory>
#include <string>
#include <tuple>
#include <vector>

#include <xxhash.h>

#include "cli_common.h"
#include "distributed.h"
#include "minkq.hpp"
#include "minkq_mpi.h"
#include "mesh_io.h"

namespace {

using namespace minkq::cli;
namespace tools = minkq::mpi_tools;

constexpr int kExitUsage = 2, kExitFailure = 3;

const char* const kUsage = R"(usage: mpirun -n K minkq-mpi query MESH --radius R | --radius-factor F [options]

  Loads an OBJ, PLY or OFF mesh on every rank, splits it over the K ranks, and runs the distributed
  VT and EE queries (incident pairs dropped) within R (or F x the mesh's mean edge length) in
  mode M. Rank 0 prints
  "vt candidates N digest HEX" and "ee candidates N digest HEX" for the union of the ranks'
  pairs, equal to `minkq query MESH --radius R --mode M`, then one line of figures per rank.
  It fails (exit 3) when a pair is reported by two ranks.

options:
  --mode M        box (default), sphere, capsule_ray, capsule_exact, as minkq query (and its
                  old word leaf_exact, with a warning); a comma-separated list runs each in
                  turn, each after a line "mode M"
  --leaf-exact    the primitive distance at the leaves too (every mode): the contacts
  --partition P   slab (triangles by centroid x), morton (chunks of the centroids' Morton
                  order), random (every triangle and every vertex on a random rank); default slab
  --seed S        the random partition's seed (default 1)
  --backend B     each rank's device: cpu, cuda, cuda:N or auto (default: cpu); "cuda" picks
                  GPU (local rank mod GPUs)
)";

// A collective failure (a minkq_mpi call: the same on every rank).
struct Failed : std::runtime_error {
  using std::runtime_error::runtime_error;
};
// Every rank stops with this exit status; the reason is printed already.
struct Stop {
  int code;
};

void check(minkq_status status, const char* call) {
  if (status != MINKQ_SUCCESS)
    throw Failed(std::string(call) + " failed: " + minkq_status_name(status) + ": " + minkq_mpi_last_error_message());
}

// This rank's index among the ranks on its node (collective).
int node_rank() {
  MPI_Comm node;
  MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &node);
  int local_rank = 0;
  MPI_Comm_rank(node, &local_rank);
  MPI_Comm_free(&node);
  return local_rank;
}

// "cuda" means one GPU per rank: the node-local rank's, round robin.
std::string device_spec(const std::string& backend, int local_rank) {
  const int gpus = minkq_cuda_device_count();
  if (backend != "cuda" || gpus == 0) return backend;  // minkq_device_create says why not
  return "cuda:" + std::to_string(local_rank % gpus);
}

// The digest `minkq query` prints: XXH64 of the canonical pairs as little-endian int32 (global
// ids of a mesh file fit).
uint64_t digest(const tools::GlobalPairs& pairs) {
  std::vector<int32_t> flat;
  flat.reserve(2 * pairs.size());
  for (const auto& [a, b] : pairs) flat.push_back(int32_t(a)), flat.push_back(int32_t(b));
  return XXH64(flat.data(), flat.size() * sizeof(int32_t), 0);
}

// Runs each rank's own set-up (arguments, mesh file, device), then agrees: when it failed
// anywhere, the lowest failing rank prints why and every rank stops, with none left waiting.
template <class Work>
void agreed(int rank, Work&& work) {
  std::string message;
  int code = 0;
  try {
    work();
  } catch (const UsageError& e) {
    message = e.what(), code = kExitUsage;
  } catch (const std::exception& e) {
    message = e.what(), code = kExitFailure;
  }
  int size = 1, first = 0;
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  const int mine = code ? rank : size;
  MPI_Allreduce(&mine, &first, 1, MPI_INT, MPI_MIN, MPI_COMM_WORLD);
  if (first == size) return;
  MPI_Bcast(&code, 1, MPI_INT, first, MPI_COMM_WORLD);
  if (rank == first)
    std::fprintf(stderr, "minkq-mpi: %s%s\n", size > 1 ? ("rank " + std::to_string(rank) + ": ").c_str() : "",
                 message.c_str());
  throw Stop{code};
}

int query(const Args& args, int rank, int size) {
  float radius = 0;
  std::vector<std::pair<std::string, QueryModes>> modes;
  minkq::meshio::Mesh mesh;
  tools::Part part;
  minkq::cxx::Device device;
  const int local_rank = node_rank();
  agreed(rank, [&] {
    if (args.positional.size() != 1) throw UsageError("query needs exactly one MESH argument");
    const std::string list = args.get("--mode") ? *args.get("--mode") : "box";
    const auto warn = [rank](const std::string& message) {
      if (rank == 0) std::fprintf(stderr, "minkq-mpi: warning: %s\n", message.c_str());
    };
    for (size_t at = 0; at <= list.size();) {
      const size_t comma = std::min(list.find(',', at), list.size());
      const std::string name = list.substr(at, comma - at);
      modes.emplace_back(name, query_modes(name, args.has("--leaf-exact"), false, true, warn));
      at = comma + 1;
    }
    tools::Partition partition;
    try {
      partition = tools::parse_partition(args.get("--partition") ? *args.get("--partition") : "slab");
    } catch (const std::invalid_argument& e) {
      throw UsageError(std::string("--partition: ") + e.what());
    }
    const double seed = args.get("--seed") ? parse_number("--seed", *args.get("--seed")) : 1;
    if (seed < 0 || seed != double(uint64_t(seed))) throw UsageError("--seed: a non-negative integer");
    mesh = minkq::meshio::load_mesh(args.positional[0]);
    radius = query_radius(args, [&] { return minkq::meshio::mean_edge_length(mesh); });
    const tools::Owners owners = tools::partition(mesh.xyz, mesh.tris, size, partition, uint64_t(seed));
    part = tools::part_of(mesh.xyz, mesh.tris, owners, rank);
    device = minkq::cxx::open_device(device_spec(args.get("--backend") ? *args.get("--backend") : "cpu", local_rank));
  });
  const minkq_mpi_scene_desc desc =
      tools::desc_of(part, MINKQ_SCENE_VT | MINKQ_SCENE_EE | MINKQ_SCENE_DROP_INCIDENT);
  minkq_mpi_scene* scene = nullptr;
  check(minkq_mpi_scene_create(MPI_COMM_WORLD, device.get(), &desc, &scene), "minkq_mpi_scene_create");
  minkq_mpi_result* result = nullptr;
  check(minkq_mpi_result_create(&result), "minkq_mpi_result_create");
  uint64_t local_pairs[2] = {0, 0};
  bool twice = false;
  for (const auto& [mode_name, m] : modes) {
    if (rank == 0 && modes.size() > 1) std::printf("mode %s\n", mode_name.c_str());
    for (const auto& [kind, name, mode] : {std::tuple{MINKQ_QUERY_VT, "vt", m.of(MINKQ_QUERY_VT)}, std::tuple{MINKQ_QUERY_EE, "ee", m.of(MINKQ_QUERY_EE)}}) {
      const minkq_query_desc q{kind, mode, m.flags, radius};
      check(minkq_mpi_scene_query(scene, &q, result), "minkq_mpi_scene_query");
      local_pairs[kind == MINKQ_QUERY_EE] = minkq_mpi_result_count(result);
      const tools::GlobalPairs all = tools::gather_pairs(MPI_COMM_WORLD, result);
      if (rank != 0) continue;
      tools::GlobalPairs distinct = all;
      distinct.erase(std::unique(distinct.begin(), distinct.end()), distinct.end());
      std::printf("%s candidates %zu digest %016" PRIx64 "\n", name, distinct.size(), digest(distinct));
      if (distinct.size() != all.size()) {
        std::fprintf(stderr, "minkq-mpi: %zu %s pairs were reported by more than one rank\n", all.size() - distinct.size(),
                     name);
        twice = true;
      }
    }
  }
  minkq_mpi_rank_info info{};
  check(minkq_mpi_scene_rank_info(scene, &info), "minkq_mpi_scene_rank_info");
  const uint64_t figures[9] = {info.owned_vertices, info.owned_triangles, info.owned_edges,
                               info.copied_vertices, info.ghost_vertices,  info.ghost_edges,
                               info.neighbours,      local_pairs[0],       local_pairs[1]};
  std::vector<uint64_t> everyone(rank == 0 ? 9 * size_t(size) : 0);
  MPI_Gather(figures, 9, MPI_UINT64_T, everyone.data(), 9, MPI_UINT64_T, 0, MPI_COMM_WORLD);
  if (rank == 0)
    for (int p = 0; p < size; ++p) {
      const uint64_t* f = everyone.data() + 9 * size_t(p);
      std::printf("rank %d owned vertices %" PRIu64 " triangles %" PRIu64 " edges %" PRIu64 " copies %" PRIu64
                  " ghost vertices %" PRIu64 " ghost edges %" PRIu64 " neighbours %" PRIu64 " pairs vt %" PRIu64
                  " ee %" PRIu64 "\n",
                  p, f[0], f[1], f[2], f[3], f[4], f[5], f[6], f[7], f[8]);
    }
  minkq_mpi_result_release(result);
  minkq_mpi_scene_release(scene);
  int failed = twice;
  MPI_Bcast(&failed, 1, MPI_INT, 0, MPI_COMM_WORLD);
  return failed ? kExitFailure : 0;
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  const std::string command = argc > 1 ? argv[1] : "";
  int code = 0;
  try {
    if (command == "--help" || command == "-h" || command == "help" || (command == "query" && wants_help(argc, argv, 2))) {
      if (rank == 0) std::fputs(kUsage, stdout);
    } else if (command == "query") {
      std::unique_ptr<Args> args;
      agreed(rank, [&] {
        args = std::make_unique<Args>(argc, argv, 2, std::vector<std::string>{"--radius", "--radius-factor", "--mode", "--partition", "--seed", "--backend"},
                                       std::vector<std::string>{"--leaf-exact"});
      });
      code = query(*args, rank, size);
    } else {
      agreed(rank, [&] { throw UsageError(command.empty() ? "no command given" : "unknown command '" + command + "'"); });
    }
  } catch (const Stop& stop) {
    if (stop.code == kExitUsage && rank == 0) std::fprintf(stderr, "(run 'minkq-mpi --help' for usage)\n");
    code = stop.code;
  } catch (const Failed& e) {
    // A collective failure: every rank has the same text; rank 0 prints it.
    if (rank == 0) std::fprintf(stderr, "minkq-mpi: %s\n", e.what());
    code = kExitFailure;
  }
  MPI_Finalize();
  return code;
}
