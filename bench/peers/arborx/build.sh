#!/usr/bin/env bash
# Builds the ArborX peer benchmark (issue 27, item 4): Kokkos 4.6.01 (OpenMP backend, C++20) and
# ArborX v2.1 from their public sources into a prefix, then bench/peers/arborx/arborx_bench against them
# and against minkq (its own build of the library, CPU backend only, tests and examples off), and
# where Open MPI is installed arborx_mpi_bench too (ArborX's DistributedTree beside minkq_mpi;
# bench/peers/arborx/run_mpi.sh runs it).
# Not part of ./build.sh test, not in the default CMake build. Debian's Kokkos (3.x, in Trilinos
# 13.2) is too old for ArborX 2.x, which needs Kokkos >= 4.5 and C++20.
#
#   bench/peers/arborx/build.sh [options] [--run [arborx_bench options]]
#
#   --src DIR         take the sources from DIR instead of cloning: DIR holds a Kokkos and an ArborX
#                     git directory (bare or not) or source tree, as kokkos+kokkos/repo and
#                     arborx+ArborX/repo (the /work/.mirror layout), kokkos[.git] and ArborX[.git]
#   --kokkos-src P    the Kokkos git directory or source tree itself (a tree must be 4.6.01)
#   --arborx-src P    the ArborX git directory or source tree itself (a tree must be 2.1.0)
#   --minkq-rev REV   build minkq from `git archive REV` of this repository (a fixed snapshot, so
#                     edits in the working tree during a run change nothing; e.g. HEAD); default:
#                     the working tree as it is
#   --no-cgal-data    do not fetch CGAL's elephant-with-holes.off (Debian package libcgal-demo,
#                     CGAL's data set; apt-get download, no root needed)
#   --jobs N          parallel compile jobs (default 2); compiles run under nice -n 10
#   --run ...         run build-bench/arborx/bin/arborx_bench with the remaining arguments
#
# Without --src it clones (what a user with network does):
#   git clone --depth 1 --branch 4.6.01 https://github.com/kokkos/kokkos.git
#   git clone --depth 1 --branch v2.1   https://github.com/arborx/ArborX.git
# Everything lands in build-bench/arborx/ (gitignored): src/, build/, prefix/ (Kokkos and ArborX
# installed), minkq-src/ (with --minkq-rev), data/cgal/, bench/ (the program's CMake build) and
# bin/arborx_bench (and bin/arborx_mpi_bench). A second run reuses what is built (delete
# build-bench/arborx to start over).
set -euo pipefail
root=$(cd "$(dirname "$0")/../../.." && pwd)
work=$root/build-bench/arborx
kokkos_tag=4.6.01 arborx_tag=v2.1
kokkos_version=4.6.1 arborx_version=2.1.0
src_dir="" kokkos_src="" arborx_src="" minkq_rev="" cgal=1 jobs=2 run=0
while [ $# -gt 0 ]; do
  case "$1" in
    --src) src_dir=$2; shift ;;
    --kokkos-src) kokkos_src=$2; shift ;;
    --arborx-src) arborx_src=$2; shift ;;
    --minkq-rev) minkq_rev=$2; shift ;;
    --no-cgal-data) cgal=0 ;;
    --jobs) jobs=$2; shift ;;
    --run) run=1; shift; break ;;
    -h|--help) sed -n '2,31p' "$0"; exit 0 ;;
    *) echo "build.sh: unknown option $1" >&2; exit 2 ;;
  esac
  shift
done
mkdir -p "$work/src" "$work/build" "$work/prefix"
say() { echo "arborx build: $*" >&2; }
compile() { nice -n 10 "$@"; }

# --src DIR: the first of the usual names that exists.
pick() {  # pick DIR NAME... -> the first DIR/NAME that exists
  local dir=$1; shift
  for n in "$@"; do [ -e "$dir/$n" ] && { echo "$dir/$n"; return; }; done
  echo "build.sh: none of $* in $dir" >&2; exit 2
}
if [ -n "$src_dir" ]; then
  [ -z "$kokkos_src" ] && kokkos_src=$(pick "$src_dir" kokkos+kokkos/repo kokkos.git kokkos)
  [ -z "$arborx_src" ] && arborx_src=$(pick "$src_dir" arborx+ArborX/repo ArborX.git arborx.git ArborX arborx)
fi

# fetch NAME TAG URL GIVEN VERSION_CHECK: puts the sources of TAG into $work/src/NAME-TAG. GIVEN is
# a git directory (its TAG is exported), a source tree (used as it is, after the version check),
# or empty (shallow clone of URL at TAG).
fetch() {
  local name=$1 tag=$2 url=$3 given=$4 dest=$work/src/$1-$2
  if [ -f "$dest/CMakeLists.txt" ]; then echo "$dest"; return; fi
  rm -rf "$dest"
  if [ -z "$given" ]; then
    say "cloning $url at $tag"
    git clone -q --depth 1 --branch "$tag" "$url" "$dest" >&2
  elif git --git-dir="$given" rev-parse --git-dir >/dev/null 2>&1 && git --git-dir="$given" rev-parse -q --verify "refs/tags/$tag" >/dev/null; then
    say "exporting $tag from $given"
    mkdir -p "$dest"
    git --git-dir="$given" archive "$tag" | tar -x -C "$dest"
  elif [ -d "$given/.git" ]; then
    say "exporting $tag from $given/.git"
    mkdir -p "$dest"
    git --git-dir="$given/.git" archive "$tag" | tar -x -C "$dest"
  elif [ -f "$given/CMakeLists.txt" ]; then
    say "using the source tree $given"
    ln -s "$(cd "$given" && pwd)" "$dest"
  else
    echo "build.sh: $given is neither a git directory with tag $tag nor a source tree" >&2; exit 2
  fi
  echo "$dest"
}
kokkos_dir=$(fetch kokkos $kokkos_tag https://github.com/kokkos/kokkos.git "$kokkos_src")
arborx_dir=$(fetch ArborX $arborx_tag https://github.com/arborx/ArborX.git "$arborx_src")
# A source tree given as is must be the version measured.
kv=$(sed -n 's/^set(Kokkos_VERSION_\(MAJOR\|MINOR\|PATCH\) \([0-9]*\)).*/\2/p' "$kokkos_dir/CMakeLists.txt" | paste -sd.)
av=$(sed -n 's/^set(ARBORX_VERSION_\(MAJOR\|MINOR\|PATCH\) \([0-9]*\)).*/\2/p' "$arborx_dir/CMakeLists.txt" | paste -sd.)
[ "$kv" = "$kokkos_version" ] || { echo "build.sh: $kokkos_dir is Kokkos $kv, not $kokkos_version" >&2; exit 2; }
[ "$av" = "$arborx_version" ] || { echo "build.sh: $arborx_dir is ArborX $av, not $arborx_version" >&2; exit 2; }

prefix=$work/prefix
# Kokkos: OpenMP (and Serial) host backends, C++20, Release (-O3, as minkq's Release build), no
# architecture flags (minkq is built without -march as well).
# A stamp file in the prefix marks each finished install.
if [ ! -f "$prefix/.kokkos-$kokkos_version" ]; then
  say "configuring Kokkos $kokkos_version"
  cmake -S "$kokkos_dir" -B "$work/build/kokkos" -DCMAKE_BUILD_TYPE=Release -DCMAKE_INSTALL_PREFIX="$prefix" \
    -DCMAKE_CXX_STANDARD=20 -DCMAKE_CXX_EXTENSIONS=OFF -DKokkos_ENABLE_OPENMP=ON -DKokkos_ENABLE_SERIAL=ON \
    -DKokkos_ENABLE_TESTS=OFF -DKokkos_ENABLE_EXAMPLES=OFF -DBUILD_SHARED_LIBS=OFF >"$work/build/kokkos.log"
  say "building Kokkos (log: $work/build/kokkos.log)"
  compile cmake --build "$work/build/kokkos" -j "$jobs" >>"$work/build/kokkos.log"
  cmake --install "$work/build/kokkos" >>"$work/build/kokkos.log"
  touch "$prefix/.kokkos-$kokkos_version"
fi
# ArborX: header-only; configure and install its headers and CMake package, with its MPI part
# (DistributedTree, for arborx_mpi_bench) where Open MPI is installed.
mpi=OFF
command -v mpicxx >/dev/null 2>&1 && mpi=ON
if [ ! -f "$prefix/.arborx-$arborx_version-mpi-$mpi" ]; then
  say "configuring ArborX $arborx_version (MPI $mpi)"
  rm -f "$prefix"/.arborx-*
  cmake -S "$arborx_dir" -B "$work/build/arborx" -DCMAKE_BUILD_TYPE=Release -DCMAKE_INSTALL_PREFIX="$prefix" \
    -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_CXX_EXTENSIONS=OFF -DARBORX_ENABLE_MPI=$mpi >"$work/build/arborx.log"
  cmake --install "$work/build/arborx" >>"$work/build/arborx.log"
  touch "$prefix/.arborx-$arborx_version-mpi-$mpi"
fi

# CGAL's elephant-with-holes.off (REFERENCES.md's second scene), from CGAL's data set as Debian
# packages it (libcgal-demo ships data.tar.gz). Skipped, with a note, where apt cannot fetch it.
elephant=$work/data/cgal/elephant-with-holes.off
if [ $cgal = 1 ] && [ ! -f "$elephant" ]; then
  tmp=$(mktemp -d)
  if (cd "$tmp" && apt-get download -q libcgal-demo >/dev/null 2>&1); then
    dpkg-deb -x "$tmp"/libcgal-demo_*.deb "$tmp/x"
    mkdir -p "$(dirname "$elephant")"
    tar -xzf "$tmp/x/usr/share/doc/libcgal-dev/data.tar.gz" -O data/meshes/elephant-with-holes.off >"$elephant"
    say "CGAL's elephant-with-holes.off from $(basename "$tmp"/libcgal-demo_*.deb)"
  else
    say "could not apt-get download libcgal-demo: the elephant-with-holes scene is skipped (give --mesh PATH)"
  fi
  rm -rf "$tmp"
fi

# minkq: the working tree, or a fixed snapshot of REV.
minkq_dir=$root
if [ -n "$minkq_rev" ]; then
  sha=$(git -C "$root" rev-parse --verify "$minkq_rev^{commit}")
  minkq_dir=$work/minkq-src
  if [ "$(cat "$minkq_dir/.rev" 2>/dev/null)" != "$sha" ]; then
    rm -rf "$minkq_dir"; mkdir -p "$minkq_dir"
    git -C "$root" archive "$sha" | tar -x -C "$minkq_dir"
    echo "$sha" >"$minkq_dir/.rev"
  fi
  say "minkq from $minkq_rev ($sha)"
fi

say "building arborx_bench"
cmake -S "$root/bench/peers/arborx" -B "$work/bench" -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH="$prefix" \
  -DMINKQ_SOURCE_DIR="$minkq_dir" -DMINKQ_WITH_CUDA=OFF -DARBORX_BENCH_BIN_DIR="$work/bin" \
  -DARBORX_BENCH_CGAL_DIR="$work/data/cgal" >"$work/build/bench.log"
targets=arborx_bench
if [ $mpi = ON ]; then
  # Only where the minkq built against has its MPI component (older revisions do not).
  # The target list is captured first: grep -q on a pipe would end cmake early, a failure
  # under pipefail.
  known=$(cmake --build "$work/bench" --target help 2>/dev/null || true)
  if grep -q arborx_mpi_bench <<<"$known"; then
    targets="arborx_bench arborx_mpi_bench"
  else
    say "arborx_mpi_bench skipped: this minkq has no MPI component"
  fi
fi
compile cmake --build "$work/bench" -j "$jobs" --target $targets >>"$work/build/bench.log" ||
  { tail -40 "$work/build/bench.log" >&2; exit 1; }
say "built $work/bin/{${targets// /,}}"
if [ $run = 1 ]; then exec "$work/bin/arborx_bench" "$@"; fi
