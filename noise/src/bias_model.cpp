// Gauss-Markov bias or flicker floor: both fitted to one Allan curve, compared by AIC on the
// chi-square likelihood of the points.
#include "noise/bias_model.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/error.hpp"

namespace calstand::solver {
namespace {

// sum edf (v/m - ln(v/m) - 1): -2 log L of chi-square distributed variance estimates, less its
// minimum (m = v at every point), so that a perfect fit scores 0 and the scale is chi-square's.
template <typename Model>
double deviance(const AllanResult& curve, const Model& model) {
  double d = 0.0;
  for (const AllanPoint& p : curve.points) {
    const double v = p.deviation * p.deviation;
    const double m = model(p.tau_s);
    if (!(v > 0.0)) continue;  // a zero estimate has no logarithm; it tells nothing here
    if (!(m > 0.0)) return INFINITY;
    const double r = v / m;
    d += p.edf * (r - std::log(r) - 1.0);
  }
  return d;
}

std::size_t resolved_count(const NoiseTerms& t) {
  std::size_t n = 0;
  for (const NoiseTerm* term :
       {&t.quantization, &t.random_walk, &t.bias_instability, &t.rate_random_walk, &t.rate_ramp}) {
    n += term->resolved ? 1 : 0;
  }
  return n;
}

}  // namespace

std::string_view to_string(BiasModel model) {
  switch (model) {
    case BiasModel::kGaussMarkov:
      return "gauss_markov";
    case BiasModel::kFlicker:
      return "flicker";
    case BiasModel::kUndecided:
      return "undecided";
  }
  return "undecided";
}

void BiasModelOptions::validate() const {
  if (!std::isfinite(min_tau_s) || min_tau_s < 0.0) {
    throw core::InputError("min_tau_s", fmt::format("must be finite and >= 0, got {}", min_tau_s));
  }
  if (!std::isfinite(aic_margin) || aic_margin < 0.0) {
    throw core::InputError("aic_margin",
                           fmt::format("must be finite and >= 0, got {}", aic_margin));
  }
}

BiasModelChoice choose_bias_model(const AllanResult& curve, const BiasModelOptions& options) {
  options.validate();
  AllanResult used = curve;
  std::erase_if(used.points, [&](const AllanPoint& p) { return p.tau_s < options.min_tau_s; });
  if (std::any_of(used.points.begin(), used.points.end(),
                  [](const AllanPoint& p) { return !(p.edf > 0.0); })) {
    throw core::InputError("curve",
                           "a bias model is chosen by the points' degrees of freedom; "
                           "this curve was computed without them");
  }
  BiasModelChoice out;
  out.gauss_markov = fit_gauss_markov(used, true, true);
  NoiseFitOptions flicker_options;
  // Past the anti-aliasing filter neither model needs quantization, and a ramp would stand in
  // for either wander's slow end; the two differ only in the wander.
  flicker_options.quantization = false;
  flicker_options.rate_ramp = false;
  out.flicker = fit_noise_terms(used, flicker_options);
  out.points = used.points.size();

  const GaussMarkovFit& gm = out.gauss_markov;
  const double n2 = gm.white_density * gm.white_density;
  const double k2 = gm.rate_random_walk * gm.rate_random_walk;
  out.deviance_gauss_markov = deviance(used, [&](double tau) {
    return (gm.sigma > 0.0 ? gauss_markov_allan_variance(gm.sigma, gm.tau_c_s, tau) : 0.0) +
           n2 / tau + k2 * tau / 3.0;
  });
  out.deviance_flicker =
      deviance(used, [&](double tau) { return noise_model_allan_variance(out.flicker, tau); });
  out.parameters_gauss_markov = gm.parameters;
  out.parameters_flicker = resolved_count(out.flicker);

  // Overlapping estimates closer than an octave share most of their data: count one point per
  // octave, as fit_noise_terms() scales its sigmas.
  const double octaves = used.points.size() > 1
                             ? std::log2(used.points.back().tau_s / used.points.front().tau_s)
                             : 0.0;
  const double per_octave =
      octaves > 0.0 ? std::max(1.0, static_cast<double>(used.points.size() - 1) / octaves) : 1.0;
  const double d_gm = out.deviance_gauss_markov / per_octave;
  const double d_fl = out.deviance_flicker / per_octave;
  const double aic_gm_raw = d_gm + 2.0 * static_cast<double>(out.parameters_gauss_markov);
  const double aic_fl_raw = d_fl + 2.0 * static_cast<double>(out.parameters_flicker);
  // Quasi-likelihood: when even the better model leaves more scatter than the EDFs allow (the
  // points are not independent, the simulated or real wander is not exactly either model),
  // every deviance is inflated by that factor, and so would be their difference.
  const bool gm_better = aic_gm_raw <= aic_fl_raw;
  const double best_deviance = gm_better ? d_gm : d_fl;
  const double best_parameters =
      static_cast<double>(gm_better ? out.parameters_gauss_markov : out.parameters_flicker);
  const double effective_points = static_cast<double>(used.points.size()) / per_octave;
  const double dof = effective_points - best_parameters;
  out.dispersion = dof > 0.0 ? std::max(1.0, best_deviance / dof) : 1.0;
  const double aic_gm =
      d_gm / out.dispersion + 2.0 * static_cast<double>(out.parameters_gauss_markov);
  const double aic_fl = d_fl / out.dispersion + 2.0 * static_cast<double>(out.parameters_flicker);
  out.aic_difference = aic_fl - aic_gm;

  const bool has_gm = gm.sigma > 0.0;
  const bool has_flicker = out.flicker.bias_instability.resolved;
  const std::string evidence = fmt::format(
      "AIC of white + flicker + rate random walk minus that of white + Gauss-Markov + rate "
      "random walk: {:.1f} over {} averaging times (choice at +-{:g}{})",
      out.aic_difference, out.points, options.aic_margin,
      out.dispersion > 1.0 ? fmt::format(", deviances divided by {:.2g}", out.dispersion) : "");
  if (!has_gm && !has_flicker) {
    out.model = BiasModel::kUndecided;
    out.reason = fmt::format(
        "neither a Gauss-Markov bias nor a flicker floor rises above the white noise and rate "
        "random walk ({})",
        evidence);
  } else if (has_gm && out.aic_difference >= options.aic_margin) {
    out.model = BiasModel::kGaussMarkov;
    out.reason = fmt::format(
        "a Gauss-Markov bias explains the curve better than a flicker floor "
        "({})",
        evidence);
  } else if (has_flicker && -out.aic_difference >= options.aic_margin) {
    out.model = BiasModel::kFlicker;
    out.reason = fmt::format(
        "a flicker floor explains the curve better than a Gauss-Markov bias "
        "({})",
        evidence);
  } else {
    out.model = BiasModel::kUndecided;
    out.reason = fmt::format(
        "the curve does not tell a Gauss-Markov bias from a flicker floor "
        "({})",
        evidence);
  }
  return out;
}

}  // namespace calstand::solver
