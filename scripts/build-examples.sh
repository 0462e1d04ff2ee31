#!/usr/bin/env bash
# Builds and runs every program in examples/ against the INSTALLED package, the way a user
# would: installs a configured and built tree into a scratch prefix, then configures each
# example as a project of its own (find_package(hivecal)) with the tree's compiler and flags,
# builds it and runs it. CTest runs it in the host preset (test examples.build).
#   scripts/build-examples.sh [build-dir]     (default: build/host, built already)
set -euo pipefail
repo=$(cd "$(dirname "$0")/.." && pwd)
build=$(cd "${1:-$repo/build/host}" && pwd)

# The same compiler and flags as the installed library (a sanitizer build needs its runtime).
cache_value() { sed -n "s/^$1:[A-Z]*=//p" "$build/CMakeCache.txt"; }
cxx=$(cache_value CMAKE_CXX_COMPILER)
cxx_flags=$(cache_value CMAKE_CXX_FLAGS)
link_flags=$(cache_value CMAKE_EXE_LINKER_FLAGS)
build_type=$(cache_value CMAKE_BUILD_TYPE)

scratch=$(mktemp -d "${TMPDIR:-/tmp}/hivecal-examples.XXXXXX")
trap 'rm -rf "$scratch"' EXIT
quiet() {  # runs a command, showing its output only when it fails
  "$@" >"$scratch/log" 2>&1 || { cat "$scratch/log" >&2; return 1; }
}
quiet cmake --install "$build" --prefix "$scratch/prefix"

run_example() {  # name [arguments...]
  local name=$1
  shift
  echo "=== $name"
  quiet cmake -S "$repo/examples/$name" -B "$scratch/$name" -G Ninja -DCMAKE_PREFIX_PATH="$scratch/prefix" \
    -DCMAKE_CXX_COMPILER="$cxx" -DCMAKE_CXX_FLAGS="$cxx_flags" -DCMAKE_EXE_LINKER_FLAGS="$link_flags" \
    -DCMAKE_BUILD_TYPE="${build_type:-Release}" -Wdev -Werror=dev
  quiet cmake --build "$scratch/$name"
  "$scratch/$name/$name" "$@"
}

run_example calibrate_samples
run_example decode_capture "$repo/tests/data/fw-session/tracker.cap"
"$scratch/decode_capture/decode_capture"  # frames encoded in memory
run_example mcu_workspace
echo "examples: all built and ran"
