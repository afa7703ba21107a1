#!/usr/bin/env bash
# Builds the libFuzzer targets (tests/fuzz) with clang and runs each for SECONDS (default 60)
# on a corpus kept in build-fuzz/corpus/<target>, started from the seeds in
# tests/fuzz/seeds/<target>/ and with the dictionary tests/fuzz/<target>.dict when they exist.
# One target at a time (the fuzzers are single-process). Needs clang and libclang-rt (Debian
# clang, libclang-rt-14-dev). Exits non-zero when a target crashes; the crashing input is kept
# in build-fuzz/ (crash-*), and the log in build-fuzz/<target>.log.
# `run-fuzz.sh --available` only checks that clang++ can link a libFuzzer target here (exit 0)
# or says what is missing (exit 2).
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-60}"
if ! command -v clang++ >/dev/null; then
  echo "run-fuzz: clang++ is not installed (apt install clang libclang-rt-14-dev)" >&2
  exit 2
fi
# clang without its runtime libraries (libclang-rt-*-dev) compiles but cannot link a fuzzer:
# link a one-line target to find out before a long build does.
probe_dir=$(mktemp -d)
trap 'rm -rf "$probe_dir"' EXIT
echo 'extern "C" int LLVMFuzzerTestOneInput(const unsigned char*, unsigned long) { return 0; }' \
  >"$probe_dir/probe.cpp"
if ! clang++ -fsanitize=fuzzer,address,undefined "$probe_dir/probe.cpp" -o "$probe_dir/probe" \
  >"$probe_dir/log" 2>&1; then
  echo "run-fuzz: clang++ cannot link a libFuzzer target (apt install libclang-rt-14-dev):" >&2
  tail -n 3 "$probe_dir/log" >&2
  exit 2
fi
if [[ "$seconds" == "--available" ]]; then exit 0; fi
# -O1 and line tables only: the build is most of the cost of a short run (the test command's
# smoke), and full debug information of the template-heavy libraries is most of the build;
# line tables still give a crash's stack its files and lines.
CC=clang CXX=clang++ cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -gline-tables-only -DNDEBUG" \
  -DCALSTAND_FUZZ=ON -DCALSTAND_BUILD_TESTS=OFF -DCALSTAND_BUILD_BENCHMARKS=OFF >/dev/null
targets=$(cd tests/fuzz && ls *_fuzz.cpp | sed 's/\.cpp$//')
# shellcheck disable=SC2086
cmake --build build-fuzz --target $targets
# The library is built with recoverable UBSan (top CMakeLists.txt): make undefined behaviour
# stop the fuzzer like a crash instead of a line in the log.
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-halt_on_error=1:print_stacktrace=1}"
status=0
for t in $targets; do
  mkdir -p "build-fuzz/corpus/$t"
  extra=()
  [[ -f "tests/fuzz/$t.dict" ]] && extra+=("-dict=../tests/fuzz/$t.dict")
  dirs=("corpus/$t")
  [[ -d "tests/fuzz/seeds/$t" ]] && dirs+=("../tests/fuzz/seeds/$t")
  echo "run-fuzz: $t for ${seconds} s"
  if ! (cd build-fuzz && "./tests/fuzz/$t" -max_total_time="$seconds" -print_final_stats=1 \
          "${extra[@]}" "${dirs[@]}" >"$t.log" 2>&1); then
    status=1
    echo "run-fuzz: $t FAILED (log: build-fuzz/$t.log)"
  fi
  grep -E 'stat::number_of_executed_units|stat::peak_rss|ERROR|SUMMARY' "build-fuzz/$t.log" || true
done
exit $status
