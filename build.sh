#!/usr/bin/env bash
# Set-up and entry points on a fresh Debian 12 machine:
#   ./build.sh demo   installs what is missing, builds, runs `minkq demo` on the default scene
#   ./build.sh test   installs what is missing, builds, runs the whole test suite (ctest, with
#                     the export and ABI checks of abi/, then cargo test and pytest for the
#                     bindings, programs built against the installed library and the .deb, then
#                     both fuzzers for a minute, then the documentation site, built with
#                     warnings as errors, its tutorials run and its pages opened in Chromium)
#   ./build.sh docs   installs what is missing, builds, builds the documentation site into
#                     build-docs/html (docs/build.sh)
#   ./build.sh build  installs what is missing and builds only
# PRESET=cpu|cuda|default (default: default = CUDA when nvcc is found).
set -euo pipefail
cd "$(dirname "$0")"
preset=${PRESET:-default}
binary_dir=build; [ "$preset" != default ] && binary_dir=build-$preset
packages=(cmake g++ make pkg-config libtbb-dev libxxhash-dev libtinyobjloader-dev libgtest-dev googletest dpkg-dev
          libopenmpi-dev openmpi-bin  # Open MPI: minkq_mpi and its tests under mpirun
          abigail-tools)  # abidw, abidiff: ctest's abi_* checks against the baselines in abi/

install_packages() {
  local missing=()
  for p in "${packages[@]}"; do dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p"); done
  [ ${#missing[@]} -eq 0 ] && return
  local sudo=""; [ "$(id -u)" -ne 0 ] && sudo=sudo
  echo "installing: ${missing[*]}"
  $sudo apt-get update -q
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -q "${missing[@]}"
}

build() {
  install_packages
  cmake --preset "$preset"
  cmake --build --preset "$preset" -j "$(nproc)"
}

case "${1:-}" in
  demo) build; "./$binary_dir/bin/minkq" demo "${@:2}" ;;
  test)
    build
    ctest --preset "$preset" -j "$(nproc)"
    # cargo test (with doctests), pytest, the wheel alone, and a wheel built from the sdist
    MINKQ_CHECK_SDIST=1 MINKQ_LIB_DIR="$PWD/$binary_dir/capi" bindings/test.sh
    examples/consumers.sh "$binary_dir"  # cmake --install, find_package, pkg-config, Rust, .deb
    fuzz/run.sh 60  # differential (vs Embree and the oracle) and C API fuzzers, a minute each
    # The site, from the wheel bindings/test.sh built; its tutorials run in that venv (Warp, mpi4py).
    MINKQ_DOCS_WHEEL=$(ls build-bindings/wheels/minkq-*.whl) MINKQ_DOCS_PYTHON=$PWD/build-bindings/venv/bin/python \
      docs/build.sh "$binary_dir" --check
    ;;
  docs) build; docs/build.sh "$binary_dir" ;;
  build) build ;;
  *) sed -n '2,11p' "$0"; exit 2 ;;
esac
