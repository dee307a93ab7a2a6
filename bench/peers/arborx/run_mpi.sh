#!/usr/bin/env bash
# minkq_mpi beside ArborX's DistributedTree (issue 28): arborx_mpi_bench under mpirun -n 1, 2 and
# 4, into bench/results/arborx_mpi.md (or --out FILE): the 1M-triangle twisted sheet (slab and
# Morton partitions, 5 steps) and the real mesh multilayer_drape.obj (84k triangles; slab,
# Morton and random, 7 steps). --quick: a 120x120 sheet and the mesh, 3 steps, into
# build-bench/arborx. Builds Kokkos, ArborX (with MPI) and the program first (bench/peers/arborx/
# build.sh, which takes the same --src option); needs Open MPI (libopenmpi-dev openmpi-bin).
#   bench/peers/arborx/run_mpi.sh [--quick] [--out FILE] [--src DIR]
set -euo pipefail
root=$(cd "$(dirname "$0")/../../.." && pwd)
work=$root/build-bench/arborx
out=$root/bench/results/arborx_mpi.md size=708 steps=5 mesh_steps=7 build_args=()
while [ $# -gt 0 ]; do
  case "$1" in
    --quick) size=120 steps=3 mesh_steps=3 out=$work/arborx_mpi-quick.md ;;
    --out) out=$2; shift ;;
    --src) build_args=(--src "$2"); shift ;;
    *) sed -n '2,8p' "$0"; exit 2 ;;
  esac
  shift
done
"$root/bench/peers/arborx/build.sh" "${build_args[@]}"
bin=$work/bin/arborx_mpi_bench
[ -x "$bin" ] || { echo "run_mpi.sh: $bin was not built (is Open MPI installed?)" >&2; exit 1; }
# Open MPI: as root and oversubscribed where it must; no binding (a rank's threads may use every
# core it is given). OpenMP: unbound threads (as minkq's TBB workers) that sleep when they wait
# (on a shared machine libgomp's spinning waits stall, bench/peers/arborx/arborx_bench.cpp says why).
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1 \
  OMPI_MCA_mpi_yield_when_idle=1 OMPI_MCA_hwloc_base_binding_policy=none OMP_PROC_BIND=false OMP_WAIT_POLICY=passive
cores=$(nproc)
{
  echo "# Distributed queries: minkq_mpi beside ArborX's DistributedTree"
  echo
  echo "Written by \`bench/peers/arborx/run_mpi.sh\` at $(git -C "$root" rev-parse --short HEAD) on $cores cores"
  echo "($(lscpu | sed -n 's/^Model name: *//p' | head -1)), $(mpirun --version | head -1), ArborX 2.1"
  echo "with its MPI part on Kokkos 4.6.01 (OpenMP). K ranks share the $cores cores, each running both"
  echo "libraries on max(1, $cores / K) threads. Both store the VT and EE box candidates (incident"
  echo "pairs dropped, EE each pair once) on the ranks in global ids, and both sets are checked pair"
  echo "by pair against the single-process minkq scene on the last step. A step (ms, the slowest"
  echo "rank's, median over the steps): minkq refit = minkq_mpi_scene_refit + VT + EE (ghost layers"
  echo "exchanged, local trees refit or built where a layer changes); minkq rebuild ="
  echo "minkq_mpi_scene_rebuild + VT + EE (local trees built afresh); ArborX = a DistributedTree over"
  echo "the owned triangles and one over the owned edges (it has no refit), then the owned vertices'"
  echo "and owned edges' grown boxes queried (sent to the ranks whose bounds they meet, results sent"
  echo "back). The ratios divide ArborX's step by minkq's, so above 1 means minkq is faster."
  echo
} > "$out"
mesh=$work/bench/minkq/data/meshes/codim-ipc/multilayer_drape.obj
for ranks in 1 2 4; do
  mpirun -n "$ranks" "$bin" --size "$size" --steps "$steps" --partitions slab,morton --out "$out" >/dev/null
  mpirun -n "$ranks" "$bin" --mesh "$mesh" --steps "$mesh_steps" --out "$out" >/dev/null
done
echo "wrote $out"
