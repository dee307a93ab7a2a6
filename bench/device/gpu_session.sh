#!/usr/bin/env bash
# A GPU session on the device machine, in stages. Every stage's detailed log goes to
# /tmp/minkq-logs; after each stage $OUT receives the running session.log, stages.tsv (stage,
# exit status, seconds) and logs.tar.gz (every log so far), so a call cut short still brings
# back everything up to its last finished stage (the device tool returns at most 8 files).
# State between calls lives in /tmp and build-sm90, which a warm machine keeps (about 30 s
# idle): make the calls back to back.
#
#   here:    bash bench/device/pack.sh                   # .carry/kit: Debian packages, ../shared
#            bash bench/device/gpu_session.sh --smoke    # the same stages, CUDA parts skipped
#   device, first call (about 5 min: the CUDA build is one long nvcc compile):
#            run(carry=[".carry/kit"], timeout_s=540, command="bash bench/device/gpu_session.sh")
#            = setup build memcheck gpu
#   device, second call, at once:
#            run(carry=[".carry/kit"], timeout_s=540,
#                command="bash bench/device/gpu_session.sh racecheck test fuzz")
#   third call, at once: command="bash bench/device/gpu_session.sh bench"
#   then Warp / Newton on the same GPU, per ../shared/tools/warp-for-device.sh (its last call
#   ends with: bash bench/device/gpu_session.sh warp)
# The device budget is 15 minutes a session, one call at most 10: the calls above and the
# Python ones below do not fit in one session together. The Python gpu tests alone (about 6 to
# 8 minutes of the 15; neither setup nor .carry/kit needed):
#   here:    bash bench/device/pack_python.sh   # .carry/py (cp312 CUDA wheel, newton; 14 MB),
#                                               # .carry/a, b, c (Warp, Newton; 38 + 38 + 23 MB)
#            mkdir -p /tmp/w && cp .carry/a/* .carry/b/* /tmp/w/ &&   # what calls 1 and 2 do
#              bash bench/device/gpu_session.sh --smoke python         # the gpu tests skip here
#   device, three calls back to back (/tmp/w must survive between them: ~30 s idle at most):
#     1 (the machine's start, 1 to 2 min): run(carry=[".carry/a"], timeout_s=120,
#                                             command="mkdir -p /tmp/w && cp .carry/a/* /tmp/w/")
#     2 (under a minute):  run(carry=[".carry/b"], timeout_s=120, command="cp .carry/b/* /tmp/w/")
#     3 (about 3 to 5 min: Warp's kernels compile on first use; pytest stops at 420 s):
#          run(carry=[".carry/c", ".carry/py"], timeout_s=540, command="bash bench/device/gpu_session.sh python")
#   then give_back. $OUT brings session.log and logs.tar.gz (python.log: pytest -v, every test).
#   Each call carries at most 64 MiB with the working tree (about 9 MB): 38, 38 and 36 + 9.
#
# Stages, in the order of their value:
#   setup      unpack the packages into /tmp/minkq-deps, ../shared from the kit; the machine,
#              the GPU and its compute mode
#   build      configure from an empty build folder (sm_90 only, benchmarks and fuzz_campaign
#              on) against the kit's packages, build everything
#   memcheck   compute-sanitizer memcheck on test_cuda, every launch synchronised
#              (CUDA_LAUNCH_BLOCKING=1, MINKQ_CUDA_SYNC=1): a fault is blamed on its kernel;
#              then the CUDA graph capture tests (CudaAsync.*) under memcheck as launched
#   gpu        the gpu-labelled tests (CPU == CUDA pairs, digests, work counts; device
#              buffers; errors)
#   racecheck  compute-sanitizer racecheck on test_cuda
#   test       the whole ctest suite
#   fuzz       fuzz_campaign (fuzz/campaign): the differential checks on the corpus and
#              $MINKQ_FUZZ_INPUTS (default 3000) random inputs, CPU == CUDA == Embree == oracle
#   bench      minkq_bench --backends cpu,cuda on $MINKQ_SUITES (default scenes,real,scale),
#              frames exported for Warp, and minkq_bench --suites count --backends cuda --large;
#              $OUT/results.tar.gz holds bench/results-style tables
#   warp       bench/peers/warp_baseline.py --device cuda:0 on the exported frames ($OUT/warp_gpu.md)
#   python     the Python package's gpu tests (pytest -m gpu on bindings/python/tests: Warp
#              ScopedCapture, the Newton detector's CUDA capture, torch CUDA graphs, CUDA
#              tensors through DLPack) on python3 with .carry/py's wheels (pack_python.sh) and
#              Warp unpacked from .carry/c over /tmp/w's parts, all in /tmp/site; fails when
#              the wheels or the parts are missing, or when the carried minkq sees no GPU;
#              under --smoke, pack_python.sh's Python 3.12 (the tests skip with their reasons)
#   profile    Nsight Compute on the 1M-triangle twisted sheet's query and refit kernels
#              ($OUT/ncu.txt)
# --smoke (first argument): on a machine without a GPU, the same script from an empty build
# folder with the CUDA backend off; the CUDA stages say they are skipped; bench runs --quick.
# Exit status: the first failing stage's, after every stage asked for has run.
set -uo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
kit=${MINKQ_KIT:-$root/.carry/kit}
out=${OUT:-/tmp/minkq-out}
deps=/tmp/minkq-deps
logs=/tmp/minkq-logs
results=/tmp/minkq-results
export_dir=/tmp/minkq-export
smoke=0
if [ "${1:-}" = "--smoke" ]; then smoke=1; shift; fi
[ $# -gt 0 ] || set -- setup build memcheck gpu
build=$root/build-sm90
[ $smoke = 1 ] && build=/tmp/minkq-smoke-build
mkdir -p "$out" "$logs"
exec > >(tee -a "$out/session.log") 2>&1
cd "$root"

# Packages unpacked into a prefix (not /): CMake finds them through CMAKE_PREFIX_PATH, the
# programs through LD_LIBRARY_PATH.
export CMAKE_PREFIX_PATH="$deps/usr${CMAKE_PREFIX_PATH:+:$CMAKE_PREFIX_PATH}"
export LD_LIBRARY_PATH="$deps/usr/lib/x86_64-linux-gnu${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
jobs=$(nproc)

have_gpu() { [ $smoke = 0 ] && command -v nvidia-smi > /dev/null && nvidia-smi -L > /dev/null 2>&1; }

stage_setup() {
  [ -d "$kit/debs" ] || { echo "no kit at $kit: run bench/device/pack.sh here and carry .carry/kit"; return 1; }
  rm -rf "$deps" && mkdir -p "$deps"
  for deb in "$kit"/debs/*.deb; do
    if command -v dpkg-deb > /dev/null; then
      dpkg-deb -x "$deb" "$deps" || return 1
    else  # a .deb is an ar archive around data.tar.*
      (t=$(mktemp -d) && cd "$t" && ar x "$deb" && tar xf data.tar.* -C "$deps") || return 1
    fi
  done
  cp -r "$kit/include" "$deps/usr/"  # FuzzedDataProvider.h for fuzz_campaign
  if [ ! -d "$root/../shared/data" ]; then
    rm -rf /tmp/minkq-shared && cp -r "$kit/shared" /tmp/minkq-shared && ln -sfn /tmp/minkq-shared "$root/../shared"
  fi
  if have_gpu; then
    nvidia-smi -L
    # Exclusive-process mode would fail a second CUDA process: the gpu tests hold a ctest
    # RESOURCE_LOCK, so they run one at a time either way.
    nvidia-smi --query-gpu=name,compute_mode,driver_version,memory.total,clocks.max.sm --format=csv
  else
    echo "no GPU here (smoke run or no driver)"
  fi
  command -v nvcc > /dev/null && nvcc --version | tail -2
  command -v compute-sanitizer > /dev/null && compute-sanitizer --version | head -2
  g++ --version | head -1
  cmake --version | head -1
  echo "$(nproc) CPUs, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2-)"
}

stage_build() {
  rm -rf "$build"  # never a stale cache: configure finds the kit's packages or fails
  if [ $smoke = 1 ]; then
    cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release -DMINKQ_WITH_CUDA=OFF -DMINKQ_BUILD_BENCH=ON \
      -DMINKQ_BUILD_FUZZ_CAMPAIGN=ON > "$logs/configure.log" 2>&1 || { tail -30 "$logs/configure.log"; return 1; }
  else
    cmake --preset sm90 -DMINKQ_BUILD_BENCH=ON -DMINKQ_BUILD_FUZZ_CAMPAIGN=ON > "$logs/configure.log" 2>&1 ||
      { tail -30 "$logs/configure.log"; return 1; }
  fi
  grep -E "^(TBB_DIR|embree_DIR|GTest_DIR|tinyobjloader_DIR|XXHASH_LIBRARY)" "$build/CMakeCache.txt"
  # The kit's packages, not the machine's: anything else means the kit is incomplete.
  if grep -E "^(TBB_DIR|embree_DIR|GTest_DIR|tinyobjloader_DIR)" "$build/CMakeCache.txt" | grep -v "$deps" | grep -q .; then
    echo "build: a dependency was found outside the kit ($deps)"
    [ $smoke = 1 ] || return 1
  fi
  cmake --build "$build" -j "$jobs" > "$logs/build.log" 2>&1 || { grep -E "error|Error" "$logs/build.log" | head -40; return 1; }
  grep -i "warning" "$logs/build.log" | head -20
  echo "built: $(ls "$build/bin" | tr '\n' ' ')"
}

# compute-sanitizer --tool $1 on the CUDA test binary, every launch synchronised.
sanitize() {
  have_gpu || { echo "skipped: no GPU"; return 0; }
  command -v compute-sanitizer > /dev/null || { echo "no compute-sanitizer on this machine"; return 1; }
  CUDA_LAUNCH_BLOCKING=1 MINKQ_CUDA_SYNC=1 timeout "${MINKQ_SANITIZER_TIMEOUT:-240}" \
    compute-sanitizer --tool "$1" --error-exitcode 99 \
    "$build/tests/test_cuda" > "$logs/$1.log" 2>&1
  local status=$?
  grep -E "ERROR SUMMARY|RACECHECK SUMMARY|PASSED|FAILED|Skipped|^=========" "$logs/$1.log" | head -40
  return $status
}
# memcheck, then the captured-graph tests under memcheck again without blocking launches (which
# capture does not mix with): a replay that touches freed or outgrown scratch is reported there.
stage_memcheck() {
  sanitize memcheck || return $?
  have_gpu || return 0
  timeout "${MINKQ_SANITIZER_TIMEOUT:-240}" compute-sanitizer --tool memcheck --error-exitcode 99 \
    "$build/tests/test_cuda" --gtest_filter='CudaAsync.*' > "$logs/memcheck-capture.log" 2>&1
  local status=$?
  grep -E "ERROR SUMMARY|PASSED|FAILED|Skipped|^=========" "$logs/memcheck-capture.log" | head -40
  return $status
}
stage_racecheck() { sanitize racecheck; }

stage_gpu() {
  ctest --test-dir "$build" -L gpu --output-on-failure --timeout 600 > "$logs/gpu.log" 2>&1
  local status=$?
  grep -E "tests passed|tests failed|\*\*\*|Failed|Skipped" "$logs/gpu.log" | tail -30
  return $status
}

stage_test() {
  ctest --test-dir "$build" -j "$jobs" --output-on-failure --timeout 1200 > "$logs/ctest.log" 2>&1
  local status=$?
  grep -E "tests passed|tests failed|\*\*\*|Failed" "$logs/ctest.log" | tail -40
  return $status
}

stage_fuzz() {
  # The differential checks on the corpus and on MINKQ_FUZZ_INPUTS random inputs, every scene
  # on the CPU, each CUDA device, Embree and the oracle; the count goes to fuzz/RESULTS.md.
  local seed=${MINKQ_FUZZ_SEED:-$(date +%s)}
  MINKQ_FUZZ_THREADS=$jobs "$build/bin/fuzz_campaign" --inputs "${MINKQ_FUZZ_INPUTS:-3000}" --seed "$seed" \
    fuzz/corpus/fuzz_differential > "$logs/fuzz.log" 2>&1
  local status=$?
  grep -E "devices:|fuzz_campaign:|at exit|MISMATCH" "$logs/fuzz.log" | head -10
  [ $status = 0 ] || tail -60 "$logs/fuzz.log"
  return $status
}

stage_bench() {
  local args=(--backends cpu,cuda --suites "${MINKQ_SUITES:-scenes,real,scale}" --out "$results" --export "$export_dir")
  [ $smoke = 1 ] && args=(--quick --out "$results" --export "$export_dir")
  rm -rf "$results" "$export_dir"
  mkdir -p "$results"
  "$build/bin/minkq_bench" "${args[@]}" > "$logs/bench.log" 2>&1
  local status=$?
  tail -20 "$logs/bench.log"
  # Count-only queries against stored ones on the GPU (count_cuda.md), beside the CPU's count.md.
  local count=(--suites count --backends cuda --large --out "$results")
  [ $smoke = 1 ] && count=(--suites count --backends cpu --quick --out "$results")  # no GPU there
  "$build/bin/minkq_bench" "${count[@]}" > "$logs/count.log" 2>&1 || status=1
  tail -2 "$logs/count.log"
  nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.mem --format=csv > "$results/device.txt" 2>&1 || true
  tar czf "$out/results.tar.gz" -C "$results" .
  return $status
}

stage_warp() {
  [ -d /tmp/site/warp ] || { echo "no Warp in /tmp/site: unpack it first (../shared/tools/warp-for-device.sh)"; return 1; }
  [ -f "$results/rows.csv" ] || { echo "no $results/rows.csv: run the bench stage on this machine first"; return 1; }
  PYTHONPATH=/tmp/site${PYTHONPATH:+:$PYTHONPATH} python3 bench/peers/warp_baseline.py "$export_dir" "$results/rows.csv" \
    "$out/warp_gpu.md" --device cuda:0
}

# The Python package's gpu tests (bindings/python/tests, marker gpu: Warp ScopedCapture of the
# stream-ordered calls, the Newton detector's CUDA capture, torch CUDA graphs, CUDA tensors
# through DLPack) on the carried cp312 wheel (CUDA libminkq) with Warp and Newton, all in /tmp/site.
stage_python() {
  local py=${MINKQ_PYTHON:-python3} site=/tmp/site parts=${MINKQ_WARP_PARTS:-$root/.carry}
  local pykit=${MINKQ_PY_KIT:-$root/.carry/py}
  # Here the cp312 wheel needs a Python 3.12: pack_python.sh's (numpy and pytest, no torch).
  if [ $smoke = 1 ] && [ -z "${MINKQ_PYTHON:-}" ] && [ -x "$root/build-sm90-py/venv/bin/python" ]; then
    py=$root/build-sm90-py/venv/bin/python
  fi
  if ! ls "$pykit"/wheels/minkq-*.whl > /dev/null 2>&1; then
    echo "no minkq wheel in $pykit/wheels: run bench/device/pack_python.sh here and carry .carry/py"
    return 1
  fi
  # Warp and Newton: .carry/c unpacked over the two parts that the calls before this one left in
  # /tmp/w (../shared/tools/warp-for-device.sh), unless an earlier call did it.
  if [ ! -f "$site/warp/bin/warp.so" ]; then
    if [ -f /tmp/w/part00 ] && [ -f /tmp/w/part01 ] && [ -f "$parts/c/unpack.sh" ]; then
      # unpack.sh imports Warp with python3: the one the tests run under.
      PATH="$(dirname "$(command -v "$py")"):$PATH" bash "$parts/c/unpack.sh" ||
        { echo "python: unpacking Warp failed"; return 1; }
    else
      echo "no Warp in $site and nothing to unpack it from (/tmp/w: $(ls /tmp/w 2> /dev/null | tr '\n' ' ')," \
        "$parts/c/unpack.sh: $([ -f "$parts/c/unpack.sh" ] && echo there || echo missing)): make the calls" \
        "carrying .carry/a and .carry/b just before this one, which carries .carry/c and .carry/py"
      return 1
    fi
  fi
  # minkq, and Newton at the version the tests pin over the one .carry/c held.
  "$py" -m pip install -q --disable-pip-version-check --no-index --no-deps --no-compile --no-cache-dir --upgrade \
    --target "$site" "$pykit"/wheels/*.whl > "$logs/python-install.log" 2>&1 || { tail -20 "$logs/python-install.log"; return 1; }
  [ -f "$pykit/VERSIONS" ] && sed 's/^/kit: /' "$pykit/VERSIONS"
  local env=(env PYTHONPATH="$site${PYTHONPATH:+:$PYTHONPATH}" PYTHONUNBUFFERED=1)
  local expect=any
  have_gpu && expect=gpu  # there every gpu test should run: a minkq that sees no GPU fails here
  "${env[@]}" "$py" - "$site" "$expect" <<'EOF' || return 1
import importlib, sys
import minkq
assert minkq.__file__.startswith(sys.argv[1]), f"minkq from {minkq.__file__}, not the carried wheel"
print(f"python {sys.version.split()[0]}; minkq {minkq.__file__}, CUDA devices {minkq.cuda_device_count()}")
if sys.argv[2] == "gpu" and minkq.cuda_device_count() == 0:
    sys.exit("python: the carried minkq sees no CUDA device (a CPU-only libminkq, or its CUDA runtime and the driver disagree)")
for name in ("numpy", "warp", "newton", "torch", "cupy"):
    try:
        module = importlib.import_module(name)
        print(f"  {name} {getattr(module, '__version__', None) or getattr(getattr(module, 'config', None), 'version', '?')}")
    except Exception as e:  # the tests that need it skip and say so
        print(f"  {name}: not importable ({type(e).__name__}: {e})")
EOF
  # faulthandler_timeout: a test hung on the GPU dumps every thread's stack into the log.
  "${env[@]}" timeout "${MINKQ_PYTEST_TIMEOUT:-420}" "$py" -m pytest -m gpu -v -rfEs -p no:cacheprovider \
    -o faulthandler_timeout=240 bindings/python/tests > "$logs/python.log" 2>&1
  local status=$?
  [ $status = 124 ] && echo "python: pytest ran past ${MINKQ_PYTEST_TIMEOUT:-420} s (log: python.log)"
  grep -E " (PASSED|FAILED|ERROR|SKIPPED)|^(FAILED|ERROR|SKIPPED) |^=+ .*(passed|failed|skipped|error|deselected)" \
    "$logs/python.log" | tail -40
  return $status
}

stage_profile() {
  # Nsight Compute on the issue's target scene, the 1M-triangle twisted sheet at r = 0.25x mean
  # edge (minkq demo --size 708: every mode, checked against the oracle): the query and refit
  # kernels' throughput, memory, occupancy and warp stalls, to say what limits them.
  have_gpu || { echo "skipped: no GPU"; return 0; }
  command -v ncu > /dev/null || { echo "no ncu on this machine"; return 1; }
  ncu --kernel-name regex:"query_kernel|refit_kernel" --launch-count 40 --section SpeedOfLight \
    --section MemoryWorkloadAnalysis --section Occupancy --section LaunchStats --section WarpStateStats \
    "$build/bin/minkq" demo --backend cuda --size 708 > "$out/ncu.txt" 2>&1
  local status=$?
  grep -E "query_kernel|refit_kernel|Duration|Memory Throughput|Compute \(SM\) Throughput|Achieved Occupancy" \
    "$out/ncu.txt" | head -80
  return $status
}

first_failure=0
for stage in "$@"; do
  echo "== $stage ($(date -u +%H:%M:%S))"
  started=$SECONDS
  case "$stage" in
    setup) stage_setup ;; build) stage_build ;; memcheck) stage_memcheck ;; gpu) stage_gpu ;;
    racecheck) stage_racecheck ;; test) stage_test ;; fuzz) stage_fuzz ;; bench) stage_bench ;; warp) stage_warp ;;
    python) stage_python ;; profile) stage_profile ;;
    *) echo "unknown stage $stage"; false ;;
  esac
  status=$?
  echo "== $stage: exit $status, $((SECONDS - started)) s"
  printf '%s\t%s\t%s\n' "$stage" "$status" "$((SECONDS - started))" >> "$out/stages.tsv"
  tar czf "$out/logs.tar.gz" -C "$logs" . 2> /dev/null
  [ $status != 0 ] && [ $first_failure = 0 ] && first_failure=$status
done
exit $first_failure
