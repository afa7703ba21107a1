#pragma once

#include <cstddef>

#include "noise/allan.hpp"

namespace calstand::solver {

/// Which IEEE Std 952 terms the noise fit may use; all by default.
struct NoiseFitOptions {
  bool quantization = true;
  bool random_walk = true;
  bool bias_instability = true;
  bool rate_random_walk = true;
  bool rate_ramp = true;
  /// Reweighting passes: the weights of a variance estimate depend on the true variance, taken
  /// from the previous pass's model (the first pass uses the measured curve).
  int iterations = 5;
  /// Averaging times below this are left out of the fit [s]. Real IMUs filter their output
  /// before sampling, which pulls the curve below the white-noise line for the first few
  /// samples of tau; with their huge degrees of freedom those points would bias every term.
  double min_tau_s = 0.0;

  /// Throws core::InputError naming the field when no term is enabled, iterations < 1 or
  /// min_tau_s is negative or not finite.
  void validate() const;
};

/// One fitted noise coefficient.
struct NoiseTerm {
  double value = 0.0;  ///< coefficient [unit given at its field]; 0 when not resolved
  double sigma = 0.0;  ///< one-sigma uncertainty from the fit covariance, same unit
  /// True when the term is in the fit's support (a positive coefficient). False: excluded, or
  /// the data carry no evidence of it (the non-negative fit put it at zero); value is 0.
  bool resolved = false;
};

/// The noise terms of a rate signal of unit u (deg/s for a gyro, m/s^2 for an accelerometer)
/// from its Allan variance, with the IEEE Std 952 model
///   AVAR(tau) = 3 Q^2 / tau^2 + N^2 / tau + (2 ln2 / pi) B^2 + K^2 tau / 3 + R^2 tau^2 / 2.
struct NoiseTerms {
  NoiseTerm quantization;      ///< Q [u s] (angle or velocity quantization)
  NoiseTerm random_walk;       ///< N [u sqrt(s)] = [u/sqrt(Hz)]: angle/velocity random walk
  NoiseTerm bias_instability;  ///< B [u]: the IEEE 952 coefficient as fitted (floor 0.664 B)
  NoiseTerm rate_random_walk;  ///< K [u/sqrt(s)]: rate (or acceleration) random walk
  NoiseTerm rate_ramp;         ///< R [u/s]
  /// The lowest Allan deviation of the curve [u] and its averaging time [s]: the "bias
  /// instability" most datasheets quote (the flicker floor, 0.664 B when flicker dominates).
  /// Only points with at least 10 degrees of freedom count (the last few taus of a record
  /// scatter too much for their minimum to mean anything), unless none has.
  double min_deviation = 0.0;
  double min_tau_s = 0.0;
  /// min_deviation / 0.664 [u]: the IEEE 952 coefficient B read from the floor, which
  /// overestimates B where white noise or random walk still lift the minimum.
  double bias_instability_from_min = 0.0;
  double chi2_dof = 0.0;   ///< weighted residual sum of squares per degree of freedom
  std::size_t points = 0;  ///< averaging times used (those from min_tau_s on)
};

/// Allan variance sqrt(2 ln 2 / pi) floor factor of flicker noise: 0.664.
double flicker_floor_factor();

/// The model Allan variance [u^2] of `terms` at tau_s.
double noise_model_allan_variance(const NoiseTerms& terms, double tau_s);

/// Fits the noise terms to an overlapping Allan deviation curve by weighted non-negative least
/// squares on the variance. Weights are the inverse variances of the estimates,
/// 2 AVAR^2 / edf (correlation between overlapping taus is ignored, so chi2_dof is indicative
/// only), with the degrees of freedom of the noise type the model has at each tau (reweighted
/// over options.iterations passes). The non-negative optimum is found exactly by solving every
/// subset of the enabled terms and keeping the best one with all coefficients positive. Sigmas
/// come from the covariance of the final weighted fit, scaled up by sqrt(chi2_dof) when that
/// exceeds 1 and by the square root of the number of taus per octave (overlapping estimates
/// closer than a factor of 2 in tau are far from independent).
///
/// Throws core::InputError when the curve is not kAllan (the model is the Allan variance's),
/// has fewer than 2 points from options.min_tau_s on, or the options are invalid.
NoiseTerms fit_noise_terms(const AllanResult& curve, const NoiseFitOptions& options = {});

/// A first-order Gauss-Markov process (correlation time tau_c, stationary sigma), optionally
/// on top of white noise, fitted to an Allan deviation curve.
struct GaussMarkovFit {
  double sigma = 0.0;             ///< stationary standard deviation [u]
  double tau_c_s = 0.0;           ///< correlation time [s]
  double white_density = 0.0;     ///< white noise N [u sqrt(s)] (0 when not fitted)
  double rate_random_walk = 0.0;  ///< K [u/sqrt(s)] (0 when not fitted or not resolved)
  /// Coefficients in the fit's support (sigma, N, K with a positive variance), plus tau_c when
  /// sigma is among them: the parameters the fit spent.
  std::size_t parameters = 0;
  double chi2_dof = 0.0;
  /// True when the Allan variance peak of the process (at 1.89 tau_c) lies inside the curve's
  /// tau range; otherwise tau_c is an extrapolation and sigma is poorly determined.
  bool peak_in_range = false;
};

/// Allan variance [u^2] at averaging time tau_s of a continuous first-order Gauss-Markov
/// process: (2 sigma^2 tau_c^2 / T^2) (T/tau_c - 3/2 + 2 e^{-T/tau_c} - e^{-2T/tau_c} / 2),
/// evaluated without cancellation for T << tau_c.
double gauss_markov_allan_variance(double sigma, double tau_c_s, double tau_s);

/// Fits sigma and tau_c (and the white noise density when with_white_noise, the rate random
/// walk K tau / 3 when with_rate_random_walk) by weighted least squares on the Allan variance:
/// a search over log tau_c (grid, then golden section), with the variances solved
/// non-negatively at each tau_c. Weights as fit_noise_terms(). Throws core::InputError as
/// fit_noise_terms().
GaussMarkovFit fit_gauss_markov(const AllanResult& curve, bool with_white_noise = true,
                                bool with_rate_random_walk = false);

}  // namespace calstand::solver
