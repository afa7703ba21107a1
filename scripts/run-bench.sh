#!/usr/bin/env bash
# The benchmarks (bench/), from a bare machine. Extra arguments go to Google Benchmark,
# e.g. --benchmark_filter=World; `daemon-load [ARGS]` runs the calstandd load bench instead,
# `fleet-sync [--hours H]` the sync to the fleet's central database, `imu-capture [SECONDS]` 8 IMUs
# of mixed wire formats at their top rates through sim-station and the serial driver.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# Explicit: the test command configures the same build folder without benchmarks.
bash "$root/scripts/build.sh" -DCALSTAND_BUILD_BENCHMARKS=ON \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -g -DNDEBUG"
bench="${CALSTAND_BUILD_DIR:-$root/build}/bench"
# `run-bench.sh daemon-load [--drivers] ...`: calstandd under load (its own program).
if [ "${1:-}" = "daemon-load" ]; then
  shift
  exec "$bench/calstand_daemon_load_bench" "$@"
fi
# `run-bench.sh fleet-sync [--hours H]`: the sync to a throw-away PostgreSQL server.
if [ "${1:-}" = "fleet-sync" ]; then
  shift
  exec "$bench/calstand_fleet_sync_bench" "$@"
fi
# `run-bench.sh imu-capture [SECONDS]`: 8 IMUs of mixed wire formats, exit 1 on any loss.
if [ "${1:-}" = "imu-capture" ]; then
  shift
  exec "$bench/calstand_imu_capture_bench" "$@"
fi
exec "$bench/calstand_bench" "$@"
