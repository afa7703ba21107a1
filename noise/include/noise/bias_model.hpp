#pragma once
// Which wandering-bias model explains an Allan variance curve: a first-order Gauss-Markov bias
// (the LN200 sheet's "bias variation with correlation time") or a flicker floor (the "bias
// instability" of IEEE Std 952), each on top of white noise and rate random walk. A datasheet
// may state a bias variation and its correlation time only when the curve shows a Gauss-Markov
// process; fitted to a flicker floor, the Gauss-Markov model still returns numbers, and they
// mean nothing.

#include <string>
#include <string_view>

#include "noise/allan.hpp"
#include "noise/noise_fit.hpp"

namespace calstand::solver {

enum class BiasModel {
  kGaussMarkov,  ///< white + Gauss-Markov + rate random walk explains the curve clearly better
  kFlicker,      ///< white + flicker (B) + rate random walk explains it clearly better
  kUndecided,    ///< neither by the margin, or neither wander is seen above the white noise
};
/// "gauss_markov", "flicker", "undecided".
std::string_view to_string(BiasModel model);

struct BiasModelOptions {
  /// Averaging times below this are left out [s] (the anti-aliasing filter lowers the curve
  /// there; see NoiseFitOptions::min_tau_s).
  double min_tau_s = 0.0;
  /// How much lower one model's AIC must be for it to be chosen. 10: Burnham and Anderson's
  /// "essentially no support" for the other model (Model Selection and Multimodel Inference,
  /// 2nd ed., section 2.6); an Allan curve is a handful of strongly informative points, and a
  /// wrong choice puts a meaningless figure on a datasheet, so only a clear difference counts.
  double aic_margin = 10.0;

  /// Throws core::InputError naming the field when min_tau_s is negative or not finite, or
  /// aic_margin is negative or not finite.
  void validate() const;
};

/// Both fits and the comparison.
struct BiasModelChoice {
  BiasModel model = BiasModel::kUndecided;
  GaussMarkovFit gauss_markov;  ///< white + Gauss-Markov + rate random walk
  NoiseTerms flicker;           ///< white + flicker + rate random walk (no Q, no ramp)
  /// Deviance of each fit: -2 log-likelihood of the measured Allan variances under the model,
  /// less its value for a perfect fit (see choose_bias_model()).
  double deviance_gauss_markov = 0.0;
  double deviance_flicker = 0.0;
  std::size_t parameters_gauss_markov = 0;
  std::size_t parameters_flicker = 0;
  /// Deviance per degree of freedom of the better fit, at least 1: divides both deviances
  /// (quasi-likelihood) when the curve scatters more than its EDF say.
  double dispersion = 1.0;
  /// AIC of the flicker fit minus that of the Gauss-Markov fit (after the dispersion):
  /// positive favours the Gauss-Markov bias.
  double aic_difference = 0.0;
  std::size_t points = 0;  ///< averaging times compared
  std::string reason;      ///< why, in a sentence
};

/// Fits both models to the Allan curve (fit_gauss_markov() with white noise and rate random
/// walk; fit_noise_terms() with white noise, flicker and rate random walk) and compares them by
/// one likelihood. An overlapping Allan variance estimate v with edf equivalent degrees of
/// freedom is distributed as AVAR(tau) chi^2(edf) / edf (NIST SP 1065 section 5.3.2, the
/// chi-squared confidence intervals; the model AVAR is IEEE Std 952-1997's), so, given the points'
/// own EDFs (curve.points[i].edf, independent of the model), -2 log L = sum edf_i (v_i / m_i + ln
/// m_i) + const. The deviance sum edf_i (v_i/m_i - ln(v_i/m_i) - 1) is that up to a constant; AIC =
/// deviance / dispersion
/// + 2 (parameters in the fit's support). The points are treated as independent (octave
/// spacing; denser spacing is divided out as points per octave, as fit_noise_terms() does).
/// A model is chosen when its AIC is lower by options.aic_margin and it holds its wander (a
/// Gauss-Markov sigma, a flicker B); otherwise undecided.
///
/// Throws core::InputError as the fits do (not an Allan curve, fewer than 2 points from
/// min_tau_s on) or for invalid options.
BiasModelChoice choose_bias_model(const AllanResult& curve, const BiasModelOptions& options = {});

}  // namespace calstand::solver
