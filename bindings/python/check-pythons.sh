#!/usr/bin/env bash
# Runs the Python suite on other CPython versions than the build's (bindings/test.sh calls it
# with the oldest and the newest minkq supports): for each version, a virtual environment
# with numpy and pytest from PyPI, the extension built for that interpreter (pyo3 reads its
# configuration from PYO3_PYTHON; a target folder per version, so that the builds do not undo
# each other), and pytest on a copy of the package with that extension. Tests that need Warp,
# Newton or mpi4py skip there (the build's own interpreter runs them).
#   check-pythons.sh BUILD_DIR VERSION...   e.g. check-pythons.sh build-bindings 3.9 3.13
# Interpreters are found as pythonX.Y on PATH or under pyenv's versions folder
# ($PYENV_ROOT, default ~/.pyenv); a version with neither fails the check, naming it.
# Needs MINKQ_LIB_DIR (libminkq.so) and cargo set up as bindings/test.sh sets them up.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
build=$1
shift

find_python() {
  local version=$1 candidate
  for candidate in "$(command -v "python$version" || true)" \
    "${PYENV_ROOT:-$HOME/.pyenv}"/versions/"$version".*/bin/"python$version"; do
    if [ -n "$candidate" ] && [ -x "$candidate" ] &&
      "$candidate" -c "import sys; assert '%d.%d' % sys.version_info[:2] == '$version'" 2>/dev/null; then
      echo "$candidate"
      return 0
    fi
  done
  return 1
}

for version in "$@"; do
  python=$(find_python "$version") || {
    echo "check-pythons.sh: no CPython $version found (python$version on PATH or under pyenv's versions);" \
      "install it (pyenv install $version) or set MINKQ_PYTHON_VERSIONS to the versions to check" >&2
    exit 1
  }
  venv=$build/venv-$version
  echo "== CPython $version: $python"
  if ! "$venv/bin/python" -c 'import numpy, pytest' 2>/dev/null; then
    "$python" -m venv "$venv"
    "$venv/bin/pip" install -q --disable-pip-version-check numpy pytest
  fi
  target=$build/target-python$version
  PYO3_PYTHON=$venv/bin/python CARGO_TARGET_DIR=$target cargo build -q -p minkq-python \
    --manifest-path "$here/Cargo.toml"
  package=$(mktemp -d "${TMPDIR:-/tmp}/minkq-python$version.XXXXXX")
  cp -r "$here/python/minkq" "$package/"
  rm -f "$package"/minkq/_native*.so
  cp "$target/debug/lib_native.so" "$package/minkq/_native.so"
  (cd "$here" && PYTHONPATH=$package LD_LIBRARY_PATH="$MINKQ_LIB_DIR${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}" \
    "$venv/bin/python" -m pytest -q -p no:cacheprovider tests)
  rm -rf "$package"
done
