#pragma once
// The noise of step means. Real IMUs do not have white noise: besides the white part, which the
// scatter inside a step measures, their bias wanders (first-order Gauss-Markov with a
// correlation time, flicker / bias instability, rate random walk). A wandering bias barely shows
// inside a step of a minute, but it moves every step mean, and steps close in time share it.
// StepNoise holds both parts per channel and gives the covariance between the means of any
// steps, which the fit uses as its weights (generalised least squares).

#include <Eigen/Core>
#include <array>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "solver/step_summary.hpp"

namespace calstand::solver {

/// The process of the wandering bias of one channel.
/// kSum: independent processes added (a composite model identified from a static record).
enum class WanderKind { kNone, kGaussMarkov, kFlicker, kRandomWalk, kSum };
/// "none", "gauss_markov", "flicker", "random_walk", "sum"
std::string_view to_string(WanderKind kind);

/// The correlated part of one channel's noise (beyond the white noise measured in the steps),
/// in the channel's unit u (deg/s or m/s^2).
struct WanderModel {
  WanderKind kind = WanderKind::kNone;
  double sigma = 0.0;  ///< Gauss-Markov stationary sigma [u]
  double tau_s = 0.0;  ///< Gauss-Markov correlation time [s]
  /// Flicker: the IEEE Std 952 coefficient B [u] (Allan deviation floor 0.664 B), as the sum
  /// of Gauss-Markov processes with correlation times log-spaced over [tau_min_s, tau_max_s].
  double flicker_b = 0.0;
  double tau_min_s = 0.0;
  double tau_max_s = 0.0;
  double random_walk_k = 0.0;  ///< rate (acceleration) random walk K [u/sqrt(s)], from run start
  /// kSum: the processes added, each of one of the other kinds.
  std::vector<WanderModel> parts;

  /// Covariance [u^2] of the means of this process over the intervals [a0, a1] and [b0, b1]
  /// (seconds since the run's first sample; a0 <= a1, b0 <= b1, the intervals equal or
  /// disjoint).
  double interval_mean_covariance(double a0, double a1, double b0, double b1) const;
};

/// How one channel's noise model was obtained.
struct ChannelStepNoise {
  WanderModel wander;
  /// True when the run determined the correlated part (it may still be "none": tested, and no
  /// evidence of a wandering bias). False: the run could not tell, and the weights are the
  /// white noise alone; `note` says why.
  bool determined = false;
  std::string source;  ///< e.g. "restricted likelihood of 216 step means (60 parameters)"
  std::string note;    ///< why the correlated part was not determined, or a caution
  /// Not determined because the run has too few step means to see a wandering bias (a
  /// six-position test): a misfit against the white noise alone may then be that wander.
  bool too_few_steps = false;
  double log_likelihood_gain = 0.0;  ///< REML gain of the chosen wander over white noise alone
};

/// The noise of a run's step means: white noise measured inside the steps (`white`) plus the
/// wandering bias of each channel.
struct StepNoise {
  NoiseFloor white;
  std::array<ChannelStepNoise, kChannels> channels{};
  std::string method;  ///< one sentence: how the noise model was obtained

  /// White noise alone, each channel marked undetermined with `why`.
  static StepNoise white_only(const NoiseFloor& floor, const std::string& why);

  /// Covariance [u^2] of the step means of `channel` over `steps` (in their order): the white
  /// part density/count on the diagonal plus the wander between every pair of steps.
  Eigen::MatrixXd covariance(int channel, const std::vector<StepSummary>& steps) const;
  /// True when some channel has a wandering bias (the covariance is not diagonal).
  bool correlated() const;
};

/// The time constants a flicker wander is spread over on a set of step means [s]: from the
/// shortest block the white floor is read at (kWhiteFitShortestBlockSamples sample periods) to
/// ten times the run's span. Beyond it a slower component is a constant the bias absorbs.
struct FlickerBand {
  double tau_min_s = 0.0;
  double tau_max_s = 0.0;
};
/// The band of `steps` (their median sample interval and the last step's end).
FlickerBand flicker_band(const std::vector<StepSummary>& steps);
/// `wander` as it moves step means whose flicker band is `band`: a flicker (or a sum's flicker
/// part) spread over the band, every other process as it is.
WanderModel spread_over(const WanderModel& wander, const FlickerBand& band);

/// Each channel's wander measured outside the run (a static run of the same unit: see
/// analysis/noise_run.hpp), given to the fit instead of a wander estimated from the run's own
/// step means: the wander is then no longer a free explanation of what the model lacks. A
/// flicker is spread over the flicker band of the steps it weighs (spread_over()), whatever band
/// it was measured on.
struct KnownWander {
  std::array<WanderModel, kChannels> wander{};
  std::string source;  ///< where it was measured, e.g. "static run 4 (GMWM of 3.0 h at 50 Hz)"
};

/// The `"noise_model"` JSON of a fit: the method, and per channel the white density, the
/// wander and how it was obtained.
nlohmann::json step_noise_to_json(const StepNoise& noise, double sample_rate_hz);
/// One wander's JSON: {"kind", and its parameters (sigma, tau_s; b, allan_floor, tau_min_s,
/// tau_max_s; k; parts)} in the channel's unit.
nlohmann::json wander_to_json(const WanderModel& wander);

}  // namespace calstand::solver
