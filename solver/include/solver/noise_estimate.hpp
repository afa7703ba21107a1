#pragma once
// Estimating a run's step-mean noise model from the run itself: the white part from the scatter
// inside the steps (the white part of their Allan curve, octave_allan.hpp, so that the wander's
// share of a block's scatter is not counted twice), the wandering bias from the step means'
// residuals across steps.
//
// Why the residuals, and how. A wandering bias (Gauss-Markov, flicker, random walk) moves every
// step mean, and steps close in time share it; a missing physical effect follows the steps'
// conditions (orientation, rate, temperature) instead. The residuals are those of the richest
// model the run supports (the model plus every catalogue term, see noise_superset()), so that a
// catalogue effect the model lacks is fitted there and cannot pose as noise. Per channel, the
// wander's parameters maximise the restricted (REML) likelihood of the step means, which
// accounts for the degrees of freedom the fitted parameters take and, with the parameters
// profiled out by generalised least squares at every trial, is feasible GLS iterated to
// convergence. The candidates are white noise alone, a first-order Gauss-Markov bias (sigma,
// correlation time), flicker (bias instability) and a random walk, chosen by the penalised
// likelihood (BIC). An excess scatter of the step means that neighbouring steps do not share
// (better explained by an independent extra variance per step than by any wander) is not
// noise a real sensor has: it is reported, and the weights stay white, so that diagnose keeps
// seeing it as a missing effect.

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "solver/fit.hpp"
#include "solver/model.hpp"
#include "solver/step_noise.hpp"
#include "solver/step_summary.hpp"

namespace calstand::solver {

struct NoiseEstimateOptions {
  /// false: white noise only (the weights of the plain weighted least squares).
  bool estimate_wander = true;
  /// Step means beyond the fitted parameters a channel needs before its wander is estimated.
  int min_dof = 10;
  /// Take flicker where it explains the step means nearly as well as the best process (a slow
  /// wander kept, so that a slowly varying effect is not claimed from it; see
  /// noise_estimate.cpp). False for a static record, where no effect competes with the wander
  /// and the best process is the measurement (analysis/noise_run.hpp).
  bool prefer_flicker = true;
  /// Each channel's wander measured outside the run (a static run of the same unit): used as
  /// it is, not estimated from the step means (white still from inside the steps).
  std::optional<KnownWander> known_wander;
};

/// `model` with every catalogue term it lacks, the next order of each temperature polynomial it
/// has, and the Earth rate: the model whose residuals the noise is estimated from.
Model noise_superset(const Model& model);

/// The noise model of `steps` (summaries built for `superset`, which must hold the Earth rate
/// for gyro rows): white from inside the steps, then per channel of `rows` the wander from the
/// residuals of `superset`. Channels whose wander the run cannot determine (too few steps
/// beyond the parameters) keep white noise and say why.
StepNoise estimate_step_noise(const std::vector<StepSummary>& steps, const Model& superset,
                              SensorRows rows, const NoiseEstimateOptions& options = {});

/// The same from a run's samples: summaries for noise_superset(model) in one pass.
StepNoise estimate_run_noise(const RunData& data, const Model& model, SensorRows rows,
                             const NoiseEstimateOptions& options = {});

/// The fit `calstand fit` makes: `model` on `data` with the run's own noise model. The step
/// summaries of `model` go to `model_steps` when given (for grouping the residuals).
FitResult fit_run(const RunData& data, const Model& model, const FitOptions& options = {},
                  const NoiseEstimateOptions& noise_options = {},
                  std::vector<StepSummary>* model_steps = nullptr);

}  // namespace calstand::solver
