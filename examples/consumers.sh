#!/usr/bin/env bash
# Uses minkq as an installed library, the way a user would, and fails on the first problem:
#   examples/consumers.sh BUILD_DIR [WORK_DIR]
# BUILD_DIR is a built CMake build folder (e.g. build-cpu); WORK_DIR (default BUILD_DIR/consumers)
# is emptied and holds everything made here.
#   1. cmake --install BUILD_DIR --prefix WORK_DIR/prefix;
#   2. examples/cmake_consumer against that prefix (find_package(minkq CONFIG), with TBB and
#      CUDAToolkit unfindable: the package must need neither), built and run through ctest;
#   3. examples/c/basic.c built with `cc $(pkg-config --cflags --libs minkq)`, run with
#      LD_LIBRARY_PATH=PREFIX/lib;
#   4. the Rust example (examples/rust) linked through MINKQ_LIB_DIR=PREFIX/lib, run on a small
#      sheet (Debian's offline crates, bindings/offline-cargo.sh);
#   5. cpack -G DEB in BUILD_DIR; as root, and when no minkq package is installed already,
#      `apt-get install ./minkq_*.deb`, the pkg-config build, the CMake consumer and the CLI
#      against /usr, then the package removed again. Otherwise step 5 stops after cpack.
# Needs cargo and the crates bindings/test.sh installs (it runs after that script in build.sh).
# Each program's shared-library lookup is checked to reach the installed libminkq, not the
# build tree's.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
[ $# -ge 1 ] || { sed -n '2,4p' "$0"; exit 2; }
build=$(cd "$1" && pwd)
work=${2:-$build/consumers}
# Emptied only when it is this script's (marked) or empty.
if [ -d "$work" ] && [ -n "$(ls -A "$work")" ] && [ ! -e "$work/.minkq-consumers" ]; then
  echo "$work is not empty and not a WORK_DIR of this script: not emptying it" >&2
  exit 1
fi
rm -rf "$work"
mkdir -p "$work"
touch "$work/.minkq-consumers"
work=$(cd "$work" && pwd)
prefix=$work/prefix
started=$SECONDS
step() { printf '\n== consumers: %s (%ds)\n' "$*" $((SECONDS - started)); }

# Fails unless the program's libminkq.so.N resolves into the folder given.
uses_lib_from() {
  local resolved
  resolved=$(ldd "$1" | awk '/libminkq\.so/ {print $3}')
  if [ -z "$resolved" ] || [ "$(realpath "$(dirname "$resolved")")" != "$(realpath "$2")" ]; then
    echo "$1 loads libminkq from '$resolved', not $2" >&2
    exit 1
  fi
  echo "$(basename "$1") loads $resolved"
}

step "cmake --install $build --prefix $prefix"
cmake --install "$build" --prefix "$prefix" >/dev/null
soname=$(readelf -d "$prefix/lib/libminkq.so" | sed -n 's/.*SONAME.*\[\(.*\)\]/\1/p')
abi=$(sed -n 's/^#define MINKQ_ABI_VERSION \([0-9]*\)$/\1/p' "$prefix/include/minkq.h")
[ "$soname" = "libminkq.so.$abi" ] || { echo "SONAME $soname, ABI $abi" >&2; exit 1; }
echo "installed $(cd "$prefix" && find . -type f -o -type l | sort | tr '\n' ' ')"

cmake_consumer() {  # BUILD_FOLDER [cmake arguments]
  local dir=$1; shift
  cmake -S "$root/examples/cmake_consumer" -B "$dir" -DCMAKE_BUILD_TYPE=Release --no-warn-unused-cli \
    -DCMAKE_DISABLE_FIND_PACKAGE_TBB=ON -DCMAKE_DISABLE_FIND_PACKAGE_CUDAToolkit=ON "$@" | grep 'minkq '
  cmake --build "$dir" -j "$(nproc)" >/dev/null
  ctest --test-dir "$dir" --output-on-failure | grep 'tests passed'
}
pkg_config_consumer() {  # OUTPUT LIB_FOLDER (LD_LIBRARY_PATH for it, empty for none)
  # shellcheck disable=SC2046  # pkg-config's flags are meant to split
  cc -std=c99 -Wall -Wextra -pedantic -Werror "$root/examples/c/basic.c" -o "$1" $(pkg-config --cflags --libs minkq)
  LD_LIBRARY_PATH=$2 "$1" | tail -1
}

step "CMake consumer (find_package(minkq CONFIG) from $prefix)"
cmake_consumer "$work/cmake" -DCMAKE_PREFIX_PATH="$prefix"
uses_lib_from "$work/cmake/consumer_cxx" "$prefix/lib"

step "pkg-config consumer (PKG_CONFIG_PATH=$prefix/lib/pkgconfig)"
export PKG_CONFIG_PATH=$prefix/lib/pkgconfig
[ "$(pkg-config --modversion minkq)" = "$(cat "$root/VERSION")" ] || { echo "minkq.pc: wrong version" >&2; exit 1; }
pkg_config_consumer "$work/basic_pc" "$prefix/lib"
LD_LIBRARY_PATH=$prefix/lib uses_lib_from "$work/basic_pc" "$prefix/lib"
unset PKG_CONFIG_PATH

step "Rust example (MINKQ_LIB_DIR=$prefix/lib)"
. "$root/bindings/offline-cargo.sh" "$work/cargo-home"
MINKQ_LIB_DIR=$prefix/lib CARGO_TARGET_DIR=$work/cargo-target \
  cargo build -q --manifest-path "$root/bindings/Cargo.toml" -p minkq-demo
uses_lib_from "$work/cargo-target/debug/minkq-demo" "$prefix/lib"
"$work/cargo-target/debug/minkq-demo" --backend cpu --size 64 | tail -2

step "Debian package (cpack -G DEB)"
(cd "$build" && rm -f minkq_*.deb && cpack -G DEB >/dev/null)
deb=$(ls "$build"/minkq_*.deb)
dpkg-deb -f "$deb" Package Version Depends
if [ "$(id -u)" -ne 0 ]; then
  echo "not root: $deb is not installed or tried (run as root for that)"
elif [ "$(dpkg-query -W -f '${db:Status-Status}' minkq 2>/dev/null)" = installed ]; then
  echo "a minkq package is installed already: $deb is not installed over it"
else
  step "apt-get install $deb; consumers against /usr"
  trap 'DEBIAN_FRONTEND=noninteractive apt-get purge -y -q minkq >/dev/null && echo "minkq package removed"' EXIT
  DEBIAN_FRONTEND=noninteractive apt-get install -y -q "$deb" >/dev/null
  pkg_config_consumer "$work/basic_deb" ""
  uses_lib_from "$work/basic_deb" /usr/lib
  cmake_consumer "$work/cmake_deb"
  uses_lib_from "$work/cmake_deb/consumer_c" /usr/lib
  minkq demo --backend cpu --size 40 | tail -1
fi
step "done"
