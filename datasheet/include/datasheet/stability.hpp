#pragma once
// In-run bias stability of a unit from a long static capture (`calstand analyze stability`), in
// the two forms datasheets state it: the Allan floor (bias instability, IEEE 952) and the
// bias variation with its correlation time (a first-order Gauss-Markov process, as the LN200
// sheet gives "0.35 deg/h, 100 s").

#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "noise/bias_model.hpp"
#include "noise/model_figures.hpp"
#include "noise/run_noise.hpp"
#include "store/database.hpp"

namespace calstand::analysis {

/// One channel's stability, in datasheet units: deg/h for a gyro, ug for an accelerometer.
struct ChannelStability {
  std::string channel;  ///< gx ... az
  /// Bias instability: the Allan deviation's minimum / 0.664, with that point's interval; the
  /// minimum among the points with at least 10 degrees of freedom of their own (the last few
  /// points scatter too much for their minimum to mean anything).
  double bias_instability = 0.0;
  double bias_instability_lo = 0.0;
  double bias_instability_hi = 0.0;
  double min_tau_s = 0.0;  ///< where the floor lies [s]
  /// The curve rises again after its minimum inside the record (a later point's interval lies
  /// wholly above the minimum's) and does not come down again (no point after that one reads
  /// lower than the minimum, as after a Gauss-Markov bias's Allan bump): a floor was seen.
  /// Otherwise the figure is only a bound.
  bool floor_resolved = false;
  /// Which wandering bias the Allan curve shows (solver::choose_bias_model(): white + Gauss-
  /// Markov + rate random walk against white + flicker + rate random walk, by AIC), and why.
  solver::BiasModel bias_model = solver::BiasModel::kUndecided;
  std::string bias_model_reason;
  double bias_model_aic_difference = 0.0;  ///< flicker's AIC minus Gauss-Markov's
  /// Bias variation: the stationary sigma and correlation time [s] of the Gauss-Markov bias
  /// fitted with white noise and rate random walk. A datasheet figure only when bias_model is
  /// Gauss-Markov; none otherwise (fitted to a flicker floor they mean nothing).
  std::optional<double> variation_sigma;
  std::optional<double> correlation_time_s;
  /// The process's Allan peak (1.89 tau_c) lies inside the part of the curve the fit uses (from
  /// 20 sample periods, above the anti-aliasing filter): otherwise tau_c is an extrapolation,
  /// or the fit has taken white noise for a process of vanishing correlation time. False when
  /// no bias variation is reported.
  bool correlation_resolved = false;
  /// The flicker coefficient B fitted to the curve (with white noise and rate random walk) and
  /// its one-sigma uncertainty, when bias_model is flicker; none otherwise.
  std::optional<double> flicker_b;
  double flicker_b_sigma = 0.0;
};

struct StabilityAnalysis {
  std::int64_t run = 0;
  std::string device;
  std::size_t step = 0;
  std::string step_label;
  double duration_s = 0.0;
  double confidence = 0.0;  ///< of the bias instability intervals
  std::array<ChannelStability, 6> channels;
  /// Per channel gx ... az, the identified composite model's figures (solver::
  /// channel_noise_models(), "gmwm") where the record supports it; empty when not asked for.
  std::vector<solver::ChannelModelFigures> models;
};

/// The stability of `device` ("" = the run's first IMU) in `run` from static capture `step`
/// (none: the longest), as solver::analyse_run_noise() reads it. Throws core::InputError as it
/// does, and naming the step when it is shorter than kMinNoiseRecordS (the floor and a
/// correlation time need a long record).
/// With `noise_model`, also the identified composite model of each channel (about 1 s of CPU per
/// channel and 2^19 samples), in `models`.
StabilityAnalysis analyse_stability(store::Database& db, std::int64_t run,
                                    const std::string& device, std::optional<std::size_t> step,
                                    bool noise_model = false);

/// The stability from a noise analysis already made, for a caller that holds the samples: the
/// report reads a long capture once for its Allan plot and its stability figures. The floor's
/// rules (the minimum among points of 10 edf or more, a later point wholly above it and none
/// after that below it) are made
/// for octave averaging times (solver::RunNoiseOptions' default, as analyse_stability() reads
/// the capture): a denser curve finds floors that are not there. `min_tau_samples` as
/// solver::RunNoiseOptions (the bias model fit leaves out the shorter averaging times). Throws
/// core::InputError naming the run and step when the record is shorter than kMinNoiseRecordS.
StabilityAnalysis stability_of(const solver::RunNoise& noise,
                               double min_tau_samples = solver::RunNoiseOptions{}.min_tau_samples);

/// `{"run", "device", "step", "step_label", "duration_s", "confidence",
///   "gyro": {"bias_instability_deg_per_h": [x,y,z], "bias_instability_interval_deg_per_h":
///            [[lo,hi] x3], "floor_tau_s": [...], "bias_variation_deg_per_h": [...],
///            "correlation_time_s": [...], "correlation_resolved": [...], "floor_resolved": [...],
///            "bias_model": ["gauss_markov"|"flicker"|"undecided" x3], "bias_model_reason": [...],
///            "bias_model_aic_difference": [...], "bias_instability_fit_deg_per_h": [...],
///            "bias_instability_fit_sigma_deg_per_h": [...]},
///   "accel": the same in ug}`; the bias variation and correlation time are null unless the
/// bias model is gauss_markov, the fitted B and its sigma null unless it is flicker. With the
/// models: per sensor also "bias_instability_model_<unit>" (a flicker term's B) with its
/// "..._interval_<unit>", "bias_variation_model_<unit>" and "correlation_time_model_s" (the
/// Gauss-Markov term of longest correlation time) with their intervals, null where the model
/// has no such term or there is no model, "model_note" (why not); top level "estimators" (which
/// estimator gives each key: allan-floor, allan-line, gmwm) and "noise_models" (per channel as
/// analysis::channel_model_figures_json()). Without them, "noise_models" is null.

nlohmann::json to_json(const StabilityAnalysis& s);

}  // namespace calstand::analysis
