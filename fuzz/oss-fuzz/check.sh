#!/usr/bin/env bash
# fuzz/oss-fuzz/check.sh [SECONDS]: builds the fuzzers as an OSS-Fuzz / ClusterFuzzLite campaign
# would (fuzz/oss-fuzz/build.sh with clang, CFLAGS/CXXFLAGS carrying ASan and
# -fsanitize=fuzzer-no-link, LIB_FUZZING_ENGINE=-fsanitize=fuzzer, SRC and OUT set), checks
# that $OUT holds each fuzzer, its seed corpus zip, dictionary and options, and that it loads
# its shared libraries from $OUT/lib, then runs each
# fuzzer for SECONDS (default 10) on its unzipped seed corpus with its dictionary and options,
# from a folder away from the build (the shared libraries found through $OUT/lib). Exits
# non-zero on any failure. Run by fuzz/run.sh (MINKQ_FUZZ_OSS_CHECK=0 skips it).
# Environment: MINKQ_FUZZ_BUILD (default build-fuzz): $OUT is its oss-out/, the CMake build its
# oss-work/ (kept: a rebuild is incremental).
set -euo pipefail
seconds=${1:-10}
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
build=${MINKQ_FUZZ_BUILD:-$root/build-fuzz}
for tool in clang clang++ zip unzip; do
  command -v $tool >/dev/null || { echo "fuzz/oss-fuzz/check.sh: $tool missing"; exit 1; }
done
# $SRC: a folder of its own holding the checkout as minkq (a link), outside the checkout (no
# link loop inside it) and the same on every run for this build folder, so that CMake's build
# folder in $WORK stays valid; the unzipped corpora go to a temporary one.
mkdir -p "$build"
src=${TMPDIR:-/tmp}/minkq-oss-src-$(printf '%s' "$(cd "$build" && pwd)" | md5sum | cut -c1-12)
mkdir -p "$src"
ln -sfn "$root" "$src/minkq"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
export SRC=$src OUT=$build/oss-out WORK=$build/oss-work
export CC=clang CXX=clang++
export CFLAGS="-O1 -fno-omit-frame-pointer -gline-tables-only -fsanitize=address -fsanitize-address-use-after-scope -fsanitize=fuzzer-no-link"
export CXXFLAGS="$CFLAGS -stdlib=libstdc++"
export LIB_FUZZING_ENGINE=-fsanitize=fuzzer
rm -rf "$OUT"
mkdir -p "$OUT" "$WORK"
start=$(date +%s)
bash "$here/build.sh"
echo "fuzz/oss-fuzz/check.sh: built in $(( $(date +%s) - start )) s into $OUT"
status=0
for fuzzer in fuzz_differential fuzz_capi; do
  for f in "$fuzzer" "${fuzzer}_seed_corpus.zip" "$fuzzer.dict" "$fuzzer.options"; do
    [ -s "$OUT/$f" ] || { echo "!!!! $OUT/$f missing"; status=1; }
  done
  # The runner image has none of the build's packages: the libraries must come from $OUT/lib.
  loaded=$(ldd "$OUT/$fuzzer")  # whole, before grep -q (a pipe would end ldd early: pipefail)
  for lib in libtbb libembree3; do
    [ "$fuzzer" = fuzz_capi ] && [ $lib = libembree3 ] && continue
    grep -q "=> $OUT/lib/$lib" <<<"$loaded" || { echo "!!!! $fuzzer does not load $lib from \$OUT/lib"; status=1; }
  done
  seeds=$(unzip -Z1 "$OUT/${fuzzer}_seed_corpus.zip" | wc -l)
  [ "$seeds" -eq "$(ls "$root/fuzz/corpus/$fuzzer" | wc -l)" ] || { echo "!!!! $fuzzer: the zip holds $seeds seeds"; status=1; }
  corpus=$tmp/corpus-$fuzzer
  mkdir -p "$corpus"
  unzip -q "$OUT/${fuzzer}_seed_corpus.zip" -d "$corpus"
  # The options file's flags, as the campaign's runner passes them.
  options=($(sed -n 's/^\([a-z_]*\) = \(.*\)$/-\1=\2/p' "$OUT/$fuzzer.options" | sed "s#^-dict=#-dict=$OUT/#"))
  log=$build/oss-$fuzzer.log
  set +e
  (cd "$tmp" && ASAN_OPTIONS=abort_on_error=1 "$OUT/$fuzzer" "${options[@]}" -max_total_time="$seconds" \
     -print_final_stats=1 "$corpus") >"$log" 2>&1
  rc=$?
  set -e
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  if [ $rc -ne 0 ] || ! grep -q "INITED" "$log"; then
    echo "!!!! $fuzzer (OSS-Fuzz build) FAILED (exit $rc); the log's end:"; tail -40 "$log"; status=1
  else
    echo "fuzz/oss-fuzz/check.sh: $fuzzer ok: $seeds seeds, ${execs:-?} executions in ${seconds} s (log: $log)"
  fi
done
exit $status
