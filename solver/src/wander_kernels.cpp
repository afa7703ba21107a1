#include "wander_kernels.hpp"

#include <fmt/format.h>

#include <Eigen/QR>
#include <algorithm>
#include <cmath>

#include "core/error.hpp"
#include "solver/octave_allan.hpp"
#include "solver/variance_component.hpp"

namespace calstand::solver::detail {
namespace {

// Gauss-Markov correlation times tried per decade: the likelihood is flat in log tau at this
// resolution (a factor 1.8), far finer than a run of tens of steps can tell.
constexpr double kGaussMarkovTausPerDecade = 4.0;
// A column below this share of the largest acting on a channel is rounding, not a regressor.
constexpr double kRoundingShare = 1e-12;
// Columns of a channel's design within this (QR pivot relative to the largest) of the span of
// the others are dropped, so that X^T C^-1 X stays well conditioned for its log-determinant.
constexpr double kRankThreshold = 1e-6;

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
  KernelBasis basis = kernel_basis(G);
  out.lambda = std::move(basis.lambda);
  out.U = std::move(basis.U);
  return out;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

double log_likelihood(const Eigen::VectorXd& lambda, const Eigen::MatrixXd& Xh,
                      const Eigen::VectorXd& yh, double white, double rho, Likelihood likelihood) {
  return likelihood == Likelihood::kRestricted
             ? restricted_log_likelihood(lambda, Xh, yh, white, rho)
             : profile_log_likelihood(lambda, Xh, yh, white, rho);
}

}  // namespace

}  // namespace calstand::solver::detail

namespace calstand::solver {

FlickerBand flicker_band(const std::vector<StepSummary>& steps) {
  std::vector<double> sample_intervals;
  double span = 0.0;
  for (const StepSummary& s : steps) {
    if (s.count > 1) sample_intervals.push_back(s.duration_s / static_cast<double>(s.count - 1));
    span = std::max(span, s.end_s);
  }
  FlickerBand band;
  band.tau_min_s = std::max(1e-3, kWhiteFitShortestBlockSamples * detail::median(sample_intervals));
  band.tau_max_s = 10.0 * std::max(span, band.tau_min_s);
  return band;
}

WanderModel spread_over(const WanderModel& wander, const FlickerBand& band) {
  WanderModel out = wander;
  if (out.kind == WanderKind::kFlicker) {
    out.tau_min_s = band.tau_min_s;
    out.tau_max_s = band.tau_max_s;
  }
  for (WanderModel& part : out.parts) part = spread_over(part, band);
  return out;
}

}  // namespace calstand::solver

namespace calstand::solver::detail {

WanderKernels make_wander_kernels(const std::vector<StepSummary>& steps) {
  std::vector<double> durations, counts;
  double span = 0.0;
  for (const StepSummary& s : steps) {
    durations.push_back(std::max(s.duration_s, 1e-3));
    counts.push_back(static_cast<double>(s.count));
    span = std::max(span, s.end_s);
  }
  WanderKernels out;
  out.typical_count = median(counts);
  // Correlation times shorter than a step would show inside the steps, where the white part is
  // measured; longer than a few run spans, a process is a constant the bias absorbs.
  const double tau_lo = std::max(1.0, median(durations));
  const double tau_hi = std::max(10.0 * tau_lo, 3.0 * span);
  const int gm_count = std::max(
      2, static_cast<int>(std::ceil(kGaussMarkovTausPerDecade * std::log10(tau_hi / tau_lo))) + 1);
  for (int i = 0; i < gm_count; ++i) {
    WanderModel gm;
    gm.kind = WanderKind::kGaussMarkov;
    gm.sigma = 1.0;
    gm.tau_s = tau_lo * std::pow(tau_hi / tau_lo, static_cast<double>(i) / (gm_count - 1));
    out.wanders.push_back(make_kernel(gm, steps, 2));
  }
  // Flicker in two bands, each one parameter, the likelihood choosing: from a step's length up
  // (a bias wandering between steps, its fast part white enough inside them: an LN200-class
  // Gauss-Markov bias of 60 s is closer to this than to any other shape the run can tell), and
  // from the shortest blocks the white floor was read at (measure_noise_floor), whose
  // components faster than a step move the step means too, by less than the slower ones, while
  // the floor holds none of them (an ADIS16488-class flicker floor from 1 s: without this band,
  // 1 clean run in 8 took a warm-up from the wander).
  const FlickerBand band = flicker_band(steps);
  WanderModel flicker;
  flicker.kind = WanderKind::kFlicker;
  flicker.flicker_b = 1.0;
  flicker.tau_min_s = tau_lo;
  flicker.tau_max_s = std::max(band.tau_max_s, 10.0 * tau_lo);
  out.wanders.push_back(make_kernel(flicker, steps, 1));
  if (band.tau_min_s < tau_lo) {
    flicker.tau_min_s = band.tau_min_s;
    out.wanders.push_back(make_kernel(flicker, steps, 1));
  }
  WanderModel walk;
  walk.kind = WanderKind::kRandomWalk;
  walk.random_walk_k = 1.0;
  out.wanders.push_back(make_kernel(walk, steps, 1));
  const auto S = static_cast<Eigen::Index>(steps.size());
  out.independent.lambda.resize(S);
  for (Eigen::Index i = 0; i < S; ++i)
    out.independent.lambda[i] = counts[static_cast<std::size_t>(i)];
  out.independent.U = Eigen::MatrixXd::Identity(S, S);
  return out;
}

namespace {

/// N^1/2 times `columns` of the steps' regressors on `channel`, those acting beyond rounding,
/// each normalised.
Eigen::MatrixXd scaled_columns(const std::vector<StepSummary>& steps, const Eigen::MatrixXd& raw) {
  const auto S = static_cast<Eigen::Index>(steps.size());
  // Columns that act on this channel: beyond rounding of the largest (a force component at 90
  // degrees is 6e-16 g, and normalised it would take a parameter and a degree of freedom).
  double largest = 0.0;
  for (Eigen::Index k = 0; k < raw.cols(); ++k) largest = std::max(largest, raw.col(k).norm());
  std::vector<Eigen::Index> acting;
  for (Eigen::Index k = 0; k < raw.cols(); ++k) {
    if (raw.col(k).norm() > kRoundingShare * largest) acting.push_back(k);
  }
  Eigen::MatrixXd X(S, static_cast<Eigen::Index>(acting.size()));
  for (Eigen::Index i = 0; i < S; ++i) {
    const double root_n = std::sqrt(static_cast<double>(steps[static_cast<std::size_t>(i)].count));
    for (std::size_t k = 0; k < acting.size(); ++k) {
      X(i, static_cast<Eigen::Index>(k)) = root_n * raw(i, acting[k]);
    }
  }
  for (Eigen::Index k = 0; k < X.cols(); ++k) {
    const double norm = X.col(k).norm();
    if (norm > 0.0) X.col(k) /= norm;
  }
  return X;
}

}  // namespace

ChannelProblem channel_problem(const std::vector<StepSummary>& steps,
                               const std::vector<Eigen::Index>& columns, int channel, double white,
                               const Eigen::MatrixXd* extra) {
  const auto S = static_cast<Eigen::Index>(steps.size());
  Eigen::MatrixXd raw(S, static_cast<Eigen::Index>(columns.size()));
  ChannelProblem p;
  p.white = white;
  p.ys.resize(S);
  for (Eigen::Index i = 0; i < S; ++i) {
    const StepSummary& s = steps[static_cast<std::size_t>(i)];
    p.ys[i] =
        std::sqrt(static_cast<double>(s.count)) * (s.measured[channel] - s.reference[channel]);
    for (std::size_t k = 0; k < columns.size(); ++k) {
      raw(i, static_cast<Eigen::Index>(k)) = s.regressors(channel, columns[k]);
    }
    // A NaN would pass every comparison below and leave no column acting, or reach the QR.
    if (!std::isfinite(p.ys[i]) || !raw.row(i).allFinite()) {
      throw core::InputError(fmt::format("step {} ({})", s.index, s.label),
                             fmt::format("its mean or regressors on channel {} are not finite: "
                                         "its samples or table states hold NaN or infinity",
                                         channel));
    }
  }
  const Eigen::MatrixXd X = scaled_columns(steps, raw);
  Eigen::MatrixXd kept(S, 0);
  if (X.cols() > 0) {  // Eigen's pivoting QR of no columns reads past its empty norms
    // Full rank: parameters acting on several channels (tilt) may be collinear on one alone.
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(X.rows(), X.cols());
    qr.setThreshold(kRankThreshold);
    qr.compute(X);
    const auto rank = static_cast<Eigen::Index>(qr.rank());
    kept.resize(S, rank);
    for (Eigen::Index k = 0; k < rank; ++k) {
      kept.col(k) = X.col(qr.colsPermutation().indices()[k]);
    }
  }
  // Extra columns after the design's own, each kept when it reaches outside their span (so that
  // a design with them nests the design without: the same columns and more).
  if (extra && extra->cols() > 0) {
    const Eigen::MatrixXd E = scaled_columns(steps, *extra);
    for (Eigen::Index k = 0; k < E.cols(); ++k) {
      Eigen::VectorXd outside = E.col(k);
      if (kept.cols() > 0) {
        const Eigen::HouseholderQR<Eigen::MatrixXd> basis(kept);
        const Eigen::MatrixXd Q = basis.householderQ() * Eigen::MatrixXd::Identity(S, kept.cols());
        outside -= Q * (Q.transpose() * outside);
      }
      if (outside.norm() > kRankThreshold) {
        kept.conservativeResize(Eigen::NoChange, kept.cols() + 1);
        kept.col(kept.cols() - 1) = E.col(k);
      }
    }
  }
  p.Xs = std::move(kept);
  p.parameters = static_cast<int>(p.Xs.cols());
  return p;
}

Trial best_amplitude(const Kernel& kernel, const ChannelProblem& p, double typical_count,
                     Likelihood likelihood) {
  const Eigen::MatrixXd Xh = kernel.U.transpose() * p.Xs;
  const Eigen::VectorXd yh = kernel.U.transpose() * p.ys;
  // rho for a log10 ratio r: amplitude * mean_variance = 10^r * white / typical_count.
  const auto rho_of = [&](double r) {
    return std::pow(10.0, r) / (typical_count * kernel.mean_variance);
  };
  const RatioFit best = best_log10_ratio([&](double r) {
    return log_likelihood(kernel.lambda, Xh, yh, p.white, rho_of(r), likelihood);
  });
  Trial t;
  t.log_likelihood = best.log_likelihood;
  t.amplitude = rho_of(best.log10_ratio) * p.white;
  return t;
}

double white_log_likelihood(const ChannelProblem& p, Likelihood likelihood) {
  return log_likelihood(Eigen::VectorXd::Zero(p.ys.size()), p.Xs, p.ys, p.white, 0.0, likelihood);
}

Kernel known_kernel(const WanderModel& wander, const std::vector<StepSummary>& steps) {
  // No wander: white noise alone, which known_log_likelihood() scores without a basis.
  if (wander.kind == WanderKind::kNone) {
    Kernel none;
    none.parameters = 0;
    return none;
  }
  return make_kernel(wander, steps, 0);
}

double known_log_likelihood(const Kernel& kernel, const ChannelProblem& p, Likelihood likelihood) {
  if (kernel.unit.kind == WanderKind::kNone) return white_log_likelihood(p, likelihood);
  const Eigen::MatrixXd Xh = kernel.U.transpose() * p.Xs;
  const Eigen::VectorXd yh = kernel.U.transpose() * p.ys;
  // The covariance of the scaled means is white (I + rho G): the kernel at amplitude 1 is the
  // known process, rho = 1 / white.
  return log_likelihood(kernel.lambda, Xh, yh, p.white, 1.0 / p.white, likelihood);
}

WanderModel with_amplitude(const Kernel& kernel, double amplitude) {
  WanderModel w = kernel.unit;
  const double root = std::sqrt(amplitude);
  if (w.kind == WanderKind::kGaussMarkov) w.sigma = root;
  if (w.kind == WanderKind::kFlicker) w.flicker_b = root;
  if (w.kind == WanderKind::kRandomWalk) w.random_walk_k = root;
  return w;
}

}  // namespace calstand::solver::detail
