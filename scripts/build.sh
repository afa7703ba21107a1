#!/usr/bin/env bash
# Configures and builds calstand in ./build (or $CALSTAND_BUILD_DIR) after installing the
# dependencies. Extra arguments are passed to cmake's configure step, e.g. -DCALSTAND_SANITIZE=ON.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="${CALSTAND_BUILD_DIR:-$root/build}"

bash "$root/scripts/setup-deps.sh"
cmake -S "$root" -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo "$@" >/dev/null
cmake --build "$build_dir" -j "$(nproc)"
