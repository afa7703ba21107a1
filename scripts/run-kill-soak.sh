#!/usr/bin/env bash
# The kill -9 soak (docs/reliability.md), from a bare machine: builds as the test command does,
# then kills a whole thermal-calibration at N points (default 20) in the foreground CLI and in
# calstandd, resumes each and compares it with an uninterrupted run. Arguments go to the
# program: [--mode cli|daemon|both] [--points N] [--work DIR] [--seed S] [--full].
# Prints a line per kill point and a JSON line per mode; exit 0 when every point passed.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/scripts/build.sh" -DCALSTAND_BUILD_BENCHMARKS=OFF \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -DNDEBUG"
exec "${CALSTAND_BUILD_DIR:-$root/build}/bench/soak/calstand_kill_soak" "$@"
