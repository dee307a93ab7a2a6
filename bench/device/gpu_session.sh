#!/usr/bin/env bash
# A GPU session on the device machine, in stages, each leaving its output in $OUT (the device
# tool brings that folder back; at most 8 files). State between calls lives in /tmp and in
# build-sm90, which a warm machine keeps (about 30 s idle): make the calls back to back.
#
#   here:    bash bench/device/pack.sh                   # .carry/kit: Debian packages, ../shared
#   device:  run(carry=[".carry/kit"], timeout_s=600,
#                command="bash bench/device/gpu_session.sh setup build test bench")
#   (should that outrun a call's 10 minutes, split it: "setup build test", then "bench" at once)
#   then Warp / Newton on the same GPU, per ../shared/tools/warp-for-device.sh (three calls; the
#   third one ends with: bash bench/device/gpu_session.sh warp)
#
# Stages:
#   setup  unpack the packages into /tmp/minkq-deps, ../shared from the kit, report the machine
#   build  cmake --preset sm90 with the benchmarks, build everything (build-sm90)
#   test   the whole ctest suite, CUDA suites included (CPU == CUDA pair sets, digests, errors)
#   bench  minkq_bench --backends cpu,cuda on $MINKQ_SUITES (default scenes,real,scale), frames
#          exported for Warp, and minkq_ablation --only fused --backend cuda (one VT + EE launch
#          against two); $OUT/results.tar.gz holds bench/results-style tables
#   warp   bench/warp_baseline.py --device cuda:0 on the exported frames beside minkq's cuda rows
#   profile  Nsight Compute on the 1M-triangle twisted sheet's query and refit kernels ($OUT/ncu.txt)
# --smoke (first argument): bench --quick, to try the script on a machine without a GPU.
# Exit status: the first failing stage's, after every stage asked for has run.
set -uo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
kit=${MINKQ_KIT:-$root/.carry/kit}
out=${OUT:-/tmp/minkq-out}
deps=/tmp/minkq-deps
results=/tmp/minkq-results
export_dir=/tmp/minkq-export
smoke=0
if [ "${1:-}" = "--smoke" ]; then smoke=1; shift; fi
[ $# -gt 0 ] || set -- setup build test bench
mkdir -p "$out"
log=$out/session.log
exec > >(tee -a "$log") 2>&1
cd "$root"

# Packages unpacked into a prefix (not /): CMake finds them through CMAKE_PREFIX_PATH, the
# programs through LD_LIBRARY_PATH; tbbbind (hwloc) is left out, TBB runs without it.
export CMAKE_PREFIX_PATH="$deps/usr${CMAKE_PREFIX_PATH:+:$CMAKE_PREFIX_PATH}"
export LD_LIBRARY_PATH="$deps/usr/lib/x86_64-linux-gnu${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
jobs=$(nproc)

stage_setup() {
  [ -d "$kit/debs" ] || { echo "no kit at $kit: run bench/device/pack.sh here and carry .carry/kit"; return 1; }
  mkdir -p "$deps"
  for deb in "$kit"/debs/*.deb; do
    if command -v dpkg-deb > /dev/null; then
      dpkg-deb -x "$deb" "$deps" || return 1
    else  # a .deb is an ar archive around data.tar.*
      (t=$(mktemp -d) && cd "$t" && ar x "$deb" && tar xf data.tar.* -C "$deps") || return 1
    fi
  done
  if [ ! -d "$root/../shared/data" ]; then
    rm -rf /tmp/minkq-shared && cp -r "$kit/shared" /tmp/minkq-shared && ln -sfn /tmp/minkq-shared "$root/../shared"
  fi
  nvidia-smi -L || echo "nvidia-smi: none"
  nvcc --version | tail -2
  g++ --version | head -1
  cmake --version | head -1
  echo "$(nproc) CPUs, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2-)"
}

stage_build() {
  cmake --preset sm90 -DMINKQ_BUILD_BENCH=ON > "$out/configure.log" 2>&1 || { tail -30 "$out/configure.log"; return 1; }
  grep -E "^(TBB_DIR|embree_DIR|GTest_DIR|tinyobjloader_DIR|XXHASH_LIBRARY)" build-sm90/CMakeCache.txt
  cmake --build build-sm90 -j "$jobs" > "$out/build.log" 2>&1 || { grep -E "error|Error" "$out/build.log" | head -40; return 1; }
  echo "built: $(ls build-sm90/bin | tr '\n' ' ')"
}

stage_test() {
  ctest --test-dir build-sm90 -j "$jobs" --output-on-failure --timeout 1200 > "$out/ctest.log" 2>&1
  local status=$?
  grep -E "tests passed|tests failed|\*\*\*|Failed|Skipped" "$out/ctest.log" | tail -40
  return $status
}

stage_bench() {
  local args=(--backends cpu,cuda --suites "${MINKQ_SUITES:-scenes,real,scale}" --out "$results" --export "$export_dir")
  [ $smoke = 1 ] && args=(--quick --out "$results" --export "$export_dir")
  rm -rf "$results" "$export_dir"
  mkdir -p "$results"
  build-sm90/bin/minkq_bench "${args[@]}" > "$out/bench.log" 2>&1
  local status=$?
  tail -20 "$out/bench.log"
  # One fused VT + EE launch against two (fused_cuda.md), beside the CPU's fused.md.
  local fused=(--only fused --backend cuda --out "$results")
  [ $smoke = 1 ] && fused=(--only fused --backend auto --quick --out "$results")  # no GPU there
  build-sm90/bin/minkq_ablation "${fused[@]}" > "$out/fused.log" 2>&1 || status=1
  tail -3 "$out/fused.log"
  nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.mem --format=csv > "$results/device.txt" 2>&1 || true
  tar czf "$out/results.tar.gz" -C "$results" .
  return $status
}

stage_warp() {
  [ -d /tmp/site/warp ] || { echo "no Warp in /tmp/site: unpack it first (../shared/tools/warp-for-device.sh)"; return 1; }
  [ -f "$results/rows.csv" ] || { echo "no $results/rows.csv: run the bench stage on this machine first"; return 1; }
  PYTHONPATH=/tmp/site${PYTHONPATH:+:$PYTHONPATH} python3 bench/warp_baseline.py "$export_dir" "$results/rows.csv" \
    "$out/warp_gpu.md" --device cuda:0
}

stage_profile() {
  # Nsight Compute on the issue's target scene, the 1M-triangle twisted sheet at r = 0.25x mean
  # edge (minkq demo --size 708: every mode, checked against the oracle): the query and refit
  # kernels' throughput, memory, occupancy and warp stalls, to say what limits them.
  command -v ncu > /dev/null || { echo "no ncu on this machine"; return 1; }
  ncu --kernel-name regex:"query_kernel|refit_kernel" --launch-count 40 --section SpeedOfLight \
    --section MemoryWorkloadAnalysis --section Occupancy --section LaunchStats --section WarpStateStats \
    build-sm90/bin/minkq demo --backend cuda --size 708 > "$out/ncu.txt" 2>&1
  local status=$?
  grep -E "query_kernel|refit_kernel|Duration|Memory Throughput|Compute \(SM\) Throughput|Achieved Occupancy" \
    "$out/ncu.txt" | head -80
  return $status
}

first_failure=0
for stage in "$@"; do
  echo "== $stage ($(date -u +%H:%M:%S))"
  case "$stage" in
    setup) stage_setup ;; build) stage_build ;; test) stage_test ;; bench) stage_bench ;; warp) stage_warp ;;
    profile) stage_profile ;;
    *) echo "unknown stage $stage"; false ;;
  esac
  status=$?
  echo "== $stage: exit $status"
  [ $status != 0 ] && [ $first_failure = 0 ] && first_failure=$status
done
exit $first_failure
