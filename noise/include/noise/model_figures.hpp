#pragma once
// The noise figures users read (`calstand noise`, its Kalibr file, `calstand analyze stability`)
// from the identified composite model (composite_noise.hpp, the GMWM) where the record supports
// it, else from the Allan-line fit (noise_fit.hpp), each figure naming its estimator.
// docs/noise-id.md, "Where the model is used".

#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "noise/composite_noise.hpp"
#include "noise/run_noise.hpp"
#include "store/database.hpp"

namespace calstand::solver {

/// The estimator names a figure carries ("estimator" in the JSON).
inline constexpr std::string_view kGmwmEstimator = "gmwm";
inline constexpr std::string_view kAllanLineEstimator = "allan-line";

/// Options of channel_noise_models().
struct ModelFigureOptions {
  /// As `calstand noise-id` by default (asymptotic intervals), so that the figures equal its
  /// output on the same record with `--min-tau` min_tau_samples sample periods.
  NoiseIdOptions id;
  /// When id.min_tau_s is 0: the scales below this many sample periods are left out, as the
  /// Allan-line fit leaves them out (RunNoiseOptions::min_tau_samples): an IMU's output low-pass
  /// lowers them (the simulated LN200-class accelerometer, 100 Hz at 400 Hz, gives half its
  /// white density and a flicker of 400 ug with every scale in; its sheet's figures from 20).
  double min_tau_samples = RunNoiseOptions{}.min_tau_samples;
  /// The model is used for records at least this long [s]: the project's "worth a noise
  /// analysis" length (analysis::kMinNoiseRecordS, 600 s) less 1 % (a capture commanded as 600 s
  /// spans a sample period less). Shorter records select terms by too few long scales (at 2^18
  /// samples the true set is missed in 1 to 3 of 10 records, docs/noise-id.md) and the
  /// Allan-line figures are given instead, saying why.
  double min_record_s = 594.0;
};

/// One figure of a channel in the channel's unit u (deg/s or m/s^2 based).
struct ModelFigure {
  /// "white_density" N [u/sqrt(Hz)], "bias_instability" B [u] (flicker; IEEE 952's coefficient,
  /// Allan floor 0.664 B), "gauss_markov_sigma" [u] and "gauss_markov_tau" [s] (one pair per
  /// Gauss-Markov term of the model, longest correlation time last), "random_walk" K [u/sqrt(s)].
  std::string name;
  double value = 0.0;
  double lo = 0.0;  ///< 95 % interval: the model's; the Allan line's value +- 1.96 sigma
  double hi = 0.0;
  std::string unit;
  std::string estimator;  ///< kGmwmEstimator or kAllanLineEstimator
  /// False: neither estimator resolved the term (the Allan line put it at zero); value 0.
  bool resolved = true;
  std::string note;  ///< why the Allan line gave it, when it did
};

/// The identified model of one channel and the figures read from it.
struct ChannelModelFigures {
  ImuChannel channel = ImuChannel::kGx;
  std::optional<NoiseModel> model;  ///< none: the record does not support one (see note)
  std::string note;                 ///< why there is no model
  double min_tau_s = 0.0;           ///< the identification's first averaging time [s]
  std::vector<ModelFigure> figures;
};

/// The figures of one channel from its identified model `model` (none: `why_none` says why) and
/// its Allan-line terms `allan` (channel unit `unit`): white density and random walk from the
/// model where it selected them, else from the Allan line; bias instability from a flicker term,
/// else the Allan line's; every Gauss-Markov term's sigma and tau (the model only).
std::vector<ModelFigure> model_figures(const std::optional<NoiseModel>& model,
                                       const NoiseTerms& allan, const std::string& unit,
                                       const std::string& why_none);

/// Per channel of `noise` (gx ... az), the model identified on `samples` (the record `noise` was
/// computed from) when the record lasts at least options.min_record_s, and its figures. A record
/// the identification refuses (core::InputError) gets the Allan-line figures with the reason.
std::vector<ChannelModelFigures> channel_noise_models(std::span<const core::ImuSample> samples,
                                                      const RunNoise& noise,
                                                      const ModelFigureOptions& options = {});

/// As above for the record analyse_run_noise() analysed: from the channels' wavelet moments
/// it kept (no second read; the same models as from the samples, to rounding up to 2^17
/// samples when the step was streamed), else (options.id.bootstrap, or a RunNoise without
/// moments) reading the samples of noise.step of noise.device in noise.run from `db`.
std::vector<ChannelModelFigures> channel_noise_models(store::Database& db, const RunNoise& noise,
                                                      const ModelFigureOptions& options = {});

}  // namespace calstand::solver
