#!/usr/bin/env bash
# Issue 28's check on real meshes: for every OBJ and PLY under DIR (default ../shared/data),
# `mpirun -n K minkq-mpi query` for K = 1..4 and every partition kind prints, in every mode, the
# lines `minkq query` prints (counts and digests of the VT and EE pairs), at r = F x mean edge.
#   bench/mpi/check_meshes.sh [--data DIR] [--factor F] [--build DIR] [--out FILE]
# BUILD (default build-cpu) holds bin/minkq and bin/minkq-mpi; writes a table to FILE
# (default bench/results/mpi_meshes.md); exit 1 on any difference.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
data=$root/../shared/data factor=1 build=$root/build-cpu out=$root/bench/results/mpi_meshes.md
while [ $# -gt 0 ]; do
  case "$1" in
    --data) data=$2; shift ;;
    --factor) factor=$2; shift ;;
    --build) build=$2; shift ;;
    --out) out=$2; shift ;;
    *) sed -n '2,8p' "$0"; exit 2 ;;
  esac
  shift
done
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
modes=(box sphere capsule_ray capsule_exact leaf_exact)
lines() { grep -E '^(mode |vt candidates|ee candidates)'; }
failed=0
{
  echo "# minkq-mpi against minkq query on the real meshes"
  echo
  echo "Written by \`bench/mpi/check_meshes.sh --factor $factor\` at $(git -C "$root" rev-parse --short HEAD):"
  echo "for each mesh, \`mpirun -n K minkq-mpi query MESH --radius-factor $factor --mode $(IFS=,; echo "${modes[*]}")"
  echo "--partition P\` (K = 1..4; random with seed 1) against \`minkq query MESH --radius-factor $factor --mode M\`"
  echo "for each mode M: every mode's VT and EE counts and digests equal (\"5/5\"), and no pair reported by"
  echo "two ranks. The counts shown are leaf_exact's (the contacts) and box's."
  echo
  echo "| mesh | triangles | leaf_exact VT / EE | box VT / EE | K = 1 | 2 | 3 | 4 |"
  echo "|---|---|---|---|---|---|---|---|"
} > "$out"
for mesh in $(find "$data" -name '*.obj' -o -name '*.ply' | sort); do
  name=${mesh#"$data"/}
  want=""
  for m in "${modes[@]}"; do
    want+="mode $m"$'\n'"$("$build/bin/minkq" query "$mesh" --radius-factor "$factor" --mode "$m" --backend cpu | lines)"$'\n'
  done
  count() { echo "$want" | sed -n "/^mode $1\$/,/^mode /p" | sed -n "s/^$2 candidates \([0-9]*\).*/\1/p" | head -1; }
  case "$mesh" in
    *.ply) triangles=$(head -c 4096 "$mesh" | tr -c '[:print:]\n' '\n' | sed -n 's/^element face \([0-9]*\).*/\1/p' | head -1) ;;
    *) triangles=$(grep -c '^f ' "$mesh" || true) ;;
  esac
  row="| $name | $triangles | $(count leaf_exact vt) / $(count leaf_exact ee) | $(count box vt) / $(count box ee) |"
  for k in 1 2 3 4; do
    cell=""
    for p in slab morton random; do
      got=$(mpirun -n "$k" "$build/bin/minkq-mpi" query "$mesh" --radius-factor "$factor" \
            --mode "$(IFS=,; echo "${modes[*]}")" --partition "$p" --seed 1 2>&1 | lines || true)
      equal=0
      for m in "${modes[@]}"; do
        a=$(echo "$want" | sed -n "/^mode $m\$/,/^mode /p" | grep candidates)
        b=$(echo "$got" | sed -n "/^mode $m\$/,/^mode /p" | grep candidates)
        [ -n "$a" ] && [ "$a" = "$b" ] && equal=$((equal + 1))
      done
      [ "$equal" = ${#modes[@]} ] || { failed=1; echo "DIFFERENT: $name K=$k $p" >&2; }
      cell+="$p ${equal}/${#modes[@]}, "
    done
    row+=" ${cell%, } |"
  done
  echo "$row" >> "$out"
  echo "$row"
done
echo "wrote $out"
exit $failed
