#!/usr/bin/env bash
# The benchmarks (bench/), from a bare machine. Extra arguments go to Google Benchmark,
# e.g. --benchmark_filter=World.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/scripts/build.sh"
exec "${CALSTAND_BUILD_DIR:-$root/build}/bench/calstand_bench" "$@"
