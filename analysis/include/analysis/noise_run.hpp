#pragma once
// The wander of a unit measured on a static run, for the fit and diagnosis of another run of the
// same unit (`calstand fit|diagnose --noise-run ID`).
//
// Why: a run's own step means are all it has to tell a wandering bias from an effect that moves
// slowly with time (a warm-up after power-on), and both explain the same residual. Where the
// wander is re-estimated under each explanation (solver/effect_or_wander.hpp), it takes its
// share of the warm-up, and its own estimate is uncertain: a warm-up of 5 step means' noise on a
// MEMS-class gyro is then below what one thermal campaign can tell without false alarms
// (docs/guide-loop.md). A static run of the same unit (hours at rest, on another day, after it
// has warmed up) measures the wander at every time scale it covers, by the composite noise
// model (noise/composite_noise.hpp, the GMWM); with it given, the diagnosis weighs each term
// against a known noise.

#include <cstdint>
#include <span>
#include <string>

#include "noise/model_figures.hpp"
#include "solver/step_noise.hpp"
#include "solver/step_summary.hpp"
#include "store/database.hpp"

namespace calstand::analysis {

/// The time constants a flicker term is spread over on a run [s]: from the shortest block the
/// white floor is read at (solver::kWhiteFitShortestBlockSamples sample periods) to ten times
/// the run's span, as the wander kernels' own flicker band (solver/src/wander_kernels.cpp).
struct FlickerBand {
  double tau_min_s = 0.0;
  double tau_max_s = 0.0;
};
/// The band for `run` (its median sample interval and span). Throws core::InputError for a run
/// without two samples in a step.
FlickerBand flicker_band_of(const solver::RunData& run);

/// Each channel's wander from its identified model (`channels`: gx gy gz ax ay az, as
/// solver::channel_noise_models() gives them): its Gauss-Markov terms, its flicker over `band`
/// and its random walk, summed. The white and quantization terms are left out (the white part
/// is measured inside the fitted run's own steps, with its output filter), and so is a drift
/// (a ramp in a static record is no stationary process: a warm-up not yet settled, or a random
/// walk's look over one record). Throws core::InputError naming the channel and why when a
/// channel has no model.
solver::KnownWander wander_from_models(std::span<const solver::ChannelModelFigures> channels,
                                       const FlickerBand& band, const std::string& source);

/// The wander of `device` ("" = the run's only IMU) measured on the static run `noise_run`
/// (its longest capture at rest, solver::choose_noise_step()), spread for `run` (the run it
/// will weigh). Throws core::InputError for an unknown run or device, a run without a capture
/// at rest, or a record too short for a noise model (at least 10 min).
solver::KnownWander noise_run_wander(store::Database& db, std::int64_t noise_run,
                                     const std::string& device, const solver::RunData& run);

}  // namespace calstand::analysis
