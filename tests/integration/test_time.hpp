#pragma once
// The tests' own waits, scaled like ctest's time limits: a sanitizer build runs the same work
// several times slower (scripts/run-sanitized-tests.sh sets CALSTAND_TEST_TIMEOUT_FACTOR, and
// tests/CMakeLists.txt passes it down as CALSTAND_TEST_TIME_FACTOR).

#include <sys/prctl.h>
#include <unistd.h>

#include <chrono>
#include <csignal>

#ifndef CALSTAND_TEST_TIME_FACTOR
#define CALSTAND_TEST_TIME_FACTOR 1
#endif

namespace calstand::testing {

/// How many times slower than a plain build this build runs the tests (1 in a plain build).
inline constexpr int kTestTimeFactor = CALSTAND_TEST_TIME_FACTOR;

/// `plain` as this build's wait: plain x kTestTimeFactor.
template <class Rep, class Period>
constexpr auto scaled(std::chrono::duration<Rep, Period> plain) {
  return plain * kTestTimeFactor;
}

/// Called in a forked child before exec: the child is killed when the test that forked it
/// dies (a failed assertion under a sanitizer aborts the test binary). Without it an orphaned
/// `sim-station` or daemon keeps ctest's output pipe open, and ctest waits for it until the
/// test's time limit. `parent` is the forking process's pid, taken before fork(): a parent
/// that died before prctl() ran would otherwise go unnoticed.
inline void die_with_parent(pid_t parent) {
  ::prctl(PR_SET_PDEATHSIG, SIGKILL);
  if (::getppid() != parent) ::_exit(127);
}

}  // namespace calstand::testing
