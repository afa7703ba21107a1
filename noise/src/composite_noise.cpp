// Composite noise model identification by the generalized method of wavelet moments (GMWM;
// Guerrier et al., JASA 2013) with model selection and parametric-bootstrap intervals.
#include "noise/composite_noise.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <random>

#include "core/error.hpp"
#include "noise/wavelet_covariance.hpp"

namespace calstand::solver {
namespace {

constexpr double kPi = 3.14159265358979323846;
// Flat Allan variance of flicker FM per squared bias instability B (IEEE Std 952: the Allan
// deviation's floor is 0.664 B).
const double kFlickerAvar = 2.0 * std::log(2.0) / kPi;

struct Term {
  NoiseKind kind;
  double value;  // N, Q, B, sigma, K or R
  double tau_s;  // Gauss-Markov only
};

std::size_t parameter_count(const std::vector<NoiseKind>& kinds) {
  std::size_t p = 0;
  for (NoiseKind k : kinds) p += k == NoiseKind::kGaussMarkov ? 2 : 1;
  return p;
}

// Allan variance of a first-order Gauss-Markov (AR(1)) sequence of variance sigma^2 and lag-1
// correlation phi at averaging factor m: (sigma^2 / m^2) (S1 - phi G^2) with S1 the variance sum
// of a block and phi G^2 the covariance of adjacent blocks, both geometric sums. Long double:
// the difference cancels to about 1 / (m (1 - phi)) of its terms for long correlation times.
double gauss_markov_avar(double sigma, double tau_s, std::size_t m, double rate_hz) {
  const long double a = 1.0L / (static_cast<long double>(tau_s) * rate_hz);
  const long double phi = std::exp(-a);
  const long double one_minus = -std::expm1(-a);
  const long double md = static_cast<long double>(m);
  const long double phim = std::exp(-a * md);
  const long double one_minus_m = -std::expm1(-a * md);
  const long double s1 = md + 2.0L * phi * (md * one_minus - one_minus_m) / (one_minus * one_minus);
  const long double g = one_minus_m / one_minus;
  (void)phim;
  const long double v = static_cast<long double>(sigma) * sigma / (md * md) * (s1 - phi * g * g);
  return static_cast<double>(std::max(v, 0.0L));
}

double term_avar(const Term& t, std::size_t m, double rate_hz) {
  const double md = static_cast<double>(m);
  const double tau = md / rate_hz;
  switch (t.kind) {
    case NoiseKind::kWhite:
      return t.value * t.value * rate_hz / md;  // sigma^2 = N^2 f_s per sample, / m
    case NoiseKind::kQuantization:
      return 3.0 * t.value * t.value / (tau * tau);
    case NoiseKind::kFlicker:
      return kFlickerAvar * t.value * t.value;
    case NoiseKind::kGaussMarkov:
      return gauss_markov_avar(t.value, t.tau_s, m, rate_hz);
    case NoiseKind::kRandomWalk:  // innovation K^2 tau0 per sample
      return t.value * t.value / rate_hz * (2.0 * md * md + 1.0) / (6.0 * md);
    case NoiseKind::kDrift:
      return 0.5 * t.value * t.value * tau * tau;
  }
  return 0.0;
}

// The two-sided spectrum of the first difference of a term, D(f) = 4 sin^2(pi f) S(f), at f
// cycles per sample, in unit^2 per cycle/sample (wavelet_variance_covariance()'s input).
// Per sample: white variance N^2 fs; quantization y = (Q fs)(e_t - e_t-1); flicker two-sided
// S = B^2 / (2 pi |f|) (its Haar variance is then (ln 2 / pi) B^2 at every scale); AR(1);
// random-walk increments of variance K^2 / fs. A ramp is not random: no spectrum.
double term_diff_psd(const Term& t, double f, double rate_hz) {
  const double s = std::sin(kPi * f);
  const double s2 = 4.0 * s * s;
  switch (t.kind) {
    case NoiseKind::kWhite:
      return s2 * t.value * t.value * rate_hz;
    case NoiseKind::kQuantization: {
      const double q = t.value * rate_hz;
      return s2 * s2 * q * q;
    }
    case NoiseKind::kFlicker:
      return s2 * t.value * t.value / (2.0 * kPi * f);
    case NoiseKind::kGaussMarkov: {
      const double a = 1.0 / (t.tau_s * rate_hz);
      const double phi = std::exp(-a);
      const double one_minus_phi2 = -std::expm1(-2.0 * a);
      // |1 - phi e^{-i 2 pi f}|^2 = (1 - phi)^2 + 4 phi sin^2(pi f), kept accurate for phi ~ 1.
      const double om = -std::expm1(-a);
      return s2 * t.value * t.value * one_minus_phi2 / (om * om + phi * s2);
    }
    case NoiseKind::kRandomWalk:
      return t.value * t.value / rate_hz;
    case NoiseKind::kDrift:
      return 0.0;
  }
  return 0.0;
}

// Parameters <-> terms: the logarithms of every value and Gauss-Markov time (all positive).
std::vector<Term> unpack(const std::vector<NoiseKind>& kinds, const Eigen::VectorXd& p) {
  std::vector<Term> terms;
  Eigen::Index i = 0;
  for (NoiseKind k : kinds) {
    Term t{k, std::exp(p[i++]), 0.0};
    if (k == NoiseKind::kGaussMarkov) t.tau_s = std::exp(p[i++]);
    terms.push_back(t);
  }
  return terms;
}
Eigen::VectorXd pack(const std::vector<Term>& terms) {
  std::vector<double> v;
  for (const Term& t : terms) {
    v.push_back(std::log(t.value));
    if (t.kind == NoiseKind::kGaussMarkov) v.push_back(std::log(t.tau_s));
  }
  return Eigen::Map<Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

Eigen::VectorXd model_nu(const std::vector<Term>& terms, const WaveletMoments& w) {
  Eigen::VectorXd nu = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(w.m.size()));
  for (std::size_t j = 0; j < w.m.size(); ++j) {
    for (const Term& t : terms)
      nu[static_cast<Eigen::Index>(j)] += 0.5 * term_avar(t, w.m[j], w.sample_rate_hz);
  }
  return nu;
}

// The residuals the Levenberg-Marquardt minimises: the GMWM's weighted distance as a sum of
// squares, for the first step's diagonal weights and the second step's full ones.
using ResidualFn = std::function<Eigen::VectorXd(const Eigen::VectorXd&)>;

// First step: sqrt(eta / 2) (nu_hat - nu) / nu_w with the weights' nu_w fixed (the inverse
// variances of chi-square estimates, scales taken as independent).
ResidualFn diagonal_residuals(const std::vector<NoiseKind>& kinds, const WaveletMoments& w,
                              const Eigen::VectorXd& nu_w) {
  return [&kinds, &w, nu_w](const Eigen::VectorXd& p) {
    const Eigen::VectorXd nu = model_nu(unpack(kinds, p), w);
    Eigen::VectorXd r(nu.size());
    for (Eigen::Index j = 0; j < nu.size(); ++j) {
      const auto ju = static_cast<std::size_t>(j);
      r[j] = std::sqrt(0.5 * w.dof[ju]) * (w.variance[ju] - nu[j]) / nu_w[j];
    }
    return r;
  };
}

// Second step: L^-1 (nu_hat - nu) with Omega = L L^T the covariance of the estimates across
// scales, so that the sum of squares is (nu_hat - nu)^T Omega^-1 (nu_hat - nu).
ResidualFn whitened_residuals(const std::vector<NoiseKind>& kinds, const WaveletMoments& w,
                              const Eigen::MatrixXd& chol_lower) {
  return [&kinds, &w, &chol_lower](const Eigen::VectorXd& p) {
    const Eigen::VectorXd nu = model_nu(unpack(kinds, p), w);
    const Eigen::VectorXd d = Eigen::Map<const Eigen::VectorXd>(w.variance.data(), nu.size()) - nu;
    return Eigen::VectorXd(chol_lower.triangularView<Eigen::Lower>().solve(d));
  };
}

// Levenberg-Marquardt on the residuals (numerical Jacobian in the log parameters).
Eigen::VectorXd levenberg_marquardt(Eigen::VectorXd p, const ResidualFn& residuals,
                                    int iterations = 60) {
  double lambda = 1e-3;
  Eigen::VectorXd r = residuals(p);
  double cost = r.squaredNorm();
  for (int it = 0; it < iterations; ++it) {
    Eigen::MatrixXd jac(r.size(), p.size());
    for (Eigen::Index k = 0; k < p.size(); ++k) {
      Eigen::VectorXd q = p;
      q[k] += 1e-6;
      jac.col(k) = (residuals(q) - r) / 1e-6;
    }
    const Eigen::MatrixXd jtj = jac.transpose() * jac;
    const Eigen::VectorXd g = jac.transpose() * r;
    bool improved = false;
    for (int tries = 0; tries < 12 && !improved; ++tries) {
      Eigen::MatrixXd a = jtj;
      a.diagonal() += lambda * (jtj.diagonal().array() + 1e-12).matrix();
      const Eigen::VectorXd step = a.ldlt().solve(-g);
      // Steps in log parameters beyond e^5 are a runaway (an unresolved term heading to 0).
      const Eigen::VectorXd q = p + step.cwiseMax(-5.0).cwiseMin(5.0);
      const Eigen::VectorXd rq = residuals(q);
      const double cq = rq.squaredNorm();
      if (std::isfinite(cq) && cq < cost) {
        const double gain = cost - cq;
        p = q;
        r = rq;
        cost = cq;
        lambda = std::max(lambda / 4.0, 1e-12);
        improved = true;
        if (gain < 1e-9 * (1.0 + cost)) return p;
      } else {
        lambda *= 8.0;
      }
    }
    if (!improved) break;
  }
  return p;
}

struct Fit {
  Eigen::VectorXd p;
  double objective = std::numeric_limits<double>::infinity();
};

// The GMWM with weights at the fit: weights from the data first, then from the fitted model
// (the data's own wavelet variances would weight a low estimate too heavily).
Fit fit_from(const std::vector<NoiseKind>& kinds, Eigen::VectorXd p, const WaveletMoments& w,
             int rounds = 3, int iterations = 60) {
  Eigen::VectorXd nu_w = Eigen::Map<const Eigen::VectorXd>(
      w.variance.data(), static_cast<Eigen::Index>(w.variance.size()));
  for (int round = 0; round < rounds; ++round) {
    p = levenberg_marquardt(p, diagonal_residuals(kinds, w, nu_w), iterations);
    nu_w = model_nu(unpack(kinds, p), w).cwiseMax(1e-300);
  }
  Fit f;
  f.p = p;
  f.objective = diagonal_residuals(kinds, w, nu_w)(p).squaredNorm();
  if (!std::isfinite(f.objective)) f.objective = std::numeric_limits<double>::infinity();
  return f;
}

// Starting points: each amplitude from the part of the curve where its term dominates; the
// Gauss-Markov times from a log grid over the scales (pairs of distinct times for two).
std::vector<Eigen::VectorXd> starts(const std::vector<NoiseKind>& kinds, const WaveletMoments& w) {
  const double fs = w.sample_rate_hz;
  const double avar1 = 2.0 * w.variance.front();
  const double tau1 = static_cast<double>(w.m.front()) / fs;  // the first scale's averaging time
  const double avar_last = 2.0 * w.variance.back();
  const double tau_last = static_cast<double>(w.m.back()) / fs;
  const double avar_min = 2.0 * *std::min_element(w.variance.begin(), w.variance.end());
  const auto avar_near = [&](double tau_s) {
    std::size_t best = 0;
    for (std::size_t j = 0; j < w.m.size(); ++j) {
      if (std::abs(std::log(static_cast<double>(w.m[j]) / fs / tau_s)) <
          std::abs(std::log(static_cast<double>(w.m[best]) / fs / tau_s))) {
        best = j;
      }
    }
    return 2.0 * w.variance[best];
  };
  std::vector<double> grid;
  const double lo = 2.0 * tau1, hi = 0.5 * tau_last;
  for (int k = 0; k < 7; ++k) grid.push_back(lo * std::pow(hi / lo, k / 6.0));
  const int gm = static_cast<int>(std::count(kinds.begin(), kinds.end(), NoiseKind::kGaussMarkov));
  std::vector<std::vector<double>> taus;
  if (gm == 0) taus.push_back({});
  if (gm == 1) {
    for (double t : grid) taus.push_back({t});
  }
  if (gm == 2) {
    for (std::size_t i = 0; i < grid.size(); ++i) {
      for (std::size_t j = i + 2; j < grid.size(); ++j) taus.push_back({grid[i], grid[j]});
    }
  }
  std::vector<Eigen::VectorXd> out;
  for (const auto& tset : taus) {
    std::vector<Term> terms;
    std::size_t g = 0;
    for (NoiseKind k : kinds) {
      switch (k) {
        case NoiseKind::kWhite:
          terms.push_back({k, 0.7 * std::sqrt(avar1 * tau1), 0.0});
          break;
        case NoiseKind::kQuantization:
          terms.push_back({k, 0.3 * std::sqrt(avar1 / 3.0) * tau1, 0.0});
          break;
        case NoiseKind::kFlicker:
          terms.push_back({k, 0.7 * std::sqrt(avar_min / kFlickerAvar), 0.0});
          break;
        case NoiseKind::kGaussMarkov: {
          const double t = tset[g++];
          terms.push_back({k, 0.7 * std::sqrt(avar_near(t) / 0.3), t});
          break;
        }
        case NoiseKind::kRandomWalk:
          terms.push_back({k, 0.5 * std::sqrt(3.0 * avar_last / tau_last), 0.0});
          break;
        case NoiseKind::kDrift:
          terms.push_back({k, 0.3 * std::sqrt(2.0 * avar_last) / tau_last, 0.0});
          break;
      }
    }
    out.push_back(pack(terms));
  }
  return out;
}

// Every start a few iterations, the most promising ones to convergence.
Fit fit_candidate(const std::vector<NoiseKind>& kinds, const WaveletMoments& w) {
  std::vector<Fit> rough;
  for (const Eigen::VectorXd& p0 : starts(kinds, w)) rough.push_back(fit_from(kinds, p0, w, 2, 8));
  std::sort(rough.begin(), rough.end(),
            [](const Fit& a, const Fit& b) { return a.objective < b.objective; });
  Fit best;
  for (std::size_t i = 0; i < std::min<std::size_t>(3, rough.size()); ++i) {
    Fit f = fit_from(kinds, rough[i].p, w);
    if (f.objective < best.objective) best = f;
  }
  return best;
}

// Every term resolved: at least 2 % of the model's wavelet variance at some scale, and a
// Gauss-Markov time within the scales (shorter it is white noise; longer than a quarter of the
// longest averaging time the record does not see it level off, and it is a random walk).
bool admissible(const std::vector<Term>& terms, const WaveletMoments& w) {
  const Eigen::VectorXd total = model_nu(terms, w);
  const double fs = w.sample_rate_hz;
  std::vector<double> gm_taus;
  for (const Term& t : terms) {
    double share = 0.0;
    for (std::size_t j = 0; j < w.m.size(); ++j) {
      share = std::max(share, 0.5 * term_avar(t, w.m[j], fs) / total[static_cast<Eigen::Index>(j)]);
    }
    if (!(share >= 0.02)) return false;
    if (t.kind == NoiseKind::kGaussMarkov) {
      // Its Allan variance peaks at 1.89 tau_s: that turn, which tells it from a random walk,
      // must lie an octave inside the longest averaging time.
      if (t.tau_s < static_cast<double>(w.m.front()) / fs ||
          2.0 * 1.89 * t.tau_s > static_cast<double>(w.m.back()) / fs) {
        return false;
      }
      gm_taus.push_back(t.tau_s);
    }
  }
  if (gm_taus.size() == 2 &&
      std::max(gm_taus[0], gm_taus[1]) < 2.0 * std::min(gm_taus[0], gm_taus[1])) {
    return false;
  }
  return true;
}

// ---- the parametric bootstrap: records simulated from a model by exact recursions ----

std::vector<double> simulate(const std::vector<Term>& terms, std::size_t n, double fs,
                             std::mt19937_64& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<double> y(n, 0.0);
  const double tau0 = 1.0 / fs;
  for (const Term& t : terms) {
    switch (t.kind) {
      case NoiseKind::kWhite: {
        const double s = t.value * std::sqrt(fs);
        for (double& v : y) v += s * g(rng);
        break;
      }
      case NoiseKind::kQuantization: {  // white phase noise, differenced
        const double s = t.value / tau0;
        double prev = s * g(rng);
        for (double& v : y) {
          const double e = s * g(rng);
          v += e - prev;
          prev = e;
        }
        break;
      }
      case NoiseKind::kGaussMarkov: {
        const double phi = std::exp(-tau0 / t.tau_s);
        const double q = t.value * std::sqrt(1.0 - phi * phi);
        double x = t.value * g(rng);
        for (double& v : y) {
          v += x;
          x = phi * x + q * g(rng);
        }
        break;
      }
      case NoiseKind::kFlicker: {
        // A bank of Gauss-Markov processes a factor of 4 apart in time spans the record; their
        // common sigma is set so that the bank's Allan variance at the record's middle octave
        // is the flicker floor (the bank is flat to a few per cent between its ends).
        std::vector<double> taus;
        for (double tc = tau0; tc < static_cast<double>(n) * tau0 * 4.0; tc *= 4.0)
          taus.push_back(tc);
        const std::size_t mid =
            std::max<std::size_t>(1, static_cast<std::size_t>(std::sqrt(static_cast<double>(n))));
        double unit = 0.0;
        for (double tc : taus) unit += gauss_markov_avar(1.0, tc, mid, fs);
        const double sigma = std::sqrt(kFlickerAvar * t.value * t.value / unit);
        for (double tc : taus) {
          const double phi = std::exp(-tau0 / tc);
          const double q = sigma * std::sqrt(1.0 - phi * phi);
          double x = sigma * g(rng);
          for (double& v : y) {
            v += x;
            x = phi * x + q * g(rng);
          }
        }
        break;
      }
      case NoiseKind::kRandomWalk: {
        const double s = t.value * std::sqrt(tau0);
        double x = 0.0;
        for (double& v : y) {
          x += s * g(rng);
          v += x;
        }
        break;
      }
      case NoiseKind::kDrift:
        for (std::size_t i = 0; i < n; ++i) y[i] += t.value * tau0 * static_cast<double>(i);
        break;
    }
  }
  return y;
}

// The covariance of the wavelet variances under a model (its spectrum), as a lower Cholesky
// factor; a relative jitter on the diagonal keeps it positive definite when two scales are
// almost perfectly correlated.
Eigen::MatrixXd covariance_factor(const std::vector<Term>& terms, const WaveletMoments& w) {
  const double fs = w.sample_rate_hz;
  Eigen::MatrixXd omega = wavelet_variance_covariance(w.m, w.samples, [&](double f) {
    double d = 0.0;
    for (const Term& t : terms) d += term_diff_psd(t, f, fs);
    return d;
  });
  omega.diagonal() *= 1.0 + 1e-9;
  Eigen::LLT<Eigen::MatrixXd> llt(omega);
  if (llt.info() != Eigen::Success) {
    omega = Eigen::MatrixXd(omega.diagonal().asDiagonal());
    llt.compute(omega);
  }
  return llt.matrixL();
}

// The second step: the GMWM with the weights Omega^-1 = (L L^T)^-1, from the first step's
// estimate and from `also` (an earlier second step); the better of the two.
Fit fit_efficient(const std::vector<NoiseKind>& kinds, const WaveletMoments& w,
                  const Eigen::MatrixXd& chol_lower, const std::vector<Eigen::VectorXd>& from) {
  const ResidualFn r = whitened_residuals(kinds, w, chol_lower);
  Fit best;
  for (const Eigen::VectorXd& p0 : from) {
    Fit f;
    f.p = levenberg_marquardt(p0, r);
    f.objective = r(f.p).squaredNorm();
    if (!std::isfinite(f.objective)) f.objective = std::numeric_limits<double>::infinity();
    if (f.objective < best.objective) best = f;
  }
  return best;
}

// The wavelet variances of `rate` from the first scale whose averaging time reaches min_tau_s.
WaveletMoments trimmed_moments(WaveletMoments wm, double min_tau_s) {
  const double sample_rate_hz = wm.sample_rate_hz;
  std::size_t skip = 0;
  while (skip < wm.m.size() && static_cast<double>(wm.m[skip]) / sample_rate_hz < min_tau_s) {
    ++skip;
  }
  if (wm.m.size() - skip < 4) {
    throw core::InputError("min_tau_s",
                           fmt::format("{} s leaves {} scales of the record; at least 4 are needed",
                                       min_tau_s, wm.m.size() - skip));
  }
  const auto d = static_cast<std::ptrdiff_t>(skip);
  wm.m.erase(wm.m.begin(), wm.m.begin() + d);
  wm.variance.erase(wm.variance.begin(), wm.variance.begin() + d);
  wm.dof.erase(wm.dof.begin(), wm.dof.begin() + d);
  return wm;
}

// The wavelet variances of `rate` from the first scale whose averaging time reaches min_tau_s.
WaveletMoments moments_from(std::span<const double> rate, double sample_rate_hz, double min_tau_s) {
  return trimmed_moments(wavelet_moments(rate, sample_rate_hz), min_tau_s);
}

double percentile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  const double pos = q * static_cast<double>(v.size() - 1);
  const auto i = static_cast<std::size_t>(std::floor(pos));
  const double f = pos - static_cast<double>(i);
  return i + 1 < v.size() ? v[i] * (1.0 - f) + v[i + 1] * f : v.back();
}

}  // namespace

std::string_view to_string(NoiseKind kind) {
  switch (kind) {
    case NoiseKind::kWhite:
      return "white";
    case NoiseKind::kQuantization:
      return "quantization";
    case NoiseKind::kFlicker:
      return "flicker";
    case NoiseKind::kGaussMarkov:
      return "gauss_markov";
    case NoiseKind::kRandomWalk:
      return "random_walk";
    case NoiseKind::kDrift:
      return "drift";
  }
  return "?";
}

void NoiseIdOptions::validate() const {
  if (!(min_tau_s >= 0.0) || !std::isfinite(min_tau_s)) {
    throw core::InputError("min_tau_s", fmt::format("must be finite and >= 0, got {}", min_tau_s));
  }
  if (bootstrap != 0 && bootstrap < 20) {
    throw core::InputError(
        "bootstrap",
        fmt::format("0 (asymptotic intervals) or at least 20 replicates, got {}", bootstrap));
  }
}

double term_wavelet_variance(NoiseKind kind, double value, double tau_s, std::size_t m,
                             double sample_rate_hz) {
  return 0.5 * term_avar(Term{kind, value, tau_s}, m, sample_rate_hz);
}

NoiseModel identify_noise_model(std::span<const double> rate, double sample_rate_hz,
                                const NoiseIdOptions& options) {
  options.validate();
  return identify_noise_model(wavelet_moments(rate, sample_rate_hz), options);
}

NoiseModel identify_noise_model(const WaveletMoments& moments, const NoiseIdOptions& options) {
  options.validate();
  if (moments.m.empty() || moments.variance.size() != moments.m.size() ||
      moments.dof.size() != moments.m.size() || moments.m.front() != 1) {
    throw core::InputError("moments", "expected the wavelet variances from m = 1 on");
  }
  const double sample_rate_hz = moments.sample_rate_hz;
  // The record's length: the bootstrap simulates records as long (it needs no data).
  const std::size_t samples = moments.samples;
  NoiseModel out;
  out.moments = trimmed_moments(moments, options.min_tau_s);
  out.sample_rate_hz = sample_rate_hz;
  out.samples = samples;
  const WaveletMoments& w = out.moments;
  // The Hannan-Quinn penalty 2 ln ln n per parameter (Andrews 1999, "Consistent moment
  // selection procedures for GMM estimation", MSC-HQIC): under the efficient weights the
  // objective J of a right candidate is chi-square with J - p degrees of freedom and that of a
  // wrong one grows as n, so any penalty growing slower than n and faster than ln ln n selects
  // the right set with probability -> 1. BIC's ln n (12.5 at 2^18 samples) assumes every
  // parameter is informed by all n samples; a random walk or a long Gauss-Markov time is
  // informed by the few long scales only, and BIC dropped them (white + GM + RW was taken
  // for white + flicker in 4 of 6 records).
  const double penalty = 2.0 * std::log(std::log(static_cast<double>(samples)));

  std::vector<std::vector<NoiseKind>> all_kinds;
  for (int q = 0; q < 2; ++q) {
    for (int f = 0; f < 2; ++f) {
      for (int gm = 0; gm < 3; ++gm) {
        for (int rw = 0; rw < 2; ++rw) {
          for (int dr = 0; dr < (options.drift ? 2 : 1); ++dr) {
            std::vector<NoiseKind> kinds{NoiseKind::kWhite};
            if (q) kinds.push_back(NoiseKind::kQuantization);
            if (f) kinds.push_back(NoiseKind::kFlicker);
            for (int k = 0; k < gm; ++k) kinds.push_back(NoiseKind::kGaussMarkov);
            if (rw) kinds.push_back(NoiseKind::kRandomWalk);
            if (dr) kinds.push_back(NoiseKind::kDrift);
            if (parameter_count(kinds) + 1 >= w.m.size()) continue;  // more parameters than moments
            all_kinds.push_back(kinds);
          }
        }
      }
    }
  }
  // First step: each candidate with diagonal weights, from several starts.
  std::vector<Fit> first;
  for (const auto& kinds : all_kinds) first.push_back(fit_candidate(kinds, w));
  // Second step: every candidate with the same efficient weights, the inverse covariance of
  // the wavelet variances under the spectrum of the candidate that fits them best in the first
  // step (whatever its size: the most flexible fit is the best estimate of the record's
  // spectrum). Common weights make the candidates' objectives comparable; a candidate's own
  // weights would let it inflate its predicted variance where it fits badly.
  std::size_t reference = 0;
  {
    bool any_admissible = false;
    for (std::size_t i = 0; i < all_kinds.size(); ++i) {
      // Not a candidate with a ramp: a ramp is not random, so its spectrum would claim the
      // long scales' wavelet variances are exact and weigh them as if they were, against
      // every candidate that explains them by a random walk.
      if (std::count(all_kinds[i].begin(), all_kinds[i].end(), NoiseKind::kDrift) > 0) continue;
      const bool adm =
          std::isfinite(first[i].objective) && admissible(unpack(all_kinds[i], first[i].p), w);
      if ((adm && !any_admissible) ||
          (adm == any_admissible && first[i].objective < first[reference].objective)) {
        reference = i;
      }
      any_admissible = any_admissible || adm;
    }
  }
  const Eigen::MatrixXd common =
      covariance_factor(unpack(all_kinds[reference], first[reference].p), w);
  std::vector<Fit> fits(all_kinds.size());
  std::size_t best = 0;
  bool any = false;
  for (std::size_t i = 0; i < all_kinds.size(); ++i) {
    fits[i] = fit_efficient(all_kinds[i], w, common, {first[i].p});
    NoiseCandidate c;
    c.kinds = all_kinds[i];
    c.parameters = parameter_count(c.kinds);
    c.objective = fits[i].objective;
    c.criterion = c.objective + static_cast<double>(c.parameters) * penalty;
    c.admissible = std::isfinite(c.objective) && admissible(unpack(all_kinds[i], fits[i].p), w);
    if (c.admissible && (!any || c.criterion < out.candidates[best].criterion)) {
      best = i;
      any = true;
    }
    out.candidates.push_back(c);
  }
  if (!any) throw core::InputError("data", "no candidate noise model fits the record");
  out.candidates[best].selected = true;
  out.selected_by = fmt::format(
      "lowest J + 2 p ln ln n (Hannan-Quinn; J: the efficient GMWM objective, chi-square with "
      "{} - p degrees of freedom for a right model; p parameters; n = {} samples) among the "
      "candidates whose every term is resolved",
      w.m.size(), samples);
  const std::vector<NoiseKind>& kinds = out.candidates[best].kinds;
  // The selected model's estimate with the weights of its own spectrum (efficient under it).
  const Eigen::MatrixXd own = covariance_factor(unpack(kinds, fits[best].p), w);
  const Fit refit = fit_efficient(kinds, w, own, {fits[best].p});
  const Eigen::VectorXd p_hat =
      std::isfinite(refit.objective) && admissible(unpack(kinds, refit.p), w) ? refit.p
                                                                              : fits[best].p;
  const std::vector<Term> terms = unpack(kinds, p_hat);
  const Eigen::MatrixXd chol = covariance_factor(terms, w);
  out.fitted.assign(w.m.size(), 0.0);
  const Eigen::VectorXd nu = model_nu(terms, w);
  for (std::size_t j = 0; j < w.m.size(); ++j) out.fitted[j] = nu[static_cast<Eigen::Index>(j)];

  // Intervals in the log parameters: the efficient GMWM's asymptotic covariance
  // (G^T Omega^-1 G)^-1, G the model's wavelet variances' derivatives (Guerrier et al. 2013,
  // Proposition 2), or the parametric bootstrap when asked for.
  const auto np = p_hat.size();
  Eigen::VectorXd lo(np), hi(np);
  if (options.bootstrap == 0) {
    out.estimator =
        "GMWM on Haar wavelet variances, weights: the inverse of their covariance across scales "
        "under the fitted model's spectrum; 95 % intervals from the estimator's asymptotic "
        "covariance (log parameters)";
    Eigen::MatrixXd g(static_cast<Eigen::Index>(w.m.size()), np);
    for (Eigen::Index k = 0; k < np; ++k) {
      Eigen::VectorXd q = p_hat;
      q[k] += 1e-6;
      g.col(k) = (model_nu(unpack(kinds, q), w) - nu) / 1e-6;
    }
    const Eigen::MatrixXd gw = chol.triangularView<Eigen::Lower>().solve(g);
    const Eigen::MatrixXd info = gw.transpose() * gw;
    const Eigen::MatrixXd cov = info.completeOrthogonalDecomposition().pseudoInverse();
    for (Eigen::Index k = 0; k < np; ++k) {
      const double se = std::sqrt(std::max(cov(k, k), 0.0));
      lo[k] = p_hat[k] - 1.959964 * se;
      hi[k] = p_hat[k] + 1.959964 * se;
    }
  } else {
    out.estimator = fmt::format(
        "GMWM on Haar wavelet variances, weights: the inverse of their covariance across scales "
        "under the fitted model's spectrum; 95 % intervals from {} parametric-bootstrap records",
        options.bootstrap);
    std::mt19937_64 rng(options.seed);
    std::vector<std::vector<double>> draws(static_cast<std::size_t>(np));
    for (std::size_t b = 0; b < options.bootstrap; ++b) {
      const std::vector<double> y = simulate(terms, samples, sample_rate_hz, rng);
      const WaveletMoments wb = moments_from(y, sample_rate_hz, options.min_tau_s);
      const Fit f = fit_efficient(kinds, wb, chol, {p_hat});
      if (!std::isfinite(f.objective)) continue;
      for (Eigen::Index k = 0; k < np; ++k) draws[static_cast<std::size_t>(k)].push_back(f.p[k]);
    }
    for (Eigen::Index k = 0; k < np; ++k) {
      const auto& d = draws[static_cast<std::size_t>(k)];
      if (d.size() < 10) {
        lo[k] = hi[k] = std::nan("");
        continue;
      }
      // Basic (reflected) percentile interval in the log: 2 theta - q(0.975), 2 theta -
      // q(0.025), which corrects the estimator's bias as the bootstrap sees it.
      lo[k] = 2.0 * p_hat[k] - percentile(d, 0.975);
      hi[k] = 2.0 * p_hat[k] - percentile(d, 0.025);
    }
  }
  Eigen::Index k = 0;
  for (const Term& term : terms) {
    NoiseModelTerm t;
    t.kind = term.kind;
    t.value = term.value;
    t.value_lo = std::exp(lo[k]);
    t.value_hi = std::exp(hi[k]);
    ++k;
    if (t.kind == NoiseKind::kGaussMarkov) {
      t.tau_s = term.tau_s;
      t.tau_lo_s = std::exp(lo[k]);
      t.tau_hi_s = std::exp(hi[k]);
      ++k;
    }
    out.terms.push_back(t);
  }
  std::sort(out.terms.begin(), out.terms.end(),
            [](const NoiseModelTerm& a, const NoiseModelTerm& b) {
              return a.kind != b.kind ? a.kind < b.kind : a.tau_s < b.tau_s;
            });
  return out;
}

}  // namespace calstand::solver
