// IEEE Std 952 noise terms and a first-order Gauss-Markov model fitted to an Allan variance
// curve by weighted non-negative least squares.
#include "noise/noise_fit.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <boost/math/tools/minima.hpp>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <vector>

#include "core/error.hpp"
#include "noise/edf.hpp"

namespace calstand::solver {
namespace {

constexpr std::size_t kTerms = 5;  // Q, N, B, K, R
constexpr double kMinEdfForMinimum = 10.0;
// Bits of ln(tau_c) Brent's method resolves in the Gauss-Markov fit: 2^-25 relative, the
// 1e-7 the fit has always been resolved to.
constexpr int kLogTauBits = 26;

// Allan variance of each term per unit squared coefficient at tau.
double basis(std::size_t term, double tau) {
  switch (term) {
    case 0:
      return 3.0 / (tau * tau);
    case 1:
      return 1.0 / tau;
    case 2:
      return 2.0 * std::numbers::ln2 / std::numbers::pi;
    case 3:
      return tau / 3.0;
    default:
      return tau * tau / 2.0;
  }
}

// Weighted non-negative least squares min sum w_i (A c - b)_i^2, c >= 0, over the columns in
// `allowed`, by solving every subset of columns (at most 2^5) and keeping the best feasible
// one: the optimum is the unconstrained solution on its own support. Columns are scaled to
// unit weighted norm first (they span many decades of tau).
struct NnlsResult {
  Eigen::VectorXd c;    // all columns; zero outside the support
  Eigen::MatrixXd cov;  // covariance of c on the support (zero elsewhere)
  std::vector<bool> support;
  double cost = 0.0;
};

NnlsResult nnls(const Eigen::MatrixXd& a, const Eigen::VectorXd& b, const Eigen::VectorXd& w,
                const std::vector<bool>& allowed) {
  const auto cols = static_cast<std::size_t>(a.cols());
  const Eigen::VectorXd sw = w.cwiseSqrt();
  const Eigen::MatrixXd aw = sw.asDiagonal() * a;
  const Eigen::VectorXd bw = sw.cwiseProduct(b);
  Eigen::VectorXd scale(a.cols());
  for (Eigen::Index j = 0; j < a.cols(); ++j) {
    const double n = aw.col(j).norm();
    scale(j) = n > 0.0 ? 1.0 / n : 1.0;
  }
  NnlsResult best;
  best.c = Eigen::VectorXd::Zero(a.cols());
  best.cov = Eigen::MatrixXd::Zero(a.cols(), a.cols());
  best.support.assign(cols, false);
  best.cost = bw.squaredNorm();
  for (unsigned mask = 1; mask < (1U << cols); ++mask) {
    std::vector<Eigen::Index> idx;
    bool ok = true;
    for (std::size_t j = 0; j < cols; ++j) {
      if ((mask >> j) & 1U) {
        if (!allowed[j]) ok = false;
        idx.push_back(static_cast<Eigen::Index>(j));
      }
    }
    if (!ok || idx.size() > static_cast<std::size_t>(a.rows())) continue;
    Eigen::MatrixXd sub(a.rows(), static_cast<Eigen::Index>(idx.size()));
    for (std::size_t k = 0; k < idx.size(); ++k) {
      sub.col(static_cast<Eigen::Index>(k)) = aw.col(idx[k]) * scale(idx[k]);
    }
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(sub);
    if (qr.rank() < sub.cols()) continue;
    const Eigen::VectorXd x = qr.solve(bw);
    if ((x.array() <= 0.0).any()) continue;
    const double cost = (sub * x - bw).squaredNorm();
    if (cost >= best.cost) continue;
    best.cost = cost;
    best.c.setZero();
    best.cov.setZero();
    best.support.assign(cols, false);
    const Eigen::MatrixXd info_inv = (sub.transpose() * sub).inverse();
    for (std::size_t k = 0; k < idx.size(); ++k) {
      best.c(idx[k]) = x(static_cast<Eigen::Index>(k)) * scale(idx[k]);
      best.support[static_cast<std::size_t>(idx[k])] = true;
      for (std::size_t l = 0; l < idx.size(); ++l) {
        best.cov(idx[k], idx[l]) =
            info_inv(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(l)) * scale(idx[k]) *
            scale(idx[l]);
      }
    }
  }
  return best;
}

// The measured variances of a checked curve, and the degrees of freedom of each point for a
// given noise type (cached: a fit asks again on every pass).
class CurveData {
 public:
  CurveData(const AllanResult& curve, double min_tau_s) : samples_(curve.samples) {
    if (curve.kind != AllanKind::kAllan) {
      throw core::InputError("curve", fmt::format("the noise model is the Allan variance's; "
                                                  "got a {} curve",
                                                  to_string(curve.kind)));
    }
    for (const AllanPoint& p : curve.points) {
      if (p.tau_s < min_tau_s) continue;
      tau.push_back(p.tau_s);
      var.push_back(p.deviation * p.deviation);
      m_.push_back(p.m);
    }
    if (tau.size() < 2) {
      throw core::InputError("curve", fmt::format("{} averaging times from {} s on; a fit needs "
                                                  "at least 2",
                                                  tau.size(), min_tau_s));
    }
    cache_.assign(m_.size() * kAlphas, 0.0);
  }
  double edf(std::size_t i, int alpha) {
    double& e = cache_[i * kAlphas + static_cast<std::size_t>(alpha + 2)];
    if (e == 0.0) e = equivalent_dof(AllanKind::kAllan, alpha, m_[i], samples_);
    return e;
  }
  std::vector<double> tau, var;

 private:
  static constexpr std::size_t kAlphas = 5;  // -2 .. 2
  std::size_t samples_;
  std::vector<std::size_t> m_;
  std::vector<double> cache_;
};

// Noise type dominating a model Allan variance at tau: the power law of its local log-log
// slope (a slope of -2 is quantization, white PM).
template <typename Model>
int model_alpha(const Model& model, double tau) {
  const double f = 1.05;
  const double lo = model(tau / f), hi = model(tau * f);
  if (!(lo > 0.0 && hi > 0.0)) return 0;
  const double mu = std::log(hi / lo) / std::log(f * f);
  const int alpha = static_cast<int>(std::lround(-mu - 1.0));
  return alpha >= 1 ? 2 : std::max(alpha, -2);
}

// Inverse variance of each variance estimate, edf / (2 v^2), with v the model variance and the
// degrees of freedom of the noise type the model has there. The first pass (no model yet) uses
// the measured variance and white rate noise. A floor keeps a zero variance from taking all the
// weight.
template <typename Model>
Eigen::VectorXd weights(CurveData& d, const Model* model) {
  const double vmax = *std::max_element(d.var.begin(), d.var.end());
  Eigen::VectorXd w(static_cast<Eigen::Index>(d.var.size()));
  for (std::size_t i = 0; i < d.var.size(); ++i) {
    const double v = model ? (*model)(d.tau[i]) : d.var[i];
    const int alpha = model ? model_alpha(*model, d.tau[i]) : 0;
    const double vi = std::max(v, 1e-12 * vmax + std::numeric_limits<double>::min());
    w(static_cast<Eigen::Index>(i)) = d.edf(i, alpha) / (2.0 * vi * vi);
  }
  return w;
}

NoiseTerm term_from(const NnlsResult& r, std::size_t j, double sigma_scale) {
  NoiseTerm t;
  const auto k = static_cast<Eigen::Index>(j);
  if (!r.support[j]) return t;
  t.resolved = true;
  t.value = std::sqrt(r.c(k));
  // d sqrt(c) = dc / (2 sqrt(c))
  t.sigma = sigma_scale * std::sqrt(std::max(r.cov(k, k), 0.0)) / (2.0 * t.value);
  return t;
}

}  // namespace

double flicker_floor_factor() { return std::sqrt(2.0 * std::numbers::ln2 / std::numbers::pi); }

void NoiseFitOptions::validate() const {
  if (!(quantization || random_walk || bias_instability || rate_random_walk || rate_ramp)) {
    throw core::InputError("noise fit", "no noise term enabled");
  }
  if (iterations < 1) {
    throw core::InputError("iterations", fmt::format("must be at least 1, got {}", iterations));
  }
  if (!std::isfinite(min_tau_s) || min_tau_s < 0.0) {
    throw core::InputError("min_tau_s", fmt::format("must be finite and >= 0, got {}", min_tau_s));
  }
}

double noise_model_allan_variance(const NoiseTerms& t, double tau_s) {
  const std::array<double, kTerms> c = {t.quantization.value, t.random_walk.value,
                                        t.bias_instability.value, t.rate_random_walk.value,
                                        t.rate_ramp.value};
  double v = 0.0;
  for (std::size_t j = 0; j < kTerms; ++j) v += c[j] * c[j] * basis(j, tau_s);
  return v;
}

NoiseTerms fit_noise_terms(const AllanResult& curve, const NoiseFitOptions& options) {
  options.validate();
  CurveData d(curve, options.min_tau_s);
  const auto n = static_cast<Eigen::Index>(d.tau.size());
  Eigen::MatrixXd a(n, static_cast<Eigen::Index>(kTerms));
  Eigen::VectorXd b(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const auto ui = static_cast<std::size_t>(i);
    for (std::size_t j = 0; j < kTerms; ++j)
      a(i, static_cast<Eigen::Index>(j)) = basis(j, d.tau[ui]);
    b(i) = d.var[ui];
  }
  const std::vector<bool> allowed = {options.quantization, options.random_walk,
                                     options.bias_instability, options.rate_random_walk,
                                     options.rate_ramp};
  Eigen::VectorXd c = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(kTerms));
  const auto model = [&c](double tau) {
    double v = 0.0;
    for (std::size_t j = 0; j < kTerms; ++j) v += c(static_cast<Eigen::Index>(j)) * basis(j, tau);
    return v;
  };
  NnlsResult r;
  for (int pass = 0; pass < options.iterations; ++pass) {
    // Reweight from the model unless it vanishes (nothing fitted): then keep the data.
    const bool have_model = pass > 0 && c.maxCoeff() > 0.0;
    r = nnls(a, b, weights(d, have_model ? &model : nullptr), allowed);
    c = r.c;
  }
  std::size_t support = 0;
  for (const bool s : r.support) support += s ? 1 : 0;
  NoiseTerms t;
  t.points = d.tau.size();
  const double dof = static_cast<double>(t.points) - static_cast<double>(support);
  t.chi2_dof = dof > 0.0 ? r.cost / dof : 0.0;
  // Overlapping estimates at taus closer than a factor of 2 share most of their data, yet the
  // weights treat every point as independent: scale the sigmas by the square root of the
  // number of points per octave (1 for octave spacing, about 3 for dense).
  const double octaves = std::log2(d.tau.back() / d.tau.front());
  const double per_octave = octaves > 0.0 ? static_cast<double>(t.points - 1) / octaves : 1.0;
  const double sigma_scale =
      std::sqrt(std::max(1.0, t.chi2_dof)) * std::sqrt(std::max(1.0, per_octave));
  t.quantization = term_from(r, 0, sigma_scale);
  t.random_walk = term_from(r, 1, sigma_scale);
  t.bias_instability = term_from(r, 2, sigma_scale);
  t.rate_random_walk = term_from(r, 3, sigma_scale);
  t.rate_ramp = term_from(r, 4, sigma_scale);
  // The last taus rest on a handful of independent averages and scatter by tens of per cent,
  // so a minimum there is chance: read it where the estimate has kMinEdfForMinimum degrees of
  // freedom (about +-22 % at one sigma), or anywhere if no point has.
  std::size_t lowest = 0;
  bool found = false;
  for (const bool strict : {true, false}) {
    for (std::size_t i = 0; i < d.tau.size(); ++i) {
      // Degrees of freedom for the noise the fitted model has there (white FM if none).
      const int alpha = c.maxCoeff() > 0.0 ? model_alpha(model, d.tau[i]) : 0;
      if (strict && d.edf(i, alpha) < kMinEdfForMinimum) continue;
      if (!found || d.var[i] < d.var[lowest]) lowest = i;
      found = true;
    }
    if (found) break;
  }
  t.min_deviation = std::sqrt(d.var[lowest]);
  t.min_tau_s = d.tau[lowest];
  t.bias_instability_from_min = t.min_deviation / flicker_floor_factor();
  return t;
}

double gauss_markov_allan_variance(double sigma, double tau_c_s, double tau_s) {
  const double x = tau_s / tau_c_s;
  double bracket = 0.0;
  if (x < 1e-2) {
    // Series of x - 3/2 + 2 e^-x - e^-2x / 2: the direct form cancels to nothing here.
    bracket = x * x * x * (1.0 / 3.0 - x / 4.0 + 7.0 * x * x / 60.0 - x * x * x / 24.0);
  } else {
    bracket = x - 1.5 + 2.0 * std::exp(-x) - 0.5 * std::exp(-2.0 * x);
  }
  return 2.0 * sigma * sigma * bracket / (x * x);
}

GaussMarkovFit fit_gauss_markov(const AllanResult& curve, bool with_white_noise,
                                bool with_rate_random_walk) {
  CurveData d(curve, 0.0);
  const auto n = static_cast<Eigen::Index>(d.tau.size());
  Eigen::VectorXd b(n);
  for (Eigen::Index i = 0; i < n; ++i) b(i) = d.var[static_cast<std::size_t>(i)];
  const std::vector<bool> allowed = {true, with_white_noise, with_rate_random_walk};

  const auto design = [&](double tau_c) {
    Eigen::MatrixXd a(n, 3);
    for (Eigen::Index i = 0; i < n; ++i) {
      const double tau = d.tau[static_cast<std::size_t>(i)];
      a(i, 0) = gauss_markov_allan_variance(1.0, tau_c, tau);
      a(i, 1) = basis(1, tau);
      a(i, 2) = basis(3, tau);
    }
    return a;
  };
  double best_log_tau = 0.0;
  NnlsResult best;
  best.c = Eigen::VectorXd::Zero(3);
  const auto model = [&](double tau) {
    return gauss_markov_allan_variance(std::sqrt(best.c(0)), std::exp(best_log_tau), tau) +
           best.c(1) * basis(1, tau) + best.c(2) * basis(3, tau);
  };
  for (int pass = 0; pass < 4; ++pass) {
    const bool have_model = pass > 0 && best.c.maxCoeff() > 0.0;
    const Eigen::VectorXd w = weights(d, have_model ? &model : nullptr);
    const auto cost = [&](double log_tau) {
      return nnls(design(std::exp(log_tau)), b, w, allowed).cost;
    };
    // Grid over two decades beyond the curve at each end (the cost may dip more than once: the
    // grid finds the deepest), then Brent's method (Boost.Math) between the best point's
    // neighbours.
    const double lo = std::log(d.tau.front() / 100.0);
    const double hi = std::log(d.tau.back() * 100.0);
    constexpr int kGrid = 200;
    const double step = (hi - lo) / kGrid;
    int best_k = 0;
    double best_cost = std::numeric_limits<double>::infinity();
    for (int k = 0; k <= kGrid; ++k) {
      const double c = cost(lo + k * step);
      if (c < best_cost) {
        best_cost = c;
        best_k = k;
      }
    }
    const auto refined =
        boost::math::tools::brent_find_minima(cost, lo + std::max(best_k - 1, 0) * step,
                                              lo + std::min(best_k + 1, kGrid) * step, kLogTauBits);
    best_log_tau = refined.second <= best_cost ? refined.first : lo + best_k * step;
    best = nnls(design(std::exp(best_log_tau)), b, w, allowed);
  }
  GaussMarkovFit fit;
  fit.tau_c_s = std::exp(best_log_tau);
  fit.sigma = std::sqrt(best.c(0));
  fit.white_density = std::sqrt(best.c(1));
  fit.rate_random_walk = std::sqrt(best.c(2));
  std::size_t support = best.support[0] ? 1 : 0;  // tau_c counts only with its process
  for (const bool s : best.support) support += s ? 1 : 0;
  fit.parameters = support;
  const double dof = static_cast<double>(d.tau.size()) - static_cast<double>(support);
  fit.chi2_dof = dof > 0.0 ? best.cost / dof : 0.0;
  const double peak = 1.89 * fit.tau_c_s;
  fit.peak_in_range = best.support[0] && peak >= d.tau.front() && peak <= d.tau.back();
  return fit;
}

}  // namespace calstand::solver
