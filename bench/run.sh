#!/usr/bin/env bash
# Regenerates every benchmark table and plot of bench/results with one command.
#
#   bench/run.sh            full run (about 45 min on 2 cores, Warp stage included): minkq_bench's
#                           suites (scenes, real meshes, radius sweep, 1M/2M twisted sheets,
#                           count-only, float64 and swept queries), plots, Warp/Newton CPU
#                           baselines, ipctk CCD broad phases (when the Scalable CCD sample data
#                           is found); writes bench/results/
#   bench/run.sh --quick    smoke run (about a minute): reference scenes (2 frames, 1 repeat) and
#                           the count, float64 and swept suites on small scenes; writes
#                           build-bench/quick-results/ and exits non-zero on any false negative
#                           or failed check
#   options: --out DIR (results folder), --no-warp (skip the Python/Warp stage),
#            --no-install (do not apt-get/pip anything)
# Environment: MINKQ_BENCH_BUILD (build folder, default build-bench), MINKQ_WITH_CUDA (AUTO|ON|OFF),
#   MINKQ_CCD_DATA (the Scalable CCD sample data), MINKQ_LIB_DIR (libminkq.so for ccd_peers.py).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${MINKQ_BENCH_BUILD:-$root/build-bench}
quick=0 warp=1 install=1 out=""
while [ $# -gt 0 ]; do
  case "$1" in
    --quick) quick=1 ;;
    --no-warp) warp=0 ;;
    --no-install) install=0 ;;
    --out) out=$2; shift ;;
    -h|--help) sed -n '2,17p' "$0"; exit 0 ;;
    *) echo "run.sh: unknown option $1" >&2; exit 2 ;;
  esac
  shift
done
[ -z "$out" ] && { [ $quick = 1 ] && out=$build/quick-results || out=$root/bench/results; }

packages=(cmake g++ make libtbb-dev libxxhash-dev libtinyobjloader-dev libembree-dev python3-venv)
if [ $install = 1 ]; then
  missing=()
  for p in "${packages[@]}"; do dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p"); done
  if [ ${#missing[@]} -gt 0 ]; then
    sudo=""; [ "$(id -u)" -ne 0 ] && sudo=sudo
    echo "installing: ${missing[*]}"
    $sudo apt-get update -q
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -q "${missing[@]}"
  fi
fi

cmake -S "$root/bench" -B "$build" -DCMAKE_BUILD_TYPE=Release -DMINKQ_WITH_CUDA="${MINKQ_WITH_CUDA:-AUTO}" >/dev/null
cmake --build "$build" -j "$(nproc)" --target minkq_bench >/dev/null
bin=$build/bin
mkdir -p "$out"
echo "machine: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2-), $(nproc) CPUs, load $(cut -d' ' -f1-3 /proc/loadavg)"

status=0
if [ $quick = 1 ]; then
  "$bin/minkq_bench" --quick --suites scenes,count,float64,swept,geometries --out "$out" || status=$?
  [ $status = 0 ] && echo "bench quick run: 1 passed, 0 failed (no false negatives; results in $out)" \
                  || echo "bench quick run: 0 passed, 1 failed (status $status; see $out)"
  exit $status
fi

# Full run: every suite. minkq_bench exits 1 on a false negative or a failed check; the tables
# are written either way, so keep going and report at the end.
"$bin/minkq_bench" --large --out "$out" || status=$?

venv=$build/venv
if [ $install = 1 ] && [ ! -x "$venv/bin/python" ]; then python3 -m venv "$venv"; fi
if [ -x "$venv/bin/python" ]; then
  if [ $install = 1 ]; then
    "$venv/bin/pip" install -q matplotlib numpy || echo "pip: matplotlib failed; plots skipped"
  fi
  "$venv/bin/python" "$root/bench/plot.py" "$out" || echo "plot.py failed"
fi

if [ $warp = 1 ] && [ -x "$venv/bin/python" ]; then
  if [ $install = 1 ]; then
    "$venv/bin/pip" install -q "warp-lang==1.19.0" "newton==1.8.0" || echo "pip: warp-lang/newton failed"
  fi
  # Warp's CPU kernels are single-threaded: minkq beside them on one thread, same scenes, same
  # float coordinates (exported), last frame each.
  rm -rf "$build/export" "$build/threads1"
  "$bin/minkq_bench" --suites scenes --frames 2 --repeats 3 --threads 1 --export "$build/export" --out "$build/threads1" || status=$?
  "$venv/bin/python" "$root/bench/peers/warp_baseline.py" "$build/export" "$build/threads1/rows.csv" "$out/warp.md" ||
    echo "warp_baseline.py failed (see $out/warp.md)"
  cp "$build/threads1/summary.md" "$out/summary_threads1.md"
  # The 1M twisted sheet, where Newton's absolute epsilon loses EE contacts; minkq's columns from the
  # main (all-threads) run.
  rm -rf "$build/export1M"
  "$bin/minkq_bench" --suites scale --scale-scenes twist_target --scale-triangles 1e6 --export-only "$build/export1M"
  "$venv/bin/python" "$root/bench/peers/warp_baseline.py" "$build/export1M" "$out/rows.csv" "$out/warp_1M.md" --minkq-threads all ||
    echo "warp_baseline.py (1M) failed"
fi

# Swept queries beside ipctk's CCD broad phases on the Scalable CCD sample data, when a copy of it
# is found (MINKQ_CCD_DATA, else ../shared/data/Sample-Scalable-CCD-Data, ...: see ccd_peers.py)
# and minkq's Python module is built (bindings/test.sh); skipped by name otherwise. ipctk in a venv
# of its own (it brings scipy and its own TBB, statically linked).
ccd_venv=$build/ccd-venv
if [ $install = 1 ] && [ ! -x "$ccd_venv/bin/python" ]; then python3 -m venv "$ccd_venv" || true; fi
if [ -x "$ccd_venv/bin/python" ] && [ $install = 1 ]; then
  "$ccd_venv/bin/pip" install -q numpy "ipctk==1.6.1" || echo "pip: ipctk failed; ccd_peers skipped"
fi
ccd_env=(env PYTHONPATH="$root/bindings/python/python${PYTHONPATH:+:$PYTHONPATH}"
         LD_LIBRARY_PATH="${MINKQ_LIB_DIR:-$build/minkq/capi}${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}")
if [ ! -x "$ccd_venv/bin/python" ] || ! "${ccd_env[@]}" "$ccd_venv/bin/python" -c 'import minkq, ipctk' 2>/dev/null; then
  echo "ccd_peers: skipped (needs ipctk in $ccd_venv and minkq's Python module: bindings/test.sh builds it)" >&2
else
  "${ccd_env[@]}" "$ccd_venv/bin/python" "$root/bench/peers/ccd_peers.py" --out "$out/ccd_peers.md" || status=$?
fi
echo "results in $out (status $status)"
exit $status
