#!/usr/bin/env bash
# The distributed queries' costs (issue 28): minkq_mpi_bench under mpirun -n 1, 2 and 4, into
# bench/results/mpi.md (or --out FILE).
#   bench/mpi/run.sh [--size N] [--steps S] [--out FILE]
# Builds the bench project (MINKQ_BENCH_BUILD, default build-bench) with MPI; needs Open MPI
# (libopenmpi-dev openmpi-bin). Runs as root and oversubscribed where it must (Open MPI's
# environment switches).
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
build=${MINKQ_BENCH_BUILD:-$root/build-bench}
out=$root/bench/results/mpi.md size=301 steps=10
while [ $# -gt 0 ]; do
  case "$1" in
    --size) size=$2; shift ;;
    --steps) steps=$2; shift ;;
    --out) out=$2; shift ;;
    *) sed -n '2,7p' "$0"; exit 2 ;;
  esac
  shift
done
cmake -S "$root/bench" -B "$build" -DCMAKE_BUILD_TYPE=Release -DMINKQ_WITH_MPI=ON >/dev/null
cmake --build "$build" --target minkq_mpi_bench -j "$(nproc)" >/dev/null
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
{
  echo "# Distributed queries: minkq_mpi against one process"
  echo
  echo "Written by \`bench/mpi/run.sh\` at $(git -C "$root" rev-parse --short HEAD) on $(nproc) cores"
  echo "($(lscpu | sed -n 's/^Model name: *//p' | head -1)), $(mpirun --version | head -1)."
  echo "Each rank runs minkq's CPU device (all cores, shared by the ranks), so the ranks compete"
  echo "for the same cores as the one process does: the ratios are the cost of distributing, not"
  echo "a speed-up. A step is refit + VT + EE (leaf-exact); its time is the slowest rank's, the"
  echo "median over the steps; \"over one process\" divides it by the single-process scene's step"
  echo "in the same run. Ghosts are per owned element, averaged over the ranks; local builds and"
  echo "refits are summed over the ranks' VT and EE trees (a ghost layer that changes members"
  echo "means a build). \"= one process\" compares the union of the pairs, pair by pair."
  echo
} > "$out"
for ranks in 1 2 4; do
  mpirun -n "$ranks" "$build/bin/minkq_mpi_bench" --size "$size" --steps "$steps" --out "$out" >/dev/null
done
echo "wrote $out"
