#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "noise/wavelet_moments.hpp"

namespace calstand::solver {

/// The processes of a composite noise model of a static rate record (IEEE Std 952 terms and
/// first-order Gauss-Markov processes).
enum class NoiseKind {
  kWhite,         ///< white rate noise: density N [unit/sqrt(Hz)] (angle/velocity random walk)
  kQuantization,  ///< white phase noise: Q [unit*s]; AVAR = 3 Q^2 / tau^2
  kFlicker,       ///< flicker (bias instability) B [unit]: a flat AVAR of (2 ln 2 / pi) B^2
  kGaussMarkov,   ///< first-order Gauss-Markov: sigma [unit], correlation time tau_s [s]
  kRandomWalk,    ///< rate random walk: density K [unit/sqrt(s)]
  kDrift,         ///< rate ramp R [unit/s]
};
/// "white", "quantization", "flicker", "gauss_markov", "random_walk", "drift" (the JSON names).
std::string_view to_string(NoiseKind kind);

/// One term with its parameters in the record's units and their 95 % intervals.
struct NoiseModelTerm {
  NoiseKind kind = NoiseKind::kWhite;
  double value = 0.0;     ///< N, Q, B, sigma, K or R (see NoiseKind)
  double tau_s = 0.0;     ///< correlation time [s], Gauss-Markov only
  double value_lo = 0.0;  ///< 95 % interval of value
  double value_hi = 0.0;
  double tau_lo_s = 0.0;  ///< 95 % interval of tau_s (Gauss-Markov)
  double tau_hi_s = 0.0;
};

/// A candidate model and how it fared.
struct NoiseCandidate {
  std::vector<NoiseKind> kinds;  ///< its terms (sorted by kind)
  std::size_t parameters = 0;
  /// The efficient GMWM objective at the optimum, (nu_hat - nu)^T Omega^-1 (nu_hat - nu) with
  /// the weights common to all candidates.
  double objective = 0.0;
  double criterion = 0.0;   ///< objective + parameters * 2 ln ln(samples); lower is better
  bool admissible = false;  ///< every term resolved by the record (see identify_noise_model())
  bool selected = false;
};

/// Options of identify_noise_model().
struct NoiseIdOptions {
  /// 0: 95 % intervals from the efficient GMWM's asymptotic covariance (G^T Omega^-1 G)^-1 in
  /// the log parameters. Otherwise the parametric-bootstrap replicates (records simulated from
  /// the fitted model by its exact discrete recursions, each refitted), at least 20.
  std::size_t bootstrap = 0;
  std::uint64_t seed = 1;  ///< of the bootstrap's generator: the same record gives the same answer
  /// Allow a rate ramp term.
  bool drift = true;
  /// Scales whose averaging time m / fs is below this are left out [s]: a sensor's output
  /// low-pass (not a term of the model) correlates neighbouring samples and lowers the first
  /// scales' variance; start a few filter time constants above it. 0: every scale.
  double min_tau_s = 0.0;
  /// Throws core::InputError naming the field.
  void validate() const;
};

/// The identified model.
struct NoiseModel {
  double sample_rate_hz = 0.0;
  std::size_t samples = 0;
  std::vector<NoiseModelTerm> terms;  ///< of the selected candidate
  std::vector<NoiseCandidate> candidates;
  std::string selected_by;     ///< the criterion, in words
  std::string estimator;       ///< the estimator and interval method, in words
  WaveletMoments moments;      ///< the wavelet variances the model was fitted to
  std::vector<double> fitted;  ///< the selected model's wavelet variances at moments.m
};

/// Identifies a composite noise model of the static rate record `rate` (unit of the data at
/// sample_rate_hz) by the GMWM with the efficient weighting: every candidate (white noise plus
/// any of quantization, flicker, one or two Gauss-Markov processes, random walk and ramp) is
/// fitted to the Haar wavelet variances, first with diagonal weights, then with the inverse of
/// the wavelet variances' covariance across scales (wavelet_variance_covariance()) under the
/// spectrum of the best first-step fit, common to all candidates. A candidate is admissible when
/// every term carries at least 2 % of the model's wavelet variance at some scale and a
/// Gauss-Markov time lies within the scales with its Allan peak an octave inside the longest;
/// the admissible candidate with the lowest J + 2 p ln ln n (Hannan-Quinn) is selected and
/// refitted with the weights of its own spectrum. Intervals: the asymptotic covariance in the
/// log parameters, or the parametric bootstrap (NoiseIdOptions::bootstrap). docs/noise-id.md.
///
/// Throws core::InputError for fewer than 32 samples, a non-finite sample, a non-positive rate,
/// fewer than 4 scales above min_tau_s or invalid options. Deterministic; thread safe.
NoiseModel identify_noise_model(std::span<const double> rate, double sample_rate_hz,
                                const NoiseIdOptions& options = {});

/// The same identification from the record's wavelet variances (wavelet_moments(), or
/// DeviationStream::moments() for a streamed record: the GMWM's weights come from a model
/// spectrum, so the moments are all it needs of the data). The same result as the overload
/// above for the moments of the same record. The bootstrap simulates whole records of
/// moments.samples samples (memory grows with the length). Throws core::InputError as the
/// overload above, and for moments that do not start at m = 1.
NoiseModel identify_noise_model(const WaveletMoments& moments, const NoiseIdOptions& options = {});

/// The Haar wavelet variance of one term at half-scale m (samples) for a record at
/// sample_rate_hz; `value` and `tau_s` as NoiseModelTerm. Exposed for the tests.
double term_wavelet_variance(NoiseKind kind, double value, double tau_s, std::size_t m,
                             double sample_rate_hz);

}  // namespace calstand::solver
