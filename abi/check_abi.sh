#!/usr/bin/env bash
# The ABI check of a minkq shared library: libabigail's abidiff of the built library against the
# baseline ABI description committed beside this script (abi/libminkq.abi, abi/libminkq_mpi.abi).
# Run by ctest (tests abi_libminkq and abi_libminkq_mpi, so by `./build.sh test` too) as
#   abi/check_abi.sh LIBRARY HEADER ABI_DEFINE BASELINE [MORE_HEADERS...]
# (MORE_HEADERS: the other public headers: those HEADER includes, e.g. minkq_async.h for minkq.h,
# or whose types it uses, e.g. minkq.h and minkq_async.h for minkq_mpi.h.)
# It fails on an incompatible change (a function removed, a parameter or return type changed, a
# struct's layout or an enum's values changed) unless ABI_DEFINE in HEADER was bumped past the
# baseline's ABI (the number ending the baseline's SONAME, libminkq.so.<ABI>). A compatible change
# (a function added) passes. Either way it says when the baseline should be refreshed.
#
# Refreshing the baseline, after an ABI bump or to record an addition (from the repository root,
# with the library built, e.g. by `cmake --preset cpu && cmake --build --preset cpu`):
#   abi/check_abi.sh --refresh build-cpu/capi/libminkq.so capi/minkq.h MINKQ_ABI_VERSION abi/libminkq.abi \
#                    capi/minkq_async.h
#   abi/check_abi.sh --refresh build-cpu/mpi/libminkq_mpi.so mpi/minkq_mpi.h MINKQ_MPI_ABI_VERSION \
#                    abi/libminkq_mpi.abi capi/minkq.h capi/minkq_async.h
# and commit the .abi file with the change. The DWARF abidw reads comes from the C API's own
# sources, compiled with -g and kept in <library file>.debug beside the library (capi/ and
# mpi/CMakeLists.txt); the types recorded are those of the public headers only (--header-file,
# --drop-private-types, --exported-interfaces-only).
set -euo pipefail

refresh=0
if [ "${1:-}" = --refresh ]; then refresh=1; shift; fi
if [ $# -lt 4 ]; then
  sed -n '2,18p' "$0" >&2
  exit 2
fi
library=$1 header=$2 abi_define=$3 baseline=$4
more_headers=("${@:5}")
for tool in abidw abidiff; do
  command -v $tool >/dev/null || { echo "$tool not found: apt-get install abigail-tools" >&2; exit 2; }
done
[ -f "$library" ] || { echo "no library at $library: build it first" >&2; exit 2; }
# The exported functions and the types of HEADER they reach, without paths, line numbers or
# DT_NEEDED, so that the baseline changes only with the ABI.
# abidw matches the headers against the DWARF's absolute paths.
abi_options=(--drop-private-types --exported-interfaces-only --no-corpus-path --no-comp-dir-path --no-elf-needed
             --no-show-locs --type-id-style hash)
for h in "$header" "${more_headers[@]}"; do abi_options+=(--header-file "$(realpath "$h")"); done
abi_options+=(--debug-info-dir "$(dirname "$(realpath "$library")")")  # <library file>.debug
refresh_command="$0 --refresh $*"

# Writes the library's ABI description to $1. Without DWARF abidw records bare symbols, against
# which abidiff sees no type change at all: every exported function must have its declaration.
describe() {
  abidw "${abi_options[@]}" --out-file "$1" "$library"
  local symbols declarations
  symbols=$(grep -c "<elf-symbol .*type='func-type'" "$1" || true)
  declarations=$(grep -c "<function-decl " "$1" || true)
  if [ "$declarations" -lt "$symbols" ]; then
    echo "$library: DWARF for $declarations of its $symbols functions: the check needs the C API's debug" \
         "information (compiled with -g, in $(realpath "$library").debug)" >&2
    exit 1
  fi
}

if [ $refresh = 1 ]; then
  describe "$baseline"
  echo "wrote $baseline from $library"
  exit 0
fi

header_abi=$(sed -n "s/^#define $abi_define \([0-9][0-9]*\)\$/\1/p" "$header")
[ -n "$header_abi" ] || { echo "$header has no '#define $abi_define N' line" >&2; exit 2; }
baseline_abi=$(sed -n "s/.*soname='[^']*\.so\.\([0-9][0-9]*\)'.*/\1/p" "$baseline" | head -n 1)
[ -n "$baseline_abi" ] || { echo "$baseline records no SONAME ending in the ABI number" >&2; exit 2; }

# abidiff reads both sides the same way: the baseline as abixml, the library through abidw's
# options (the same header, private types dropped), written to a scratch file.
current=$(mktemp --suffix=.abi)
trap 'rm -f "$current"' EXIT
describe "$current"
# abidiff's status is a bit field: 1 error, 2 usage error, 4 an ABI change, 8 an incompatible one
# for sure (a removed function). A changed parameter, return or struct type is only "4", so the
# rule is stricter than abidiff's 8: any change to what the baseline holds is incompatible
# (abidiff --no-added-syms sees only those); functions and variables added are compatible.
diff_status() {
  set +e
  report=$(abidiff --no-show-locs "$@" "$baseline" "$current")
  status=$?
  set -e
  if (( status & 3 )); then
    echo "$report"
    echo "abidiff failed (status $status)" >&2
    exit 1
  fi
}
name=$(basename "$library")
diff_status --no-added-syms
if (( status & 12 )); then
  echo "$report"
  if [ "$header_abi" -gt "$baseline_abi" ]; then
    echo "$name: incompatible ABI change, with $abi_define bumped from $baseline_abi to $header_abi:"
    echo "refresh the baseline: $refresh_command"
    exit 0
  fi
  echo "$name: incompatible ABI change against $baseline while $abi_define is still $header_abi (the baseline's):"
  echo "keep the ABI, or bump $abi_define in $header and refresh the baseline: $refresh_command"
  exit 1
fi
diff_status
if (( status & 12 )); then
  echo "$report"
  echo "$name: compatible ABI change (functions added) against $baseline; to record it: $refresh_command"
elif [ "$header_abi" != "$baseline_abi" ]; then
  echo "$name: $abi_define is $header_abi, the baseline's is $baseline_abi; refresh it: $refresh_command"
else
  echo "$name: the ABI of $baseline ($abi_define $header_abi), unchanged"
fi
