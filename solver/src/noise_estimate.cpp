#include "solver/noise_estimate.hpp"

#include <fmt/format.h>

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.hpp"
#include "variance_component.hpp"

namespace calstand::solver {
namespace {

// The wander's size is searched as the ratio r of its variance (mean over the steps' means) to
// a typical step mean's white variance (variance_component.hpp: 10^-3 .. 10^4; below, it
// changes no weight; above, the white noise would not matter and the run would be a random
// walk with samples attached).
// Gauss-Markov correlation times tried per decade: the likelihood is flat in log tau at this
// resolution (a factor 1.8), far finer than a run of tens of steps can tell.
constexpr double kGaussMarkovTausPerDecade = 4.0;
// An independent extra variance per step must beat the best wander by this much penalised log
// likelihood (a BIC difference of 10: "very strong" on the Kass-Raftery scale) before the
// excess is called an effect rather than noise. Real wanders (flicker above all, whose fast
// components look nearly independent from step to step) come within a few units of it.
constexpr double kNotWanderMargin = 5.0;
// Penalised log likelihood within which flicker is preferred to another wander (see there).
constexpr double kCautiousFlickerMargin = 3.0;
// A column below this share of the largest acting on a channel is rounding, not a regressor.
constexpr double kRoundingShare = 1e-12;
// Columns of a channel's design within this (QR pivot relative to the largest) of the span of
// the others are dropped, so that X^T C^-1 X stays well conditioned for its log-determinant.
constexpr double kRankThreshold = 1e-6;

/// A wander process of unit amplitude (its variance parameter 1: sigma^2, B^2 or K^2) and the
/// eigen-decomposition of its step-mean covariance scaled by the step counts,
/// G = N^1/2 K N^1/2 = U diag(lambda) U^T, which turns every trial of amplitude into diagonal
/// arithmetic and serves all channels at once (their white parts differ only by a factor).
struct Kernel {
  WanderModel unit;
  Eigen::VectorXd lambda;
  Eigen::MatrixXd U;
  double mean_variance = 1.0;  ///< mean of K's diagonal: one step mean's wander variance
  int parameters = 1;          ///< of the wander: amplitude, and tau for Gauss-Markov
};

Kernel make_kernel(const WanderModel& unit, const std::vector<StepSummary>& steps, int parameters) {
  const auto S = static_cast<Eigen::Index>(steps.size());
  Eigen::MatrixXd G(S, S);
  double diag = 0.0;
  for (Eigen::Index i = 0; i < S; ++i) {
    const StepSummary& a = steps[static_cast<std::size_t>(i)];
    for (Eigen::Index j = 0; j <= i; ++j) {
      const StepSummary& b = steps[static_cast<std::size_t>(j)];
      const double k = unit.interval_mean_covariance(a.start_s, a.end_s, b.start_s, b.end_s);
      if (i == j) diag += k;
      G(i, j) = G(j, i) =
          k * std::sqrt(static_cast<double>(a.count) * static_cast<double>(b.count));
    }
  }
  Kernel out;
  out.unit = unit;
  out.parameters = parameters;
  out.mean_variance = diag / static_cast<double>(S);
  detail::KernelBasis basis = detail::kernel_basis(G);
  out.lambda = std::move(basis.lambda);
  out.U = std::move(basis.U);
  return out;
}

/// One channel's regression: N^1/2 X and N^1/2 y (X: the superset's columns that act on the
/// channel, scaled and reduced to full rank), and its white variance per sample.
struct ChannelProblem {
  Eigen::MatrixXd Xs;
  Eigen::VectorXd ys;
  double white = 1.0;
  int parameters = 0;
};

struct Trial {
  double log_likelihood = -std::numeric_limits<double>::infinity();
  double amplitude = 0.0;  ///< the wander's variance parameter
};

/// The best amplitude of `kernel` for one channel: a grid over the variance ratio, then golden
/// section between the best point's neighbours.
Trial best_amplitude(const Kernel& kernel, const ChannelProblem& p, double typical_count) {
  const Eigen::MatrixXd Xh = kernel.U.transpose() * p.Xs;
  const Eigen::VectorXd yh = kernel.U.transpose() * p.ys;
  // rho for a log10 ratio r: amplitude * mean_variance = 10^r * white / typical_count.
  const auto rho_of = [&](double r) {
    return std::pow(10.0, r) / (typical_count * kernel.mean_variance);
  };
  const detail::RatioFit best = detail::best_log10_ratio([&](double r) {
    return detail::restricted_log_likelihood(kernel.lambda, Xh, yh, p.white, rho_of(r));
  });
  Trial t;
  t.log_likelihood = best.log_likelihood;
  t.amplitude = rho_of(best.log10_ratio) * p.white;
  return t;
}

/// The columns of `superset`'s parameters that `fit` determined and that act on `channel`,
/// as N^1/2 X reduced to full rank.
ChannelProblem channel_problem(const std::vector<StepSummary>& steps, const Model& superset,
                               const FitResult& fit, int channel, double white) {
  std::vector<Eigen::Index> columns;
  for (const FittedParameter& fp : fit.parameters) {
    const auto& all = superset.parameters();
    const auto it = std::find_if(all.begin(), all.end(),
                                 [&](const ParameterInfo& q) { return q.name == fp.name; });
    if (it == all.end()) continue;
    columns.push_back(it - all.begin());
  }
  // Columns that act on this channel: beyond rounding of the largest (a force component at 90
  // degrees is 6e-16 g, and normalised it would take a parameter and a degree of freedom).
  std::vector<double> norms;
  double largest = 0.0;
  for (Eigen::Index col : columns) {
    double sum = 0.0;
    for (const StepSummary& s : steps)
      sum += s.regressors(channel, col) * s.regressors(channel, col);
    norms.push_back(std::sqrt(sum));
    largest = std::max(largest, norms.back());
  }
  std::vector<Eigen::Index> acting;
  for (std::size_t k = 0; k < columns.size(); ++k) {
    if (norms[k] > kRoundingShare * largest) acting.push_back(columns[k]);
  }
  columns = std::move(acting);
  const auto S = static_cast<Eigen::Index>(steps.size());
  Eigen::MatrixXd X(S, static_cast<Eigen::Index>(columns.size()));
  ChannelProblem p;
  p.white = white;
  p.ys.resize(S);
  for (Eigen::Index i = 0; i < S; ++i) {
    const StepSummary& s = steps[static_cast<std::size_t>(i)];
    const double root_n = std::sqrt(static_cast<double>(s.count));
    p.ys[i] = root_n * (s.measured[channel] - s.reference[channel]);
    for (std::size_t k = 0; k < columns.size(); ++k) {
      X(i, static_cast<Eigen::Index>(k)) = root_n * s.regressors(channel, columns[k]);
    }
  }
  for (Eigen::Index k = 0; k < X.cols(); ++k) {
    const double norm = X.col(k).norm();
    if (norm > 0.0) X.col(k) /= norm;
  }
  // Full rank: parameters acting on several channels (tilt) may be collinear on one alone.
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(X.rows(), X.cols());
  qr.setThreshold(kRankThreshold);
  qr.compute(X);
  const auto rank = static_cast<Eigen::Index>(qr.rank());
  p.Xs.resize(S, rank);
  for (Eigen::Index k = 0; k < rank; ++k) p.Xs.col(k) = X.col(qr.colsPermutation().indices()[k]);
  p.parameters = static_cast<int>(rank);
  return p;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

std::string describe(const WanderModel& w, int channel) {
  const bool gyro = channel < kAx;
  // Datasheet units: deg/h for a gyro bias, ug for an accelerometer's.
  const double to_sheet = gyro ? 3600.0 : 1e6 / 9.80665;
  const char* unit = gyro ? "deg/h" : "ug";
  switch (w.kind) {
    case WanderKind::kGaussMarkov:
      return fmt::format("Gauss-Markov bias {:.3g} {} with {:.3g} s correlation time",
                         w.sigma * to_sheet, unit, w.tau_s);
    case WanderKind::kFlicker:
      return fmt::format("bias instability (flicker) B {:.3g} {} (Allan floor {:.3g} {})",
                         w.flicker_b * to_sheet, unit, 0.664 * w.flicker_b * to_sheet, unit);
    case WanderKind::kRandomWalk:
      return fmt::format("{} random walk {:.3g} {}/sqrt(h)", gyro ? "rate" : "acceleration",
                         w.random_walk_k * to_sheet * 60.0, unit);
    case WanderKind::kNone:
      return "no wandering bias";
  }
  return "";
}

// Order of the temperature polynomials in the noise superset.
constexpr int kNoiseSupersetTemperatureOrder = 3;

}  // namespace

Model noise_superset(const Model& model) {
  Model m = model;
  for (const auto& info : core::error_term_catalogue()) {
    const ModelTerm* present = model.find(info.name);
    if (present && !info.polynomial_order) continue;
    // Temperature polynomials to a fixed order beyond the model's (the fit drops the orders
    // the run's plateaus cannot determine), so that every model of the same run, and every
    // candidate diagnose tries, is weighed with one noise model.
    const int order = info.polynomial_order ? std::max(kNoiseSupersetTemperatureOrder,
                                                       present ? present->order + 1 : 1)
                                            : 1;
    m = m.with_term(info, order);
  }
  return m;
}

StepNoise estimate_step_noise(const std::vector<StepSummary>& steps, const Model& superset,
                              SensorRows rows, const NoiseEstimateOptions& options) {
  const NoiseFloor white = measure_noise_floor(steps);
  if (!options.estimate_wander) {
    return StepNoise::white_only(
        white, "white noise inside the steps only (wander not estimated, as asked)");
  }
  FitOptions fo;
  fo.rows = rows;
  FitResult fit;
  bool fitted = true;
  try {
    fit = fit_model(steps, superset, white, fo);
  } catch (const core::InputError&) {
    fitted = false;  // more catalogue parameters than step means: no room to see a wander
  }
  StepNoise noise = StepNoise::white_only(white, "");
  if (!fitted) {
    noise.method = fmt::format(
        "white noise from the scatter inside {} {} only: the run's {} step means are too few "
        "for every catalogue term, so a wandering bias cannot be told from a missing effect",
        white.steps_used, white.from_static_steps ? "static steps" : "steps", steps.size());
  } else {
    noise.method = fmt::format(
        "white noise from the scatter inside {} {}; wandering bias per channel by restricted "
        "likelihood of the {} step means' residuals after every catalogue term",
        white.steps_used, white.from_static_steps ? "static steps" : "steps", steps.size());
  }

  std::vector<double> durations, counts;
  double span = 0.0;
  for (const StepSummary& s : steps) {
    durations.push_back(std::max(s.duration_s, 1e-3));
    counts.push_back(static_cast<double>(s.count));
    span = std::max(span, s.end_s);
  }
  const double typical_count = median(counts);
  // Correlation times shorter than a step would show inside the steps, where the white part is
  // measured; longer than a few run spans, a process is a constant the bias absorbs.
  const double tau_lo = std::max(1.0, median(durations));
  const double tau_hi = std::max(10.0 * tau_lo, 3.0 * span);

  std::vector<Kernel> kernels;
  const int gm_count = std::max(
      2, static_cast<int>(std::ceil(kGaussMarkovTausPerDecade * std::log10(tau_hi / tau_lo))) + 1);
  for (int i = 0; i < gm_count; ++i) {
    WanderModel gm;
    gm.kind = WanderKind::kGaussMarkov;
    gm.sigma = 1.0;
    gm.tau_s = tau_lo * std::pow(tau_hi / tau_lo, static_cast<double>(i) / (gm_count - 1));
    kernels.push_back(make_kernel(gm, steps, 2));
  }
  WanderModel flicker;
  flicker.kind = WanderKind::kFlicker;
  flicker.flicker_b = 1.0;
  flicker.tau_min_s = tau_lo;
  flicker.tau_max_s = std::max(10.0 * span, 10.0 * tau_lo);
  kernels.push_back(make_kernel(flicker, steps, 1));
  WanderModel walk;
  walk.kind = WanderKind::kRandomWalk;
  walk.random_walk_k = 1.0;
  kernels.push_back(make_kernel(walk, steps, 1));
  // The alternative that is not a wander: an extra variance of each step mean on its own.
  Kernel independent;
  {
    const auto S = static_cast<Eigen::Index>(steps.size());
    independent.lambda.resize(S);
    for (Eigen::Index i = 0; i < S; ++i)
      independent.lambda[i] = counts[static_cast<std::size_t>(i)];
    independent.U = Eigen::MatrixXd::Identity(S, S);
  }

  for (int c = 0; c < kChannels; ++c) {
    const bool used = rows == SensorRows::kBoth || (rows == SensorRows::kGyro) == (c < kAx);
    ChannelStepNoise& ch = noise.channels[static_cast<std::size_t>(c)];
    if (!used) {
      ch.note = "its sensor's rows are not part of this fit";
      continue;
    }
    if (!fitted) {
      ch.note =
          "the run has fewer step means than the catalogue has parameters: the wander "
          "cannot be told from a missing effect; weights from the white noise alone";
      continue;
    }
    const ChannelProblem p = channel_problem(steps, superset, fit, c, white.density[c]);
    const int dof = static_cast<int>(steps.size()) - p.parameters;
    if (dof < options.min_dof) {
      ch.note = fmt::format(
          "{} step means leave {} degrees of freedom beyond the {} parameters "
          "acting on {} (at least {} needed to see a wandering bias); weights "
          "from the white noise alone",
          steps.size(), dof, p.parameters, channel_name(c), options.min_dof);
      continue;
    }
    const double white_ll = detail::restricted_log_likelihood(
        Eigen::VectorXd::Zero(static_cast<Eigen::Index>(steps.size())), p.Xs, p.ys, p.white, 0.0);
    const double penalty_per_parameter = 0.5 * std::log(static_cast<double>(dof));
    double best_score = white_ll;
    WanderModel best;
    WanderModel flicker_fit;
    double flicker_score = -std::numeric_limits<double>::infinity();
    for (const Kernel& k : kernels) {
      const Trial t = best_amplitude(k, p, typical_count);
      const double score = t.log_likelihood - penalty_per_parameter * k.parameters;
      WanderModel w = k.unit;
      const double root = std::sqrt(t.amplitude);
      if (w.kind == WanderKind::kGaussMarkov) w.sigma = root;
      if (w.kind == WanderKind::kFlicker) w.flicker_b = root;
      if (w.kind == WanderKind::kRandomWalk) w.random_walk_k = root;
      if (w.kind == WanderKind::kFlicker) {
        flicker_score = score;
        flicker_fit = w;
      }
      if (score > best_score) {
        best_score = score;
        best = w;
      }
    }
    // A run of tens of steps tells the fast part of a wander far better than its slow part,
    // which only a few plateaus hours apart carry. Where flicker explains the data nearly as
    // well as the best wander, take it: it keeps the slow wander that a fast Gauss-Markov fit
    // would deny, so that a slowly varying effect (a temperature polynomial's next order) is
    // not claimed from bias wander between plateaus.
    if (best.kind != WanderKind::kNone && best.kind != WanderKind::kFlicker &&
        flicker_score >= best_score - kCautiousFlickerMargin) {
      best = flicker_fit;
      best_score = flicker_score;
    }
    const Trial excess = best_amplitude(independent, p, typical_count);
    const double excess_score = excess.log_likelihood - penalty_per_parameter;
    ch.source = fmt::format("restricted likelihood of {} step means ({} parameters act on {})",
                            steps.size(), p.parameters, channel_name(c));
    if (best.kind != WanderKind::kNone && excess_score - best_score > kNotWanderMargin) {
      ch.determined = false;
      ch.note = fmt::format(
          "the step means scatter {:.2g} times more than the white noise inside the steps, but "
          "neighbouring steps do not share the excess as a wandering bias would: an effect the "
          "model lacks, not noise; weights from the white noise alone",
          std::sqrt(1.0 + excess.amplitude / (p.white / typical_count)));
      continue;
    }
    ch.determined = true;
    ch.wander = best;
    ch.log_likelihood_gain = best_score - white_ll;
    ch.note = describe(best, c);
  }
  return noise;
}

StepNoise estimate_run_noise(const RunData& data, const Model& model, SensorRows rows,
                             const NoiseEstimateOptions& options) {
  const Model superset = noise_superset(model);
  return estimate_step_noise(summarize_steps(data, superset), superset, rows, options);
}

FitResult fit_run(const RunData& data, const Model& model, const FitOptions& options,
                  const NoiseEstimateOptions& noise_options,
                  std::vector<StepSummary>* model_steps) {
  const Model superset = noise_superset(model);
  const std::vector<StepSummary> all = summarize_steps(data, superset);
  const StepNoise noise = estimate_step_noise(all, superset, options.rows, noise_options);
  const std::vector<StepSummary> steps =
      model.earth_rate() ? select_parameters(all, superset, model) : summarize_steps(data, model);
  FitResult fit = fit_model(steps, model, noise, options);
  if (model_steps) *model_steps = steps;
  return fit;
}

}  // namespace calstand::solver
