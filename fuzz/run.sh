#!/usr/bin/env bash
# fuzz/run.sh [SECONDS]: builds the fuzzers (clang, libFuzzer, ASan + UBSan + LSan; a separate
# CMake project, fuzz/CMakeLists.txt) and runs each one for SECONDS (default 60) from its
# corpus. Exits non-zero if any fuzzer fails; a failure is minimised (-minimize_crash) and its
# scene printed as C++ for tests/test_fuzz_regressions.cpp.
#
#   fuzz/run.sh            CI: about a minute per fuzzer
#   fuzz/run.sh 3600       a campaign: an hour per fuzzer (record it in fuzz/RESULTS.md)
#
# Environment: MINKQ_FUZZERS="fuzz_differential fuzz_capi" (which to run),
# MINKQ_FUZZ_BUILD (build folder, default build-fuzz; its corpus/ keeps what a run found, so
# later runs continue from there), MINKQ_FUZZ_THREADS (TBB threads, default 1),
# MINKQ_FUZZ_STATS_EVERY=N (a progress line every N inputs of the differential fuzzer),
# MINKQ_FUZZ_OSS_CHECK (seconds per fuzzer of fuzz/oss-fuzz/check.sh, the OSS-Fuzz-style build
# run on its seed corpus zips, after the runs; default 10, 0 skips it).
# Installs clang, libclang-rt-14-dev, libembree-dev and the build dependencies when missing and
# run as root (or with sudo).
set -euo pipefail
seconds=${1:-60}
[[ "$seconds" =~ ^[0-9]+$ ]] || { sed -n '2,17p' "$0"; exit 2; }
here=$(cd "$(dirname "$0")" && pwd)
root=$(dirname "$here")
build=${MINKQ_FUZZ_BUILD:-$root/build-fuzz}
fuzzers=${MINKQ_FUZZERS:-fuzz_differential fuzz_capi}

packages=(clang libclang-rt-14-dev libembree-dev cmake ninja-build pkg-config libtbb-dev libxxhash-dev
          libtinyobjloader-dev zip unzip)
missing=()
for p in "${packages[@]}"; do dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p"); done
if [ ${#missing[@]} -gt 0 ]; then
  sudo=""
  if [ "$(id -u)" -ne 0 ]; then
    if command -v sudo >/dev/null; then sudo=sudo; else echo "fuzz/run.sh: missing packages ${missing[*]} (run as root to install)"; exit 1; fi
  fi
  echo "fuzz/run.sh: installing ${missing[*]}"
  $sudo apt-get update -q
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -q "${missing[@]}"
fi

start=$(date +%s)
cmake -S "$here" -B "$build" -G Ninja -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ >/dev/null
cmake --build "$build" -j "$(nproc)"
built=$(date +%s)
echo "fuzz/run.sh: built in $((built - start)) s; running ${fuzzers} for ${seconds} s each"

export ASAN_OPTIONS=${ASAN_OPTIONS:-abort_on_error=1:detect_stack_use_after_return=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
status=0
summary=()
for fuzzer in $fuzzers; do
  seeds="$here/corpus/$fuzzer"
  work="$build/corpus/$fuzzer"
  artifacts="$build/artifacts/$fuzzer"
  log="$build/$fuzzer.log"
  mkdir -p "$work" "$artifacts" "$seeds"
  options=(-max_total_time="$seconds" -timeout=120 -rss_limit_mb=4096 -print_final_stats=1
           -artifact_prefix="$artifacts/")
  case $fuzzer in
    # Leaks are the C API fuzzer's job (LSan on there); here a leak check after every input
    # (TBB's and Embree's caches trip libFuzzer's malloc/free balance) would halve the rate.
    fuzz_differential) options+=(-max_len=2048 -detect_leaks=0) ;;
    fuzz_capi) options+=(-max_len=4096 -detect_leaks=1) ;;
  esac
  echo "---- $fuzzer (log: $log)"
  set +e
  "$build/$fuzzer" "${options[@]}" "$work" "$seeds" >"$log" 2>&1
  rc=$?
  set -e
  grep -E "^#[0-9]+[[:space:]]+(INITED|DONE)|^Done|at exit|^stat::" "$log" || true
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1 || true)
  cov=$(grep -E "^#[0-9]+[[:space:]]+(DONE|INITED|pulse|NEW|REDUCE)" "$log" | tail -1 |
        sed -n 's/.*cov: \([0-9]*\) ft: \([0-9]*\).*/cov \1, ft \2/p' || true)
  # The differential fuzzer prints two lines at exit (mesh and box scenes; geometry scenes).
  counts=$(grep "at exit" "$log" | sed 's/^[a-z_]* at exit: //' | awk 'NR > 1 {printf "; "} {printf "%s", $0}' || true)
  if [ $rc -ne 0 ]; then
    status=1
    crash=$(ls -t "$artifacts"/crash-* "$artifacts"/leak-* "$artifacts"/timeout-* "$artifacts"/oom-* 2>/dev/null | head -1 || true)
    echo "!!!! $fuzzer FAILED (exit $rc); the report:"
    grep -E -A40 "==== minkq|ERROR: (AddressSanitizer|LeakSanitizer|libFuzzer)|runtime error" "$log" | head -80 || true
    if [ -n "$crash" ]; then
      echo "!!!! minimising $crash (60 s)"
      "$build/$fuzzer" -minimize_crash=1 -max_total_time=60 -exact_artifact_path="$crash.min" "$crash" \
        >"$build/$fuzzer.minimize.log" 2>&1 || true
      [ -f "$crash.min" ] || cp "$crash" "$crash.min"
      echo "!!!! minimised reproducer: $crash.min (replay: $build/$fuzzer $crash.min); its report:"
      "$build/$fuzzer" "$crash.min" 2>&1 | grep -E -A60 "==== minkq|ERROR: |runtime error" | head -100 || true
    fi
    summary+=("$fuzzer: FAILED (exit $rc) after ${execs:-?} executions; ${cov}")
  else
    summary+=("$fuzzer: ok, ${execs:-?} executions, ${cov}; ${counts}")
  fi
done
oss_seconds=${MINKQ_FUZZ_OSS_CHECK:-10}
if [ "$oss_seconds" != 0 ]; then
  echo "---- the OSS-Fuzz / ClusterFuzzLite build (fuzz/oss-fuzz/check.sh $oss_seconds)"
  if MINKQ_FUZZ_BUILD=$build "$here/oss-fuzz/check.sh" "$oss_seconds"; then
    summary+=("OSS-Fuzz build: ok (fuzz/oss-fuzz/build.sh; each fuzzer ran ${oss_seconds} s on its seed corpus zip)")
  else
    status=1
    summary+=("OSS-Fuzz build: FAILED (fuzz/oss-fuzz/check.sh)")
  fi
fi
echo "==== fuzz/run.sh summary ($(date -u +%Y-%m-%dT%H:%MZ), ${seconds} s each, total $(( $(date +%s) - start )) s)"
printf '  %s\n' "${summary[@]}" | tee -a "$build/summary.txt"
exit $status
