#!/usr/bin/env bash
# Packs what a GPU session needs on the device machine (no package registry there, and only the
# repository travels): the Debian packages minkq builds against (TBB with libtbbbind, whose
# file Debian's TBB CMake config requires, xxHash, tinyobjloader, GoogleTest, Embree; about
# 10 MB) and ../shared (meshes and scene data; about 14 MB), into .carry/kit, which git ignores. Run here, once per session that has a GPU:
#
#   bash bench/device/pack.sh            # then see bench/device/gpu_session.sh for the calls
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
kit=${1:-$root/.carry/kit}
packages=(libtbb-dev libtbb12 libtbbmalloc2 libtbbbind-2-5 libxxhash-dev libxxhash0 libtinyobjloader-dev
          libtinyobjloader2rc10 libgtest-dev libgmock-dev libembree-dev libembree3-3)
rm -rf "$kit"
mkdir -p "$kit/debs"
(cd "$kit/debs" && apt-get download "${packages[@]}" 2>&1 | grep -v "^Get:" || true)
[ "$(ls "$kit/debs" | wc -l)" = "${#packages[@]}" ] || { echo "pack.sh: apt-get download fetched $(ls "$kit/debs" | wc -l) of ${#packages[@]} packages" >&2; exit 1; }
# libFuzzer's FuzzedDataProvider.h (one header, from clang here) for fuzz_campaign there.
provider=$(ls /usr/lib/llvm-*/lib/clang/*/include/fuzzer/FuzzedDataProvider.h 2>/dev/null | head -1)
[ -n "$provider" ] || { echo "pack.sh: FuzzedDataProvider.h not found (Debian: libclang-common-14-dev)" >&2; exit 1; }
mkdir -p "$kit/include/fuzzer"
cp "$provider" "$kit/include/fuzzer/"
shared=$root/../shared
[ -d "$shared/data" ] || { echo "pack.sh: $shared/data not found" >&2; exit 1; }
mkdir -p "$kit/shared"
cp -r "$shared/data" "$kit/shared/"
[ -d "$shared/tools" ] && cp -r "$shared/tools" "$kit/shared/"
echo "kit ready: $kit ($(du -sh "$kit" | cut -f1)); carry \".carry/kit\""
