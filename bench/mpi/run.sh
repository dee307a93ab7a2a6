#!/usr/bin/env bash
# The distributed queries' costs (issue 28): minkq_mpi_bench under mpirun -n 1, 2 and 4, into
# bench/results/mpi.md (or --out FILE): the 1M-triangle twisted sheet (slab and Morton
# partitions, 5 steps) and the real mesh multilayer_drape.obj (84k triangles; slab, Morton and
# random, 10 steps). --quick: a 120x120 sheet and the mesh, 3 steps, into build-bench.
#   bench/mpi/run.sh [--quick] [--out FILE]
# Builds the bench project (MINKQ_BENCH_BUILD, default build-bench) with MPI; needs Open MPI
# (libopenmpi-dev openmpi-bin). Runs as root and oversubscribed where it must (Open MPI's
# environment switches).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
build=${MINKQ_BENCH_BUILD:-$root/build-bench}
out=$root/bench/results/mpi.md size=708 steps=5 mesh_steps=10
while [ $# -gt 0 ]; do
  case "$1" in
    --quick) size=120 steps=3 mesh_steps=3 out=$build/mpi-quick.md ;;
    --out) out=$2; shift ;;
    *) sed -n '2,7p' "$0"; exit 2 ;;
  esac
  shift
done
cmake -S "$root/bench" -B "$build" -DCMAKE_BUILD_TYPE=Release -DMINKQ_WITH_MPI=ON >/dev/null
cmake --build "$build" --target minkq_mpi_bench -j "$(nproc)" >/dev/null
# binding none: Open MPI binds each of 1 or 2 ranks to one core by default, which would leave
# rank 0's one-process timing one core of two. yield_when_idle: ranks waiting in a collective
# give their cores back more readily.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1 OMPI_MCA_mpi_yield_when_idle=1 \
  OMPI_MCA_hwloc_base_binding_policy=none
{
  echo "# Distributed queries: minkq_mpi against one process"
  echo
  echo "Written by \`bench/mpi/run.sh\` at $(git -C "$root" rev-parse --short HEAD) on $(nproc) cores"
  echo "($(lscpu | sed -n 's/^Model name: *//p' | head -1)), $(mpirun --version | head -1)."
  echo "Each rank runs minkq's CPU device (all cores, shared by the ranks), so the ranks compete"
  echo "for the same cores as the one process does: the ratios are the cost of distributing, not"
  echo "a speed-up. A step is refit + VT + EE (leaf-exact) + handing the pairs back to rank 0 (a"
  echo "gather); each phase's time is the slowest rank's, the median over the steps (ms, VT and EE"
  echo "together): refit (the copies' positions from their owners), reach boxes (one all-gather),"
  echo "ghost layer (choosing, sending, receiving and assembling it, or with a skin sending the"
  echo "ghosts' positions), local trees (build or refit), local query. \"over one process\" divides"
  echo "the step by the single-process scene's step (refit + VT + EE) in the same run. KiB sent"
  echo "counts ghost and copy payload, the slowest rank's. Ghosts are per owned element, averaged over"
  echo "the ranks; local builds and refits are summed over the ranks' VT and EE trees (a ghost layer"
  echo "that changes members means a build). \"= one process\" compares the union of the pairs, pair"
  echo "by pair, on the last step."
  echo
} > "$out"
mesh=$build/minkq/data/meshes/codim-ipc/multilayer_drape.obj
for ranks in 1 2 4; do
  mpirun -n "$ranks" "$build/bin/minkq_mpi_bench" --size "$size" --steps "$steps" --partitions slab,morton \
    --out "$out" >/dev/null
  mpirun -n "$ranks" "$build/bin/minkq_mpi_bench" --mesh "$mesh" --steps "$mesh_steps" --out "$out" >/dev/null
done
echo "wrote $out"
