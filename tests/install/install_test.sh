#!/usr/bin/env bash
# Installs the build tree into a temporary prefix, then configures, builds and runs an outside
# project (tests/install/consumer) that uses find_package(hapticd) and links haptic::sdk, and
# haptic::recorder in a second program, and a C project (tests/install/c_consumer) that links the C
# API, haptic::c. (The
# Python package's install: python_install_test.sh.)
# Usage: install_test.sh <build-dir> <source-dir> [compiler and linker flags the SDK was built with,
#        e.g. -fsanitize=address,undefined: a consumer must link what they need]
set -euo pipefail
build_dir="$1"
source_dir="$2"
flags="${3:-}"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cmake --install "$build_dir" --prefix "$work/prefix" >/dev/null
test -f "$work/prefix/include/haptic/haptic.hpp" || { echo "FAIL: public headers not installed"; exit 1; }
if ls "$work/prefix/include/haptic" | grep -q -E '\.pb\.h$'; then
  echo "FAIL: generated protobuf headers leaked into the public include dir"; exit 1
fi
launcher=()
command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
cmake -S "$source_dir/tests/install/consumer" -B "$work/consumer" -G Ninja \
  -DCMAKE_PREFIX_PATH="$work/prefix" -DCMAKE_CXX_FLAGS="$flags" -DCMAKE_EXE_LINKER_FLAGS="$flags" \
  "${launcher[@]}" >/dev/null
cmake --build "$work/consumer" -j2 >/dev/null
"$work/consumer/consumer"
"$work/consumer/recorder_consumer"
c_launcher=()
command -v ccache >/dev/null && c_launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache)
cmake -S "$source_dir/tests/install/c_consumer" -B "$work/c_consumer" -G Ninja \
  -DCMAKE_PREFIX_PATH="$work/prefix" -DCMAKE_C_FLAGS="$flags" -DCMAKE_EXE_LINKER_FLAGS="$flags" \
  "${c_launcher[@]}" >/dev/null
cmake --build "$work/c_consumer" >/dev/null
"$work/c_consumer/c_consumer"
# The same C program through pkg-config (haptic_c.pc), as a Makefile would build it.
if command -v pkg-config >/dev/null; then
  pc_flags=$(PKG_CONFIG_PATH=$(dirname "$(find "$work/prefix" -name haptic_c.pc)") pkg-config --cflags --libs haptic_c)
  echo "pkg-config --cflags --libs haptic_c: $pc_flags"
  # shellcheck disable=SC2086
  cc -std=c99 $flags "$source_dir/tests/install/c_consumer/main.c" $pc_flags -o "$work/pc_consumer"
  LD_LIBRARY_PATH=$(dirname "$(find "$work/prefix" -name 'libhaptic_c.so.1')") "$work/pc_consumer"
else
  echo "FAIL: pkg-config is missing (scripts/setup installs pkgconf)"; exit 1
fi
