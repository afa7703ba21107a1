#include "tablefree/pose_noise.hpp"

#include <fmt/format.h>

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <limits>

#include "solver/variance_component.hpp"

namespace calstand::solver {
namespace {

// The amplitude is searched as the ratio of a pose mean's wander variance to a typical pose
// mean's white variance (variance_component.hpp: 10^-3 .. 10^4; below it changes no weight;
// above, white noise would not matter).
// Gauss-Markov correlation times per decade: thirty residuals cannot tell a factor of 1.8.
constexpr double kPoseTausPerDecade = 4.0;
// Penalised log likelihood within which flicker is preferred to the best candidate (see there).
constexpr double kPoseCautiousFlickerMargin = 3.0;
// Columns within this (QR pivot relative to the largest) of the span of the others are
// dropped, so that X^T Sigma^-1 X stays well conditioned for its log-determinant.
constexpr double kPoseRankThreshold = 1e-6;

/// A unit-amplitude candidate and the eigen-decomposition of its covariance in the whitened
/// residuals, D^-1/2 K D^-1/2 = U diag(lambda) U^T, which makes every amplitude trial
/// diagonal arithmetic.
struct PoseKernel {
  WanderModel unit;  ///< kind none: the independent extra variance
  Eigen::VectorXd lambda;
  Eigen::MatrixXd U;
  double mean_variance = 1.0;  ///< mean of K's diagonal: one pose mean's variance at amplitude 1
  int parameters = 1;
};

double shared_wander_covariance(const WanderModel& w, const PoseSpan& a, const PoseSpan& b) {
  return a.direction.dot(b.direction) *
         w.interval_mean_covariance(a.start_s, a.end_s, b.start_s, b.end_s);
}

PoseKernel make_pose_kernel(const WanderModel& unit, const std::vector<PoseSpan>& poses,
                            int parameters) {
  const auto n = static_cast<Eigen::Index>(poses.size());
  Eigen::MatrixXd G(n, n);
  double diag = 0.0;
  for (Eigen::Index i = 0; i < n; ++i) {
    const PoseSpan& a = poses[static_cast<std::size_t>(i)];
    for (Eigen::Index j = 0; j <= i; ++j) {
      const PoseSpan& b = poses[static_cast<std::size_t>(j)];
      double k = 0.0;
      if (unit.kind == WanderKind::kNone) {
        k = i == j ? 1.0 : 0.0;
      } else {
        k = shared_wander_covariance(unit, a, b);
      }
      if (i == j) diag += k;
      G(i, j) = G(j, i) = k / std::sqrt(a.white_variance * b.white_variance);
    }
  }
  PoseKernel out;
  out.unit = unit;
  out.parameters = parameters;
  out.mean_variance = diag / static_cast<double>(n);
  detail::KernelBasis basis = detail::kernel_basis(G);
  out.lambda = std::move(basis.lambda);
  out.U = std::move(basis.U);
  return out;
}

struct PoseTrial {
  double log_likelihood = -std::numeric_limits<double>::infinity();
  double amplitude = 0.0;
};

PoseTrial best_pose_amplitude(const PoseKernel& kernel, const Eigen::MatrixXd& Xw,
                              const Eigen::VectorXd& yw, double typical_white) {
  const Eigen::MatrixXd Xh = kernel.U.transpose() * Xw;
  const Eigen::VectorXd yh = kernel.U.transpose() * yw;
  const auto rho_of = [&](double r) {
    return std::pow(10.0, r) * typical_white / kernel.mean_variance;
  };
  const detail::RatioFit best = detail::best_log10_ratio([&](double r) {
    return detail::restricted_log_likelihood(kernel.lambda, Xh, yh, 1.0, rho_of(r));
  });
  return {best.log_likelihood, rho_of(best.log10_ratio)};
}

double median_of(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

WanderModel with_amplitude(WanderModel w, double amplitude) {
  const double root = std::sqrt(amplitude);
  if (w.kind == WanderKind::kGaussMarkov) w.sigma = root;
  if (w.kind == WanderKind::kFlicker) w.flicker_b = root;
  if (w.kind == WanderKind::kRandomWalk) w.random_walk_k = root;
  return w;
}

std::string describe_pose_noise(const PoseNoise& n, const PoseNoiseOptions& o) {
  const double s = o.description_scale;
  const std::string& u = o.description_unit;
  const std::string from = fmt::format("estimated by REML from {} residuals", n.residuals);
  switch (n.wander.kind) {
    case WanderKind::kGaussMarkov:
      return fmt::format(
          "pose means share a wandering bias (Gauss-Markov): sigma {:.3g} {}, correlation time "
          "{:.3g} s, {}",
          n.wander.sigma * s, u, n.wander.tau_s, from);
    case WanderKind::kSum:
      return fmt::format("pose means share a wandering bias (a sum of processes), {}", from);
    case WanderKind::kFlicker:
      return fmt::format(
          "pose means share a wandering bias (flicker, bias instability B {:.3g} {}): sigma "
          "{:.3g} {} per pose mean, correlation times {:.3g} to {:.3g} s, {}",
          n.wander.flicker_b * s, u, n.pose_sigma * s, u, n.wander.tau_min_s, n.wander.tau_max_s,
          from);
    case WanderKind::kRandomWalk:
      return fmt::format(
          "pose means share a wandering bias (random walk {:.3g} {}/sqrt(s)): sigma {:.3g} {} per "
          "pose mean, {}",
          n.wander.random_walk_k * s, u, n.pose_sigma * s, u, from);
    case WanderKind::kNone:
      break;
  }
  if (n.extra_variance > 0.0) {
    return fmt::format(
        "each pose mean scatters {:.3g} {} beyond its white noise, independently of its "
        "neighbours (hand placement, sway, or an effect the model lacks), {}",
        std::sqrt(n.extra_variance) * s, u, from);
  }
  return fmt::format(
      "pose means agree with their white noise (no shared wander nor extra scatter found by "
      "REML from {} residuals)",
      n.residuals);
}

}  // namespace

Eigen::MatrixXd PoseNoise::covariance(const std::vector<PoseSpan>& poses) const {
  const auto n = static_cast<Eigen::Index>(poses.size());
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(n, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const PoseSpan& a = poses[static_cast<std::size_t>(i)];
    C(i, i) = a.white_variance + extra_variance;
    if (wander.kind == WanderKind::kNone) continue;
    for (Eigen::Index j = 0; j <= i; ++j) {
      const double c = shared_wander_covariance(wander, a, poses[static_cast<std::size_t>(j)]);
      C(i, j) += c;
      if (j != i) C(j, i) += c;
    }
  }
  return C;
}

PoseNoise estimate_pose_noise(const std::vector<PoseSpan>& poses, const Eigen::VectorXd& residuals,
                              const Eigen::MatrixXd& jacobian, const PoseNoiseOptions& o) {
  PoseNoise out;
  const auto n = static_cast<Eigen::Index>(poses.size());
  out.residuals = static_cast<int>(n);

  // Whitened by the white part; columns normalised and reduced to full rank.
  Eigen::VectorXd yw(n);
  Eigen::MatrixXd X(n, jacobian.cols());
  for (Eigen::Index k = 0; k < n; ++k) {
    const double root = std::sqrt(poses[static_cast<std::size_t>(k)].white_variance);
    yw[k] = residuals[k] / root;
    X.row(k) = jacobian.row(k) / root;
  }
  for (Eigen::Index c = 0; c < X.cols(); ++c) {
    const double norm = X.col(c).norm();
    if (norm > 0.0) X.col(c) /= norm;
  }
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(X.rows(), X.cols());
  qr.setThreshold(kPoseRankThreshold);
  qr.compute(X);
  const auto rank = static_cast<Eigen::Index>(qr.rank());
  Eigen::MatrixXd Xw(n, rank);
  for (Eigen::Index c = 0; c < rank; ++c) Xw.col(c) = X.col(qr.colsPermutation().indices()[c]);
  out.dof = static_cast<int>(n - rank);
  if (out.dof < o.min_dof) {
    out.description = fmt::format(
        "white noise of the pose means alone: {} residuals leave {} degrees of freedom beyond "
        "the fitted parameters (at least {} needed to estimate a wandering bias)",
        n, out.dof, o.min_dof);
    return out;
  }
  out.estimated = true;

  std::vector<double> whites, durations;
  double first = poses.front().start_s, last = poses.front().end_s;
  for (const PoseSpan& p : poses) {
    whites.push_back(p.white_variance);
    durations.push_back(std::max(p.end_s - p.start_s, 1e-3));
    first = std::min(first, p.start_s);
    last = std::max(last, p.end_s);
  }
  const double typical_white = median_of(whites);
  const double span = std::max(last - first, 1e-3);
  // Correlation times shorter than a pose would show inside it (where the white part is
  // measured); longer than a few session spans, a process is a constant the bias absorbs.
  const double tau_lo = std::max(1.0, median_of(durations));
  const double tau_hi = std::max(10.0 * tau_lo, 3.0 * span);

  std::vector<PoseKernel> kernels;
  const int gm_count = std::max(
      2, static_cast<int>(std::ceil(kPoseTausPerDecade * std::log10(tau_hi / tau_lo))) + 1);
  for (int i = 0; i < gm_count; ++i) {
    WanderModel gm;
    gm.kind = WanderKind::kGaussMarkov;
    gm.sigma = 1.0;
    gm.tau_s = tau_lo * std::pow(tau_hi / tau_lo, static_cast<double>(i) / (gm_count - 1));
    kernels.push_back(make_pose_kernel(gm, poses, 2));
  }
  WanderModel flicker;
  flicker.kind = WanderKind::kFlicker;
  flicker.flicker_b = 1.0;
  // Flicker's components faster than a pose still move its mean (a component of a tenth of
  // a pose's duration adds a fifth of its variance), beyond what the scatter inside the pose
  // shows once white noise dominates the sample-to-sample scatter; below a tenth they average
  // out.
  flicker.tau_min_s = 0.1 * median_of(durations);
  flicker.tau_max_s = std::max(10.0 * span, 10.0 * tau_lo);
  kernels.push_back(make_pose_kernel(flicker, poses, 1));
  kernels.push_back(make_pose_kernel(WanderModel{}, poses, 1));  // independent extra variance

  const double white_ll =
      detail::restricted_log_likelihood(Eigen::VectorXd::Zero(n), Xw, yw, 1.0, 0.0);
  const double penalty_per_parameter = 0.5 * std::log(static_cast<double>(out.dof));
  double best_score = white_ll;
  const auto take = [&](const PoseKernel& k, const PoseTrial& t, double score) {
    best_score = score;
    out.pose_sigma = std::sqrt(t.amplitude * k.mean_variance);
    if (k.unit.kind == WanderKind::kNone) {
      out.wander = WanderModel{};
      out.extra_variance = t.amplitude;
    } else {
      out.wander = with_amplitude(k.unit, t.amplitude);
      out.extra_variance = 0.0;
    }
  };
  const PoseKernel* flicker_kernel = nullptr;
  PoseTrial flicker_trial;
  double flicker_score = -std::numeric_limits<double>::infinity();
  bool beyond_white = false;
  for (const PoseKernel& k : kernels) {
    const PoseTrial t = best_pose_amplitude(k, Xw, yw, typical_white);
    const double score = t.log_likelihood - penalty_per_parameter * k.parameters;
    if (k.unit.kind == WanderKind::kFlicker) {
      flicker_kernel = &k;
      flicker_trial = t;
      flicker_score = score;
    }
    if (!(score > best_score)) continue;
    take(k, t, score);
    beyond_white = true;
  }
  // Some twenty degrees of freedom tell a wander from white noise far better than one wander
  // from another: where flicker explains the residuals nearly as well as the best candidate,
  // take it. It is what accelerometer spec sheets describe (bias instability), and it keeps
  // both the fast part (which alone looks like an independent scatter per pose) and the slow
  // part (which alone looks like a long Gauss-Markov) that a narrower candidate would deny,
  // which made the sigmas too small.
  if (beyond_white && flicker_kernel != nullptr && out.wander.kind != WanderKind::kFlicker &&
      flicker_score >= best_score - kPoseCautiousFlickerMargin) {
    take(*flicker_kernel, flicker_trial, flicker_score);
  }
  out.log_likelihood_gain = best_score - white_ll;
  out.description = describe_pose_noise(out, o);
  return out;
}

nlohmann::json pose_noise_to_json(const PoseNoise& n) {
  nlohmann::json j{{"estimated", n.estimated},
                   {"kind", n.wander.kind == WanderKind::kNone && n.extra_variance > 0.0
                                ? std::string("independent")
                                : std::string(to_string(n.wander.kind))}};
  switch (n.wander.kind) {
    case WanderKind::kGaussMarkov:
      j["sigma"] = n.wander.sigma;
      j["tau_s"] = n.wander.tau_s;
      break;
    case WanderKind::kSum:
      j["parts"] = wander_to_json(n.wander)["parts"];
      break;
    case WanderKind::kFlicker:
      j["b"] = n.wander.flicker_b;
      j["tau_min_s"] = n.wander.tau_min_s;
      j["tau_max_s"] = n.wander.tau_max_s;
      break;
    case WanderKind::kRandomWalk:
      j["k"] = n.wander.random_walk_k;
      break;
    case WanderKind::kNone:
      break;
  }
  j["extra_sigma"] = std::sqrt(n.extra_variance);
  j["pose_sigma"] = n.pose_sigma;
  j["residuals"] = n.residuals;
  j["dof"] = n.dof;
  j["log_likelihood_gain"] = n.log_likelihood_gain;
  j["description"] = n.description;
  return j;
}

}  // namespace calstand::solver
