#pragma once
// The wander a static run of a simulated unit measures, as `calstand diagnose --noise-run` takes
// it from a stored one: shared by the noise-run tests (noise_run_test.cpp) and the warm-up
// sweep (bench/warm_up_detection_bench.cpp).

#include <fmt/format.h>

#include <cstdint>

#include "../solver/sim_run.hpp"
#include "analysis/noise_run.hpp"

namespace calstand::testing {

/// `truth` at rest for `hours` (seed `seed`: another day's record), its wander measured for
/// `campaign`.
inline solver::KnownWander static_run_wander(const sim::ImuTruth& truth, double hours,
                                             std::uint64_t seed, const solver::RunData& campaign) {
  solver::testing::SimStep rest;
  rest.duration_s = hours * 3600.0;
  const solver::RunData record = solver::testing::simulate_run(truth, {rest}, seed);
  return analysis::wander_of_static_record(record, campaign,
                                           fmt::format("a simulated static run of {} h", hours));
}

}  // namespace calstand::testing
