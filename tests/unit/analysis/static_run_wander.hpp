#pragma once
// The wander a static run of a simulated unit measures, as `calstand diagnose --noise-run` takes
// it from a stored one: shared by the noise-run tests (noise_run_test.cpp) and the warm-up
// sweep (bench/warm_up_detection_bench.cpp).

#include <fmt/format.h>

#include <cstdint>

#include "../solver/sim_run.hpp"
#include "analysis/noise_run.hpp"
#include "noise/model_figures.hpp"
#include "noise/run_noise.hpp"

namespace calstand::testing {

/// `truth` at rest for `hours` (seed `seed`: another day's record), its composite noise model
/// per channel, spread for `campaign`.
inline solver::KnownWander static_run_wander(const sim::ImuTruth& truth, double hours,
                                             std::uint64_t seed, const solver::RunData& campaign) {
  solver::testing::SimStep rest;
  rest.duration_s = hours * 3600.0;
  const solver::RunData record = solver::testing::simulate_run(truth, {rest}, seed);
  const auto& samples = record.steps.front().samples;
  const solver::RunNoise noise = solver::analyse_noise_samples(samples);
  const auto models = solver::channel_noise_models(samples, noise);
  return analysis::wander_from_models(models, analysis::flicker_band_of(campaign),
                                      fmt::format("a simulated static run of {} h", hours));
}

}  // namespace calstand::testing
