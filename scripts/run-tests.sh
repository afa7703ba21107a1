#!/usr/bin/env bash
# Every test, from a bare machine: installs the dependencies, builds, and runs ctest.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
# Benchmarks have their own command (scripts/run-bench.sh); tests need no debug info. Both cut
# the build, most of this command's time on a 2-core machine.
bash "$root/scripts/build.sh" -DCALSTAND_BUILD_BENCHMARKS=OFF \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -DNDEBUG"
cd "${CALSTAND_BUILD_DIR:-$root/build}"
# setup-deps installed python3-pymodbus: the cross-tests against it must run, not skip.
export CALSTAND_REQUIRE_PYMODBUS=1
# ... and json-schema-test-suite: the schema validator must run against it, not skip.
export CALSTAND_REQUIRE_SCHEMA_SUITE=1
# Likewise nodejs and node-eventsource: calstandd's event stream is read by that standard client.
export CALSTAND_REQUIRE_SSE_CLIENT=1
# ... and chromium, chromium-driver and python3-selenium: the console's browser test must run too.
export CALSTAND_REQUIRE_BROWSER=1
# ... and postgresql: the fleet tests start a throw-away PostgreSQL server and must not skip.
export CALSTAND_REQUIRE_POSTGRES=1
# ... and python3-zstandard, python3-lz4, python3-rosbag: the recordings' independent writers
# (tests/support/write_recordings.py) must write every format, none skipped.
export CALSTAND_REQUIRE_RECORDING_WRITERS=1
# One CPU slot per core for the tests that compute, and one test more than the cores: the
# station tests, which hold no slot and mostly wait on the simulator, run beside them
# (tests/CMakeLists.txt, calstand_on_a_cpu).
cores="$(nproc)"
spec="$PWD/ctest-resources.json"
printf '{"version": {"major": 1, "minor": 0}, "local": [{"cpus": [{"id": "0", "slots": %d}]}]}\n' \
  "$cores" >"$spec"
ctest --output-on-failure -j "$((cores + 1))" --resource-spec-file "$spec" --timeout 600
# Fuzzing itself (clang, libFuzzer, sanitizers: a build of its own) is not part of this command:
# `bash scripts/run-fuzz.sh [SECONDS]`. ctest above replays every fuzz target's kept seeds.
