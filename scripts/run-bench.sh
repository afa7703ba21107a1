#!/usr/bin/env bash
# The benchmarks (bench/), from a bare machine. Extra arguments go to Google Benchmark,
# e.g. --benchmark_filter=World.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# Explicit: the test command configures the same build folder without benchmarks.
bash "$root/scripts/build.sh" -DCALSTAND_BUILD_BENCHMARKS=ON \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -g -DNDEBUG"
exec "${CALSTAND_BUILD_DIR:-$root/build}/bench/calstand_bench" "$@"
