#!/usr/bin/env bash
# Builds the documentation site into $MINKQ_DOCS_BUILD/html (default: build-docs/ at the
# repository root) on a fresh Debian 12 machine; build.sh's `docs` and `test` commands call it
# after the CMake build:
#   docs/build.sh BUILD_DIR [--check]
#   - installs what is missing: Debian's doxygen and chromium; Sphinx, MyST, breathe and
#     matplotlib from PyPI into a virtual environment under the docs build folder;
#   - installs the minkq wheel there for autodoc (MINKQ_DOCS_WHEEL, or one built from
#     bindings/python against BUILD_DIR/capi), runs Doxygen on the C headers (XML for breathe),
#     `cargo doc` on the Rust crates (Debian's offline crates) and the figure script;
#   - sphinx-build with warnings as errors (-W).
#   --check then runs the tutorials' code (docs/tutorials/*.py, with MINKQ_DOCS_PYTHON or the
#   docs venv's python; a tutorial that needs a GPU, mpi4py or Warp skips with its reason) and
#   opens every page of the site in headless Chromium (docs/_tools/check_site.py: no blank
#   page, every internal link and anchor resolves).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
[ $# -ge 1 ] || { sed -n '2,15p' "$0"; exit 2; }
build_dir=$(cd "$1" && pwd)
check=${2:-}
out=${MINKQ_DOCS_BUILD:-$root/build-docs}
export MINKQ_DOCS_BUILD=$out
venv=$out/venv
started=$SECONDS
step() { printf '\n== docs: %s (%ds)\n' "$*" $((SECONDS - started)); }

# ---- Debian packages ---------------------------------------------------------------------------
packages=(doxygen chromium python3-venv)
missing=()
for p in "${packages[@]}"; do dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p"); done
command -v cargo >/dev/null || missing+=(cargo)  # rustup's or Debian's
if [ ${#missing[@]} -gt 0 ]; then
  step "installing ${missing[*]}"
  sudo=""; [ "$(id -u)" -ne 0 ] && sudo=sudo
  $sudo apt-get update -q
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

# ---- Python tools ------------------------------------------------------------------------------
python_tools=(sphinx==9.0.4 myst-parser==5.2.0 breathe==5.1.0 matplotlib==3.11.2 numpy)
if ! "$venv/bin/python" -c 'import sphinx, myst_parser, breathe, matplotlib, numpy' 2>/dev/null; then
  step "installing ${python_tools[*]} into $venv"
  mkdir -p "$out"
  python3 -m venv "$venv"
  "$venv/bin/pip" install -q --disable-pip-version-check "${python_tools[@]}"
fi

# ---- The minkq package, for autodoc ------------------------------------------------------------
. "$root/bindings/offline-cargo.sh" "$out/cargo-home"  # cargo doc and the wheel's cargo
export MINKQ_LIB_DIR=$build_dir/capi
wheel=${MINKQ_DOCS_WHEEL:-}
if [ -z "$wheel" ]; then
  step "building the minkq wheel against $MINKQ_LIB_DIR"
  rm -rf "$out/wheels"
  "$venv/bin/pip" wheel -q --disable-pip-version-check --no-deps -w "$out/wheels" "$root/bindings/python"
  wheel=$(ls "$out"/wheels/minkq-*.whl)
fi
step "installing $wheel"
"$venv/bin/pip" install -q --disable-pip-version-check --force-reinstall --no-deps "$wheel"

# ---- Generated inputs --------------------------------------------------------------------------
step "doxygen (C reference), cargo doc (Rust reference), figures"
rm -rf "$out/doxygen" "$out/rust"
(cd "$root" && MINKQ_DOXYGEN_OUT="$out/doxygen" doxygen docs/_tools/Doxyfile)
(cd "$root/bindings" && RUSTDOCFLAGS="-D warnings" cargo doc -q --no-deps -p minkq -p minkq-sys)
mkdir -p "$out/rust"
cp -r "${CARGO_TARGET_DIR:-$root/bindings/target}/doc" "$out/rust/rust"
"$venv/bin/python" "$root/docs/_tools/figures.py" "$root/docs/_generated"

# ---- The site ----------------------------------------------------------------------------------
step "sphinx-build -W"
rm -rf "$out/html" "$out/doctrees"
"$venv/bin/sphinx-build" -q -W --keep-going -b html -d "$out/doctrees" "$root/docs" "$out/html"
echo "site: $out/html/index.html"

if [ "$check" = --check ]; then
  step "tutorials"
  [ -e "$build_dir/mpi/libminkq_mpi.so" ] && export MINKQ_MPI_LIB_DIR=$build_dir/mpi
  "${MINKQ_DOCS_PYTHON:-$venv/bin/python}" "$root/docs/_tools/run_tutorials.py" "$root/docs/tutorials"
  step "the site in headless Chromium"
  "$venv/bin/python" "$root/docs/_tools/check_site.py" "$out/html"
fi
step "done"
