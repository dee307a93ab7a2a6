#!/usr/bin/env bash
# Checks that a repaired minkq wheel stands alone (bindings/test.sh runs it on the wheel it
# builds):
#   1. `auditwheel show` says manylinux_2_XX, and the file name carries that tag;
#   2. the wheel goes into a FRESH virtual environment holding only numpy and pytest;
#   3. every .so in the installed package has only $ORIGIN-relative rpath entries (no build
#      tree), and `ldd` of the extension, with an empty LD_LIBRARY_PATH, resolves libminkq,
#      libtbb and libxxhash to files inside the installed package and finds every library;
#   4. the installed-package tests (tests/, copied out of the source tree, without the Newton
#      tests, which need warp-lang and newton) and `minkq-demo` / `python -m minkq` run with the
#      system's TBB and xxHash and every libminkq build tree hidden from the loader for real:
#      in a private mount namespace (unshare -m; as a user unshare -rm) each such file is
#      covered by /dev/null and each build tree by an empty tmpfs, and the script checks that
#      the system's libtbb.so.12 can no longer be loaded. Where no namespace can be made, the
#      ldd check of step 3 is the evidence (printed as such).
# Usage: check-wheel.sh WHEEL WORKDIR [HIDE...]
#   WORKDIR: made afresh (the venv and the copied tests; not inside a hidden folder);
#   HIDE: folders to hide besides the system's libraries (the repository, MINKQ_LIB_DIR).
# Environment: PYTHON (default python3) makes the venv; AUDITWHEEL (default: auditwheel on PATH).
set -euo pipefail
wheel=$(realpath "$1")
work=$2
shift 2
hide=("$@")
here=$(cd "$(dirname "$0")" && pwd)
python=${PYTHON:-python3}
auditwheel=${AUDITWHEEL:-auditwheel}
fail() { echo "check-wheel: FAIL: $*" >&2; exit 1; }

# ---- 1. the tag ----------------------------------------------------------------------------------
shown=$("$auditwheel" show "$wheel" | tr '\n' ' ')
tag=$(grep -o 'platform tag: "manylinux_[0-9]*_[0-9]*_[a-z0-9_]*"' <<<"$shown" | head -1 | cut -d'"' -f2) ||
  fail "auditwheel show reports no manylinux tag: $shown"
case $(basename "$wheel") in *"$tag"*) ;; *) fail "$(basename "$wheel") is not tagged $tag" ;; esac
echo "check-wheel: auditwheel show: $tag"

# ---- 2. a fresh venv -----------------------------------------------------------------------------
rm -rf "$work"
mkdir -p "$work"
work=$(realpath "$work")
"$python" -m venv "$work/venv"
"$work/venv/bin/pip" install -q --disable-pip-version-check numpy pytest
"$work/venv/bin/pip" install -q --disable-pip-version-check --no-deps "$wheel"
py=$work/venv/bin/python
site=$("$py" -c 'import sysconfig; print(sysconfig.get_paths()["platlib"])')
[ -d "$site/minkq" ] || fail "the wheel installed no minkq package into $site"

# ---- 3. rpaths and ldd ---------------------------------------------------------------------------
mapfile -t sos < <(find "$site/minkq" "$site"/minkq.libs -name '*.so*' -type f 2>/dev/null | sort)
[ ${#sos[@]} -ge 4 ] || fail "expected the extension and 3 vendored libraries, found: ${sos[*]}"
for so in "${sos[@]}"; do
  rpath=$(readelf -d "$so" | sed -n 's/.*(R\(UN\)\{0,1\}PATH).*\[\(.*\)\]/\2/p')
  IFS=: read -ra entries <<<"$rpath"
  for entry in "${entries[@]}"; do
    case $entry in '$ORIGIN' | '$ORIGIN/'*) ;; *) fail "${so#"$site"/} has rpath entry $entry (rpath: $rpath)" ;; esac
  done
  echo "check-wheel: ${so#"$site"/}: rpath '${rpath}'"
done
ext=$(find "$site/minkq" -maxdepth 1 -name '_native*.so' | head -1)
[ -n "$ext" ] || fail "no minkq/_native*.so in $site"
deps=$(env LD_LIBRARY_PATH= ldd "$ext")
! grep -q 'not found' <<<"$deps" || fail "ldd $ext: $deps"
for lib in libminkq libtbb libxxhash; do
  line=$(grep -E "^\s*$lib[-.]" <<<"$deps") || fail "ldd $ext lists no $lib: $deps"
  resolved=$(awk '{print $3}' <<<"$line")
  case $(realpath "$resolved") in "$(realpath "$site")"/*) ;; *) fail "$lib resolves outside the package: $line" ;; esac
  echo "check-wheel: ldd: $(xargs <<<"$line")"
done

# ---- 4. the tests, with the system's libraries hidden ---------------------------------------------
cp -r "$here/tests" "$work/tests"
cp "$here/pyproject.toml" "$work/"  # pytest's settings (the gpu marker); no sources
rm -rf "$work/tests/__pycache__" "$work/tests/test_newton.py" "$work/tests/test_newton_capture.py"
cat >"$work/run.sh" <<EOF
set -euo pipefail
hidden=\${1:-}
if [ -n "\$hidden" ]; then
  for f in /usr/lib/x86_64-linux-gnu/libtbb*.so* /usr/lib/x86_64-linux-gnu/libxxhash*.so* /lib/x86_64-linux-gnu/libtbb*.so* /lib/x86_64-linux-gnu/libxxhash*.so*; do
    if [ -f "\$f" ] && [ ! -L "\$f" ]; then mount --bind /dev/null "\$f"; fi
  done
  for d in ${hide[*]@Q}; do
    if [ -d "\$d" ]; then mount -t tmpfs none "\$d"; fi  # one under an earlier one is gone already
  done
  if "$py" -c 'import ctypes; ctypes.CDLL("libtbb.so.12")' 2>/dev/null; then
    echo "check-wheel: FAIL: the system's libtbb.so.12 still loads inside the namespace" >&2; exit 1
  fi
  echo "check-wheel: system libtbb/libxxhash hidden (covered by /dev/null); hidden folders: ${hide[*]:-none}"
fi
cd "$work"
unset LD_LIBRARY_PATH LD_PRELOAD PYTHONPATH MINKQ_LIB_DIR
"$py" - <<'PY'
import minkq
site = "$site"
assert minkq.__file__.startswith(site + "/"), minkq.__file__
with open("/proc/self/maps") as maps:
    loaded = sorted({l.split()[-1] for l in maps if any(n in l for n in ("/libminkq", "/libtbb", "/libxxhash"))})
outside = [p for p in loaded if not p.startswith(site + "/")]
assert len(loaded) >= 3 and not outside, loaded
print("check-wheel: imported", minkq.__file__, "version", minkq.version(), "with", *(p[len(site) + 1:] for p in loaded))
PY
PYTHONMALLOC=debug "$py" -m pytest -q -p no:cacheprovider tests
"$work/venv/bin/minkq-demo" --backend cpu --size 48 --repeat 1 | tail -1
"$py" -m minkq --backend cpu --size 32 --repeat 1 | tail -1
EOF
if [ "$(id -u)" -eq 0 ] && unshare -m true 2>/dev/null; then
  unshare -m --propagation private bash "$work/run.sh" hidden
elif unshare -rm true 2>/dev/null; then
  unshare -rm --propagation private bash "$work/run.sh" hidden
else
  echo "check-wheel: no mount namespace here: the system's libraries stay visible; the ldd check above is the evidence"
  bash "$work/run.sh"
fi
echo "check-wheel: OK: $(basename "$wheel") stands alone ($tag)"
