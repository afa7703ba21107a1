// Composite noise model identification by the generalized method of wavelet moments (GMWM;
// Guerrier et al., JASA 2013) with model selection and parametric-bootstrap intervals.
#include "noise/composite_noise.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "core/error.hpp"

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

// Weighted residuals sqrt(eta / 2) (nu_hat - nu) / nu_w with the weights' nu_w fixed.
Eigen::VectorXd residuals(const std::vector<NoiseKind>& kinds, const Eigen::VectorXd& p,
                          const WaveletMoments& w, const Eigen::VectorXd& nu_w) {
  const Eigen::VectorXd nu = model_nu(unpack(kinds, p), w);
  Eigen::VectorXd r(nu.size());
  for (Eigen::Index j = 0; j < nu.size(); ++j) {
    const auto ju = static_cast<std::size_t>(j);
    r[j] = std::sqrt(0.5 * w.dof[ju]) * (w.variance[ju] - nu[j]) / nu_w[j];
  }
  return r;
}

// Levenberg-Marquardt on the weighted residuals (numerical Jacobian in the log parameters).
Eigen::VectorXd levenberg_marquardt(const std::vector<NoiseKind>& kinds, Eigen::VectorXd p,
                                    const WaveletMoments& w, const Eigen::VectorXd& nu_w) {
  double lambda = 1e-3;
  Eigen::VectorXd r = residuals(kinds, p, w, nu_w);
  double cost = r.squaredNorm();
  for (int it = 0; it < 60; ++it) {
    Eigen::MatrixXd jac(r.size(), p.size());
    for (Eigen::Index k = 0; k < p.size(); ++k) {
      Eigen::VectorXd q = p;
      q[k] += 1e-6;
      jac.col(k) = (residuals(kinds, q, w, nu_w) - r) / 1e-6;
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
      const Eigen::VectorXd rq = residuals(kinds, q, w, nu_w);
      const double cq = rq.squaredNorm();
      if (std::isfinite(cq) && cq < cost) {
        const double gain = cost - cq;
        p = q;
        r = rq;
        cost = cq;
        lambda = std::max(lambda / 4.0, 1e-12);
        improved = true;
        if (gain < 1e-12 * (1.0 + cost)) return p;
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
Fit fit_from(const std::vector<NoiseKind>& kinds, Eigen::VectorXd p, const WaveletMoments& w) {
  Eigen::VectorXd nu_w = Eigen::Map<const Eigen::VectorXd>(
      w.variance.data(), static_cast<Eigen::Index>(w.variance.size()));
  for (int round = 0; round < 3; ++round) {
    p = levenberg_marquardt(kinds, p, w, nu_w);
    nu_w = model_nu(unpack(kinds, p), w).cwiseMax(1e-300);
  }
  Fit f;
  f.p = p;
  f.objective = residuals(kinds, p, w, nu_w).squaredNorm();
  if (!std::isfinite(f.objective)) f.objective = std::numeric_limits<double>::infinity();
  return f;
}

// Starting points: each amplitude from the part of the curve where its term dominates; the
// Gauss-Markov times from a log grid over the scales (pairs of distinct times for two).
std::vector<Eigen::VectorXd> starts(const std::vector<NoiseKind>& kinds, const WaveletMoments& w) {
  const double fs = w.sample_rate_hz;
  const double avar1 = 2.0 * w.variance.front();
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
  const double lo = 2.0 / fs, hi = 0.5 * tau_last;
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
          terms.push_back({k, 0.7 * std::sqrt(avar1 / fs), 0.0});
          break;
        case NoiseKind::kQuantization:
          terms.push_back({k, 0.3 * std::sqrt(avar1 / 3.0) / fs, 0.0});
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

Fit fit_candidate(const std::vector<NoiseKind>& kinds, const WaveletMoments& w) {
  Fit best;
  for (const Eigen::VectorXd& p0 : starts(kinds, w)) {
    Fit f = fit_from(kinds, p0, w);
    if (f.objective < best.objective) best = f;
  }
  return best;
}

// Every term resolved: at least 2 % of the model's wavelet variance at some scale, and a
// Gauss-Markov time within the scales (shorter it is white noise, longer a random walk).
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
      if (t.tau_s < 1.0 / fs || t.tau_s > static_cast<double>(w.m.back()) / fs) return false;
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
  if (bootstrap < 20) {
    throw core::InputError("bootstrap", fmt::format("at least 20 replicates, got {}", bootstrap));
  }
}

double term_wavelet_variance(NoiseKind kind, double value, double tau_s, std::size_t m,
                             double sample_rate_hz) {
  return 0.5 * term_avar(Term{kind, value, tau_s}, m, sample_rate_hz);
}

NoiseModel identify_noise_model(std::span<const double> rate, double sample_rate_hz,
                                const NoiseIdOptions& options) {
  options.validate();
  NoiseModel out;
  out.moments = wavelet_moments(rate, sample_rate_hz);
  out.sample_rate_hz = sample_rate_hz;
  out.samples = rate.size();
  const WaveletMoments& w = out.moments;
  const double log_j = std::log(static_cast<double>(w.m.size()));

  std::vector<Fit> fits;
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
            NoiseCandidate c;
            c.kinds = kinds;
            c.parameters = parameter_count(kinds);
            if (c.parameters + 1 >= w.m.size()) continue;  // more parameters than moments
            const Fit fit = fit_candidate(kinds, w);
            c.objective = fit.objective;
            c.criterion = fit.objective + static_cast<double>(c.parameters) * log_j;
            c.admissible = std::isfinite(fit.objective) && admissible(unpack(kinds, fit.p), w);
            out.candidates.push_back(c);
            fits.push_back(fit);
          }
        }
      }
    }
  }
  std::size_t best = 0;
  bool any = false;
  for (std::size_t i = 0; i < out.candidates.size(); ++i) {
    if (!out.candidates[i].admissible) continue;
    if (!any || out.candidates[i].criterion < out.candidates[best].criterion) best = i;
    any = true;
  }
  if (!any) throw core::InputError("data", "no candidate noise model fits the record");
  out.candidates[best].selected = true;
  out.selected_by = fmt::format(
      "lowest GMWM objective + p ln(J) (J = {} dyadic scales) among the candidates whose every "
      "term is resolved",
      w.m.size());
  out.estimator = fmt::format(
      "GMWM on Haar wavelet variances, inverse-variance weights at the fit; 95 % intervals from "
      "{} parametric-bootstrap records",
      options.bootstrap);
  const std::vector<NoiseKind>& kinds = out.candidates[best].kinds;
  const std::vector<Term> terms = unpack(kinds, fits[best].p);
  out.fitted.assign(w.m.size(), 0.0);
  const Eigen::VectorXd nu = model_nu(terms, w);
  for (std::size_t j = 0; j < w.m.size(); ++j) out.fitted[j] = nu[static_cast<Eigen::Index>(j)];

  // Parametric bootstrap: the selected model refitted to records simulated from the fit.
  std::mt19937_64 rng(options.seed);
  std::vector<std::vector<double>> values(terms.size()), taus(terms.size());
  for (std::size_t b = 0; b < options.bootstrap; ++b) {
    const std::vector<double> y = simulate(terms, rate.size(), sample_rate_hz, rng);
    const WaveletMoments wb = wavelet_moments(y, sample_rate_hz);
    const Fit f = fit_from(kinds, fits[best].p, wb);
    if (!std::isfinite(f.objective)) continue;
    const std::vector<Term> tb = unpack(kinds, f.p);
    for (std::size_t k = 0; k < tb.size(); ++k) {
      values[k].push_back(tb[k].value);
      taus[k].push_back(tb[k].tau_s);
    }
  }
  for (std::size_t k = 0; k < terms.size(); ++k) {
    NoiseModelTerm t;
    t.kind = terms[k].kind;
    t.value = terms[k].value;
    t.tau_s = terms[k].tau_s;
    if (values[k].size() >= 10) {
      // Basic (reflected) percentile interval: 2 theta - q(0.975), 2 theta - q(0.025) in the
      // log, which corrects the estimator's bias as the bootstrap sees it; the plain percentile
      // interval would repeat the bias.
      const auto reflect = [](double est, const std::vector<double>& v, double& lo, double& hi) {
        std::vector<double> lv;
        for (double x : v) lv.push_back(std::log(x));
        const double le = std::log(est);
        lo = std::exp(2.0 * le - percentile(lv, 0.975));
        hi = std::exp(2.0 * le - percentile(lv, 0.025));
      };
      reflect(t.value, values[k], t.value_lo, t.value_hi);
      if (t.kind == NoiseKind::kGaussMarkov) reflect(t.tau_s, taus[k], t.tau_lo_s, t.tau_hi_s);
    } else {
      t.value_lo = t.value_hi = t.tau_lo_s = t.tau_hi_s = std::nan("");
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
