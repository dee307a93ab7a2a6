#!/bin/bash -eu
# The fuzzers built the OSS-Fuzz / ClusterFuzzLite way (their build.sh): with the compilers,
# flags and engine the campaign's environment gives ($CC, $CXX, $CFLAGS, $CXXFLAGS,
# $LIB_FUZZING_ENGINE), from the checkout at $SRC/minkq, into $OUT:
#   $OUT/fuzz_differential, $OUT/fuzz_capi       the fuzzers (shared libraries they need in $OUT/lib)
#   $OUT/<fuzzer>_seed_corpus.zip               fuzz/corpus/<fuzzer>, zipped here (none committed)
#   $OUT/<fuzzer>.dict, $OUT/<fuzzer>.options   fuzz/dict/<fuzzer>.dict, and libFuzzer's options
# CMake's build folder is $WORK/minkq-fuzz (kept between builds, so a rebuild is incremental);
# its build type OSSFuzz adds no flags: the optimisation is the campaign's (in CFLAGS).
# Checked here by fuzz/oss-fuzz/check.sh, which sets those variables as a campaign would.
set -euo pipefail  # also when run as "bash build.sh", which ignores the first line's options
repo=${MINKQ_SRC:-$SRC/minkq}
work=${WORK:-/tmp}/minkq-fuzz
fuzzers=(fuzz_differential fuzz_capi)

cmake -S "$repo/fuzz" -B "$work" -G Ninja -DCMAKE_BUILD_TYPE=OSSFuzz \
  -DCMAKE_C_COMPILER="$CC" -DCMAKE_CXX_COMPILER="$CXX" \
  -DCMAKE_C_FLAGS="$CFLAGS" -DCMAKE_CXX_FLAGS="$CXXFLAGS" \
  -DMINKQ_FUZZ_ENGINE="$LIB_FUZZING_ENGINE" \
  -DCMAKE_BUILD_RPATH='$ORIGIN/lib' >/dev/null
cmake --build "$work" -j "$(nproc)" --target "${fuzzers[@]}"

# The campaign's runner image has none of the build's packages: the fuzzers take the shared
# libraries they link (TBB, Embree, xxHash, ...) along in $OUT/lib, found through their rpath.
mkdir -p "$OUT/lib"
for fuzzer in "${fuzzers[@]}"; do
  cp "$work/$fuzzer" "$OUT/"
  ldd "$work/$fuzzer" | awk '/=> \// {print $3}' | while read -r lib; do
    case $(basename "$lib") in
      libc.so*|libm.so*|libdl.so*|librt.so*|libpthread.so*|ld-linux*|libgcc_s.so*|libstdc++.so*) ;;
      *) cp -L "$lib" "$OUT/lib/" ;;
    esac
  done
  (cd "$repo/fuzz/corpus/$fuzzer" && rm -f "$OUT/${fuzzer}_seed_corpus.zip" && zip -q -j "$OUT/${fuzzer}_seed_corpus.zip" ./*)
  cp "$repo/fuzz/dict/$fuzzer.dict" "$OUT/$fuzzer.dict"
done
# libFuzzer's options per fuzzer (OSS-Fuzz reads $OUT/<fuzzer>.options), as fuzz/run.sh runs them.
printf '[libfuzzer]\ndict = fuzz_differential.dict\nmax_len = 2048\ndetect_leaks = 0\ntimeout = 120\n' >"$OUT/fuzz_differential.options"
printf '[libfuzzer]\ndict = fuzz_capi.dict\nmax_len = 4096\n' >"$OUT/fuzz_capi.options"
