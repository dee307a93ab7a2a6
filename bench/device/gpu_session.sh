#!/usr/bin/env bash
# A GPU session on the device machine in calls of stages, planned to fit a session's device time:
# 15 minutes, of which a machine's start takes 1 to 2, one command at most 10 (device/README.md).
# Every stage runs under its cap (timeout: exit 124 past it). After each stage $OUT receives
# session.log, stages.tsv (stage, exit status, seconds) and logs.tar.gz (every stage's log so
# far, from /tmp/minkq-logs), so a call cut short still brings back what it finished.
#
#   here:   bash bench/device/pack.sh                        # .carry/kit: Debian packages, ../shared
#           bash bench/device/gpu_session.sh --plan          # the calls and their run() lines
#           bash bench/device/gpu_session.sh --smoke --call 1; ... --smoke --call 2
#   device: run(carry=[".carry/kit"], timeout_s=<T1>, command="bash bench/device/gpu_session.sh --call 1")
#           at once (build-sm90 and /tmp last while the machine is warm, about 30 s idle):
#           run(carry=[".carry/kit"], timeout_s=<T2>, command="bash bench/device/gpu_session.sh --call 2")
#           give_back. The "later" stages below belong to another session's 15 minutes:
#   racecheck, fuzz and profile after a build (--call 1's stages, then those), and test; warp
#   after bench on the same machine (it reads bench's frames and rows.csv) with Warp unpacked per
#   ../shared/tools/warp-for-device.sh. The Python gpu tests carry Warp in three parts over one
#   call's 64 MiB (bash bench/device/pack_python.sh here: .carry/py, .carry/a, b, c), back to back:
#     run(carry=[".carry/a"], timeout_s=120, command="mkdir -p /tmp/w && cp .carry/a/* /tmp/w/")
#     run(carry=[".carry/b"], timeout_s=120, command="cp .carry/b/* /tmp/w/")
#     run(carry=[".carry/c", ".carry/py"], timeout_s=540, command="bash bench/device/gpu_session.sh python")
#   (here: mkdir -p /tmp/w && cp .carry/a/* .carry/b/* /tmp/w/ && gpu_session.sh --smoke python).
#
# The budget: one line a stage, "call stage expected cap" in seconds of the device machine. The
# expectations scale --smoke's times on the 2-core helper machine (shared with other builds) by
# its cores to the device's 16; the CUDA compile (backend.cu) is one serial nvcc job, as slow
# there per core as here: see the notes beside each line. --plan checks that call 1 (with the
# start and its copies) stays within about 6 minutes, each command within its 10, and the whole
# session within 15 minutes; tests/CMakeLists.txt runs that check under ctest (label cpu).
plan=(
  # setup: unpack the kit (12 .deb, 14 MB of meshes), query the GPU. Here: under a second.
  "1 setup 5 20"
  # build: configure from nothing (4 s here), then test_cuda: the library, the oracle, testing/
  # and the tests. Here it took 164 s of CPU, of which backend.cu's nvcc (cicc, ptxas for sm_90)
  # 98 s alone: one serial job and the critical path, taken as long there per core; the other
  # 66 s spread over 16 cores beside it, then capi/ and the test sources (about 15 s). The scenes
  # of many geometries (issue 53) made backend.cu about a tenth slower (its minkq_core build here:
  # 174 s against 162 s at 86b73bc, the same machine) and added four job-pass units of about 70 s
  # each (cuda/job_passes_*.cu), compiled beside it.
  "1 build 135 190"
  # gpu: the gpu-labelled tests, 25 processes of test_cuda one after another on small scenes
  # (3000-triangle soup, 40x40 sheet): a CUDA context and a module load each (about a second).
  "1 gpu 30 60"
  # memcheck: the chosen tests (memcheck_tests) with blocking launches, then the capture tests:
  # two sanitizer processes, each instrumenting the module first, on the same small scenes (a
  # guess: nothing here runs it; the cap bounds it, and the gpu stage's time will calibrate it).
  "2 memcheck 60 120"
  # bench: minkq_bench on top of call 1's build (its own sources: about 20 s of CPU here), the
  # small scenes suite on cpu and cuda (14 s of CPU here on the cpu backend: the 130k-triangle
  # sheet, the oracle, Embree), then the count suite on cuda with the 1M sheet (15 repeats).
  "2 bench 45 90"
  # leaf: a copy with kLeafSize 16 built from nothing for minkq_bench alone (here, with CUDA for
  # sm_90: 164 s of CPU, as call 1's build, backend.cu's 98 s again the critical path), then the
  # small scenes suite on cuda alone (no Embree) with each.
  "2 leaf 155 210"
  # Later, in another session: no budget here, each with its cap.
  "later racecheck 200 300" "later test 300 540" "later fuzz 300 540" "later warp 120 300"
  "later python 300 480" "later profile 120 300"
)
start_s=120       # a machine's start: 1 to 2 minutes (device/README.md)
copy_s=15         # per call: the tree and .carry/kit out (about 33 MB), results back
gap_s=15          # between calls: the next one is sent at once
margin_s=10       # per call: the script's own start, the tars after each stage
call1_limit_s=360 # the issue's "call 1 at most about 6 minutes", the start included
command_limit_s=600
budget_s=900
set -uo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
self=$root/bench/device/gpu_session.sh  # each stage runs in a child of its own: $self --stage
kit=${MINKQ_KIT:-$root/.carry/kit}
out=${OUT:-/tmp/minkq-out}
deps=/tmp/minkq-deps
logs=/tmp/minkq-logs
results=/tmp/minkq-results
export_dir=/tmp/minkq-export
smoke=0 mode=run call="" one=""
while [ $# -gt 0 ]; do
  case "$1" in
    --smoke) smoke=1; shift ;;  # no GPU: the CUDA backend off, the CUDA parts skipped with a reason
    --plan) mode=plan; shift ;;
    --call) call=${2:-}; shift 2 || { echo "--call needs a number"; exit 2; } ;;
    --stage) mode=stage; one=${2:-}; shift 2 || exit 2 ;;  # internal: one stage, under the caller's cap
    --*) echo "gpu_session.sh: unknown option $1 (--smoke, --plan, --call N, or stage names)"; exit 2 ;;
    *) break ;;
  esac
done
build=$root/build-sm90
[ $smoke = 1 ] && build=/tmp/minkq-smoke-build
smoke_factor=${MINKQ_SMOKE_CAP_FACTOR:-20}  # --smoke's caps: 2 shared cores against 16
jobs=$(nproc)
# Packages unpacked into a prefix (not /): CMake finds them through CMAKE_PREFIX_PATH, the
# programs through LD_LIBRARY_PATH.
export CMAKE_PREFIX_PATH="$deps/usr${CMAKE_PREFIX_PATH:+:$CMAKE_PREFIX_PATH}"
export LD_LIBRARY_PATH="$deps/usr/lib/x86_64-linux-gnu${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"

# A stage's cap: the plan's, or MINKQ_CAP_<stage> (seconds) where set.
cap_of() {
  local override="MINKQ_CAP_$1" line n s e c
  [ -n "${!override:-}" ] && { echo "${!override}"; return; }
  for line in "${plan[@]}"; do
    read -r n s e c <<< "$line"
    [ "$s" = "$1" ] && { echo "$c"; return; }
  done
  echo $command_limit_s
}
stages_of_call() {
  local line n s e c
  for line in "${plan[@]}"; do
    read -r n s e c <<< "$line"
    [ "$n" = "$1" ] && printf '%s ' "$s"
  done
}

# Prints the calls with their stages, sums and run() lines; non-zero when a stage is unknown,
# call 1 as expected passes its 6 minutes, a call's caps pass one command's limit, or the whole
# session at the caps (every stage cut at its cap) passes the budget.
plan_check() {
  local bad=0 session=$start_s calls=0 c line n s e cap
  for line in "${plan[@]}"; do
    read -r n s e cap <<< "$line"
    declare -F "stage_$s" > /dev/null || { echo "plan: no stage $s"; bad=1; }
    [[ "$e" =~ ^[0-9]+$ && "$cap" =~ ^[0-9]+$ ]] || { echo "plan: $line: expected and cap must be seconds"; bad=1; }
  done
  for c in 1 2; do
    local expected=0 caps=0 list=""
    for line in "${plan[@]}"; do
      read -r n s e cap <<< "$line"
      [ "$n" = "$c" ] || continue
      cap=$(cap_of "$s")
      [ "$e" -le "$cap" ] || { echo "plan: $s expects $e s, over its cap $cap s"; bad=1; }
      expected=$((expected + e)) caps=$((caps + cap)) list="$list $s $e/$cap"
    done
    # The call as expected (with the start for call 1), and the command's timeout: its caps.
    local timeout_s=$((caps + margin_s)) whole=$((copy_s + expected + margin_s))
    [ "$c" = 1 ] && whole=$((whole + start_s))
    [ $calls -gt 0 ] && session=$((session + gap_s))
    session=$((session + copy_s + caps + margin_s)) calls=$((calls + 1))
    printf 'call %s:%s (expected/cap s)\n  stages expected %s s, capped at %s s; the call expected %s s with %s\n' \
      "$c" "$list" "$expected" "$caps" "$whole" "$([ "$c" = 1 ] && echo "the start and the copies" || echo "the copies")"
    printf '  run(carry=[".carry/kit"], timeout_s=%s, command="bash bench/device/gpu_session.sh --call %s")\n' "$timeout_s" "$c"
    if [ $timeout_s -gt $command_limit_s ]; then echo "  OVER: a command runs at most $command_limit_s s"; bad=1; fi
    if [ "$c" = 1 ] && [ $whole -gt $call1_limit_s ]; then echo "  OVER: call 1 is expected within $call1_limit_s s with the start"; bad=1; fi
  done
  printf 'session at the caps: start %s + calls + gaps %s = %s s of %s s' "$start_s" "$gap_s" "$session" "$budget_s"
  if [ $session -gt $budget_s ]; then echo ": OVER"; bad=1; else echo " ($((budget_s - session)) s to spare)"; fi
  echo "later (another session):$(for line in "${plan[@]}"; do read -r n s e cap <<< "$line"; [ "$n" = later ] && printf ' %s %s/%s' "$s" "$e" "$(cap_of "$s")"; done)"
  for line in "${plan[@]}"; do  # each of those at least fits one command
    read -r n s e cap <<< "$line"
    [ "$n" = later ] && [ $(($(cap_of "$s") + margin_s)) -gt $command_limit_s ] && { echo "  OVER: $s alone passes one command"; bad=1; }
  done
  return $bad
}

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

# Configures $build from nothing: sm_90 only against the kit's packages (here, under --smoke,
# the CUDA backend off), benchmarks and fuzz_campaign on so that later stages only add targets.
configure() {
  # A call that found a fresh machine (call 1's went back) unpacks the kit first.
  [ -d "$deps/usr" ] || { echo "no kit unpacked in $deps: setup first"; stage_setup > "$logs/setup.log" 2>&1; } ||
    { tail -20 "$logs/setup.log"; return 1; }
  rm -rf "$build"  # never a stale cache: configure finds the kit's packages or fails
  local flags=(-DMINKQ_BUILD_BENCH=ON -DMINKQ_BUILD_FUZZ_CAMPAIGN=ON)
  if [ $smoke = 1 ]; then
    cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release -DMINKQ_WITH_CUDA=OFF "${flags[@]}" > "$logs/configure.log" 2>&1
  else
    cmake --preset sm90 "${flags[@]}" > "$logs/configure.log" 2>&1
  fi || { tail -30 "$logs/configure.log"; return 1; }
  grep -E "^(TBB_DIR|embree_DIR|GTest_DIR|tinyobjloader_DIR|XXHASH_LIBRARY)" "$build/CMakeCache.txt"
  # The kit's packages, not the machine's: anything else means the kit is incomplete.
  if grep -E "^(TBB_DIR|embree_DIR|GTest_DIR|tinyobjloader_DIR)" "$build/CMakeCache.txt" | grep -v "$deps" | grep -q .; then
    echo "build: a dependency was found outside the kit ($deps)"
    [ $smoke = 1 ] || return 1
  fi
}
# Builds the targets, configuring first where this machine has no build yet (a call that found
# a fresh machine: it then pays the build again, within the stage's cap).
build_targets() {
  [ -f "$build/CMakeCache.txt" ] || configure || return 1
  echo "building $* ($jobs jobs)"
  cmake --build "$build" -j "$jobs" --target "$@" >> "$logs/build.log" 2>&1 ||
    { grep -E "error|Error" "$logs/build.log" | head -40; return 1; }
}

# Only what the gpu-labelled tests run: test_cuda, and test_mpi where MPI was found.
stage_build() {
  configure || return 1
  local targets=(test_cuda)
  cmake --build "$build" --target help 2> /dev/null | grep -q ' test_mpi$' && targets+=(test_mpi)
  build_targets "${targets[@]}" || return 1
  grep -i "warning" "$logs/build.log" | head -20
  ctest --test-dir "$build" -N -L gpu | tail -1
}

stage_gpu() {
  [ -x "$build/tests/test_cuda" ] || { echo "no $build/tests/test_cuda: run the build stage first"; return 1; }
  ctest --test-dir "$build" -L gpu --output-on-failure --timeout 120 > "$logs/gpu.log" 2>&1
  local status=$?
  grep -E "tests passed|tests failed|\*\*\*|Failed|Skipped" "$logs/gpu.log" | tail -30
  return $status
}

# memcheck on one test per kernel family, every launch synchronised (CUDA_LAUNCH_BLOCKING=1,
# MINKQ_CUDA_SYNC=1: a fault is blamed on its kernel). All of test_cuda under memcheck would not
# fit the call; these reach every kernel of core/src/cuda at least once:
memcheck_tests=(
  Cuda.rebuild_and_tree_growth_match_cpu   # build: boxes, Morton codes, the radix sort, Karras,
                                           # collapse, node counts, area cost; node storage grown
  Cuda.refit_matches_cpu_after_moving_vertices                      # refit: arrival flags, atomics
  Cuda.capacity_returns_the_exact_count_and_writes_nothing_past_the_buffer  # VT/EE query at its capacity
  Cuda.device_output_buffers_match_host_output_and_respect_capacity # canonical sort: pack and unpack
  Cuda.count_only_queries_match_cpu_counts_blocking_and_async       # counts-only emission
  Cuda.user_box_queries_match_cpu_for_every_shape_and_after_refit   # user shapes: leaf groups, fill/scatter
  Cuda.swept_queries_match_cpu                                      # swept shapes in the query kernel
  Cuda.float64_vertices_from_host_and_device_memory_match_cpu       # the float64 and float32 gathers
  Cuda.non_finite_device_vertices_name_the_first_bad_vertex         # checked gather, first non-finite, commit
  Cuda.scenes_of_many_geometries_match_cpu_over_moves               # job passes: self, cross, reversed
)
# Then the captured graphs, launched as the tests launch them (capture does not mix with blocking
# launches): a replay that touches freed or outgrown scratch is reported there.
capture_tests=(
  CudaAsync.captured_refit_and_queries_replay_over_moving_vertices
  CudaAsync.blocking_rebuilds_and_queries_between_replays_keep_a_captured_graph_valid
  CudaGeometriesAsync.captured_step_replays_over_moving_geometries  # job passes, stream-ordered
)
# Each name must still name a test in test_cuda's sources (a renamed test fails here, also under
# --smoke, whose CPU-only test_cuda lacks the tests that need the CUDA runtime), and each run
# must pass as many tests as it names (a filter that matched less is no check).
check_tests() {
  local name
  for name in "$@"; do
    grep -qE "^TEST_F\(${name%%.*}, ${name#*.}\)" tests/test_cuda*.cpp ||
      { echo "memcheck: $name is no test of test_cuda (renamed?): update memcheck_tests"; return 1; }
  done
}
sanitize() {  # tool, log name, how many tests, gtest filter, environment...
  local tool=$1 log=$2 count=$3 filter=$4
  shift 4
  env "$@" compute-sanitizer --tool "$tool" --error-exitcode 99 "$build/tests/test_cuda" --gtest_filter="$filter" \
    > "$logs/$log.log" 2>&1
  local status=$?
  grep -E "ERROR SUMMARY|RACECHECK SUMMARY|tests? ran|PASSED|FAILED|Skipped|^=========" "$logs/$log.log" | head -40
  [ $status != 0 ] && return $status
  [ "$count" = any ] || grep -qE "^\[  PASSED  \] $count tests?\.$" "$logs/$log.log" ||
    { echo "$log: not all $count tests ran and passed"; return 1; }
}
stage_memcheck() {
  build_targets test_cuda || return 1  # nothing to do where call 1 built it on this machine
  check_tests "${memcheck_tests[@]}" "${capture_tests[@]}" || return 1
  have_gpu || { echo "skipped: no GPU (the ${#memcheck_tests[@]} + ${#capture_tests[@]} tests are named in test_cuda)"; return 0; }
  command -v compute-sanitizer > /dev/null || { echo "no compute-sanitizer on this machine"; return 1; }
  local IFS=:
  sanitize memcheck memcheck ${#memcheck_tests[@]} "${memcheck_tests[*]}" CUDA_LAUNCH_BLOCKING=1 MINKQ_CUDA_SYNC=1 ||
    return $?
  sanitize memcheck memcheck-capture ${#capture_tests[@]} "${capture_tests[*]}"
}
stage_racecheck() {
  build_targets test_cuda || return 1
  have_gpu || { echo "skipped: no GPU"; return 0; }
  sanitize racecheck racecheck any '*' CUDA_LAUNCH_BLOCKING=1 MINKQ_CUDA_SYNC=1
}

stage_test() {
  build_targets all || return 1
  ctest --test-dir "$build" -j "$jobs" --output-on-failure --timeout 1200 > "$logs/ctest.log" 2>&1
  local status=$?
  grep -E "tests passed|tests failed|\*\*\*|Failed" "$logs/ctest.log" | tail -40
  return $status
}

stage_fuzz() {
  build_targets fuzz_campaign || return 1
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

# The CUDA benchmark tables: the scenes suite (the eight Newton scenes and the twisted sheet;
# build, refit, VT/EE in every mode, Embree) on cpu and cuda, small (2 frames, 3 repeats), its
# frames exported for Warp; then count-only queries against stored ones on cuda (count_cuda.md),
# the 1M sheet included. $OUT/results.tar.gz holds the bench/results-style tables.
bench_small=(--suites scenes --frames 2 --repeats 3)
stage_bench() {
  build_targets minkq_bench || return 1
  rm -rf "$results" "$export_dir"
  mkdir -p "$results"
  local args=(--backends cpu,cuda "${bench_small[@]}" --out "$results" --export "$export_dir")
  local count=(--suites count --backends cuda --large --out "$results")
  if [ $smoke = 1 ]; then  # the same commands on the CPU backend alone, and --quick
    echo "cuda: skipped, no GPU (the cpu backend alone, --quick)"
    args=(--backends cpu --quick "${bench_small[@]:0:2}" --out "$results" --export "$export_dir")
    count=(--suites count --backends cpu --quick --out "$results")
  fi
  "$build/bin/minkq_bench" "${args[@]}" > "$logs/bench.log" 2>&1
  local status=$?
  tail -20 "$logs/bench.log"
  "$build/bin/minkq_bench" "${count[@]}" > "$logs/count.log" 2>&1 || status=1
  tail -2 "$logs/count.log"
  nvidia-smi --query-gpu=name,driver_version,clocks.sm,clocks.mem --format=csv > "$results/device.txt" 2>&1 || true
  tar czf "$out/results.tar.gz" -C "$results" .
  return $status
}

# The CUDA leaf size, 16 or 32, by measurement: kLeafSize is a compile-time constant of the
# library (core/include/minkq/tree.h), so a copy of the source with 16 is built beside (another
# backend.cu compile: most of this stage), then the scenes suite runs on cuda with each.
# $results/leaf16 and leaf32 (in results.tar.gz) hold the two tables.
leaf_header=core/include/minkq/tree.h
leaf_from='constexpr int32_t kLeafSize = 32;'
leaf_to='constexpr int32_t kLeafSize = 16;'
stage_leaf() {
  local dir=/tmp/minkq-leaf16 entry
  [ "$(grep -cxF "$leaf_from" "$leaf_header")" = 1 ] ||
    { echo "leaf: $leaf_header does not hold '$leaf_from' once: update stage_leaf"; return 1; }
  rm -rf "$dir" && mkdir -p "$dir/src"
  for entry in "$root"/* "$root"/.[!.]*; do
    case ${entry##*/} in build-* | build | .carry | .git | .gl | .whl | target) continue ;; esac
    cp -r "$entry" "$dir/src/"
  done
  sed -i "s/^${leaf_from}\$/${leaf_to}/" "$dir/src/$leaf_header"
  # The copy differs from the source in that line alone.
  [ "$(diff "$leaf_header" "$dir/src/$leaf_header" | grep -c '^[<>]')" = 2 ] && grep -qxF "$leaf_to" "$dir/src/$leaf_header" ||
    { echo "leaf: the copy's $leaf_header is not the source's with '$leaf_to'"; return 1; }
  build_targets minkq_bench || return 1  # kLeafSize 32
  local cuda=(-DMINKQ_WITH_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90)  # as the sm90 preset
  [ $smoke = 1 ] && cuda=(-DMINKQ_WITH_CUDA=OFF)
  cmake -S "$dir/src" -B "$dir/build" -DCMAKE_BUILD_TYPE=Release "${cuda[@]}" -DMINKQ_BUILD_BENCH=ON \
    -DMINKQ_BUILD_TESTS=OFF -DMINKQ_BUILD_EXAMPLES=OFF > "$logs/leaf-configure.log" 2>&1 ||
    { tail -30 "$logs/leaf-configure.log"; return 1; }
  have_gpu || { echo "leaf: the copy with kLeafSize 16 configures; its build and the cuda runs skipped: no GPU"; return 0; }
  cmake --build "$dir/build" -j "$jobs" --target minkq_bench > "$logs/leaf-build.log" 2>&1 ||
    { grep -E "error|Error" "$logs/leaf-build.log" | head -40; return 1; }
  local status=0 leaf bin
  for leaf in 32 16; do
    bin=$build/bin/minkq_bench
    [ $leaf = 16 ] && bin=$dir/build/bin/minkq_bench
    "$bin" --backends cuda --no-embree "${bench_small[@]}" --data "$root/../shared/data" --out "$results/leaf$leaf" \
      > "$logs/leaf$leaf.log" 2>&1 || status=1
    echo "-- kLeafSize $leaf"
    tail -12 "$logs/leaf$leaf.log"
  done
  mkdir -p "$results" && tar czf "$out/results.tar.gz" -C "$results" .
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
  build_targets minkq_cli || return 1
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

case $mode in
  plan) plan_check; exit $? ;;
  stage) cd "$root" && mkdir -p "$out" "$logs" && "stage_$one"; exit $? ;;
esac
if [ -n "$call" ]; then
  [ $# = 0 ] || { echo "gpu_session.sh: --call $call or stage names, not both"; exit 2; }
  set -- $(stages_of_call "$call")
  [ $# -gt 0 ] || { echo "gpu_session.sh: the plan has no call $call"; exit 2; }
fi
[ $# -gt 0 ] || set -- $(stages_of_call 1)
for stage in "$@"; do
  declare -F "stage_$stage" > /dev/null || { echo "gpu_session.sh: unknown stage $stage"; exit 2; }
done
mkdir -p "$out" "$logs"
exec > >(tee -a "$out/session.log") 2>&1
cd "$root"
first_failure=0
for stage in "$@"; do
  cap=$(cap_of "$stage")
  [ $smoke = 1 ] && cap=$((cap * smoke_factor))
  echo "== $stage ($(date -u +%H:%M:%S), cap $cap s)"
  started=$SECONDS
  # A child under the cap: timeout ends its whole process group (ctest, compute-sanitizer, nvcc).
  timeout -k 10 "$cap" "$BASH" "$self" $([ $smoke = 1 ] && echo --smoke) --stage "$stage"
  status=$?
  [ $status = 124 ] || [ $status = 137 ] && echo "== $stage: stopped at its cap of $cap s"
  echo "== $stage: exit $status, $((SECONDS - started)) s"
  printf '%s\t%s\t%s\n' "$stage" "$status" "$((SECONDS - started))" >> "$out/stages.tsv"
  tar czf "$out/logs.tar.gz" -C "$logs" . 2> /dev/null
  [ $status != 0 ] && [ $first_failure = 0 ] && first_failure=$status
done
exit $first_failure
