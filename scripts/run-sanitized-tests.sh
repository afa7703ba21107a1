#!/usr/bin/env bash
# Every test under AddressSanitizer and UndefinedBehaviorSanitizer: builds into ./build-asan
# (or $CALSTAND_ASAN_BUILD_DIR) with -DCALSTAND_SANITIZE=ON, benchmarks off, and runs ctest
# with the same requirements as scripts/run-tests.sh. Long: the build is a second full build,
# and the tests run several times slower (hence the time limits multiplied by
# CALSTAND_TEST_TIMEOUT_FACTOR, default 6). Extra arguments go to ctest, e.g. -R Capture.
# Any finding fails the test that made it: UBSan does not recover (-fno-sanitize-recover) and
# ASan stops at the first error, leaks included (LeakSanitizer, at each program's exit).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="${CALSTAND_ASAN_BUILD_DIR:-$root/build-asan}"
factor="${CALSTAND_TEST_TIMEOUT_FACTOR:-6}"
# -O1: the usual level for sanitizer builds (readable stacks, a fraction of -O2's build time);
# asserts stay on, a second net under the sanitizers.
CALSTAND_BUILD_DIR="$build_dir" bash "$root/scripts/build.sh" -DCALSTAND_SANITIZE=ON \
  -DCALSTAND_BUILD_BENCHMARKS=OFF -DCALSTAND_TEST_TIMEOUT_FACTOR="$factor" \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g"
cd "$build_dir"
export CALSTAND_REQUIRE_PYMODBUS=1 CALSTAND_REQUIRE_SCHEMA_SUITE=1 CALSTAND_REQUIRE_SSE_CLIENT=1
export CALSTAND_REQUIRE_BROWSER=1
# Programs the tests start (calstand, calstandd) inherit these. detect_leaks: a leak is a
# finding too. check_initialization_order: static initialisers reading other files' globals.
# abort_on_error=0 keeps the exit code (1) ctest reports, rather than a core dump per finding.
export ASAN_OPTIONS="${ASAN_OPTIONS:-detect_leaks=1:check_initialization_order=1:strict_init_order=1:abort_on_error=0}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
# Leaks of libraries, each with whose it is and how that was found (none of calstand's own).
export LSAN_OPTIONS="${LSAN_OPTIONS:-suppressions=$root/scripts/lsan-suppressions.txt:print_suppressions=0}"
ctest --output-on-failure -j "$(nproc)" --timeout $((600 * factor)) "$@"
