#!/usr/bin/env bash
# The benchmarks (bench/), from a bare machine. Extra arguments go to Google Benchmark,
# e.g. --benchmark_filter=World; `daemon-load [ARGS]` runs the calstandd load bench instead,
# `fleet-sync [--hours H]` the sync to the fleet's central database, `imu-capture [SECONDS]` 8 IMUs
# of mixed wire formats at their top rates through sim-station and the serial driver, `import
# [--samples N]` the import of recordings against numpy.loadtxt, `allan-csv [--samples N]`
# calstand allan --csv against numpy (loadtxt and the cumulative-sum Allan deviation), `stream-day`
# a day at 1 kHz through the streamed allan and noise-id (bench/stream_day_bench.py).
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
# `run-bench.sh import [--samples N] [--keep DIR]`: calstand import of an MCAP file with zstd
# chunks and of the same CSV against numpy.loadtxt (bench/import_bench.py); then the readers
# per format on the test recordings (calstand_recording_import_bench).
if [ "${1:-}" = "import" ]; then
  shift
  /usr/bin/python3 "$root/bench/import_bench.py" "${CALSTAND_BUILD_DIR:-$root/build}/cli/calstand" "$@"
  tmp="$(mktemp -d)"
  /usr/bin/python3 "$root/tests/support/write_recordings.py" "$tmp" --samples 200000
  (cd "$tmp" && "$bench/calstand_recording_import_bench" zstd.mcap lz4.mcap none.mcap db3 \
    none.bag bz2.bag lz4.bag euroc)
  rm -rf "$tmp"
  exit 0
fi
# `run-bench.sh allan-csv [--samples N] [--keep DIR] [--repeat R] [--baseline BIN]`: calstand
# allan --csv on 5.4 M rows (default) against numpy.loadtxt plus its Allan deviation
# (bench/allan_csv_bench.py); --baseline times another calstand build in the same rounds.
if [ "${1:-}" = "allan-csv" ]; then
  shift
  exec /usr/bin/python3 "$root/bench/allan_csv_bench.py" \
    "${CALSTAND_BUILD_DIR:-$root/build}/cli/calstand" "$@"
fi
# `run-bench.sh stream-day [--samples N] [--small N] [--stored N] [--baseline BIN] [--keep DIR]`:
# a day at 1 kHz (86.4 M rows) through the streamed allan --csv and noise-id --csv, seconds and
# peak memory, against a baseline build's in-memory path on a tenth (bench/stream_day_bench.py).
if [ "${1:-}" = "stream-day" ]; then
  shift
  exec /usr/bin/python3 "$root/bench/stream_day_bench.py" \
    "${CALSTAND_BUILD_DIR:-$root/build}/cli/calstand" "$@"
fi
exec "$bench/calstand_bench" "$@"
