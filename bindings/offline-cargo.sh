# shellcheck shell=bash
# Sourced by the scripts that run cargo (bindings/test.sh, examples/consumers.sh) with a folder
# as $1: points cargo, and maturin's cargo, at Debian's offline crates (the librust-*-dev
# packages' directory registry, /usr/share/cargo/registry) through a cargo home of their own in
# that folder, so that the user's ~/.cargo configuration and registry are neither used nor
# changed. MINKQ_CARGO_OFFLINE=0 keeps the caller's cargo configuration (e.g. crates.io).
# Plain cargo runs in the repository use the user's own configuration.
if [ "${MINKQ_CARGO_OFFLINE:-1}" != 0 ]; then
  export CARGO_HOME=$1
  mkdir -p "$CARGO_HOME"
  cat >"$CARGO_HOME/config.toml" <<'TOML'
[source.crates-io]
replace-with = "debian-packages"

[source.debian-packages]
directory = "/usr/share/cargo/registry"

[net]
offline = true
TOML
fi
