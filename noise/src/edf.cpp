// Equivalent degrees of freedom of the Allan, modified Allan and Hadamard variances (Greenhall
// and Riley, PTTI 2003), and chi-square confidence intervals.
#include "noise/edf.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <boost/math/distributions/chi_squared.hpp>
#include <boost/math/quadrature/gauss_kronrod.hpp>
#include <cmath>

#include "core/error.hpp"

namespace calstand::solver {
namespace {

// t^p ln|t| with the limit 0 at t = 0.
double tlog(double t, int p) { return t == 0.0 ? 0.0 : std::pow(t, p) * std::log(std::abs(t)); }

// Generalised autocovariance of the integral of the phase for power-law noise of exponent
// alpha (S_y ~ f^alpha), up to a constant factor: the "sw" function of the paper.
double sw(double t, int alpha) {
  const double a = std::abs(t);
  switch (alpha) {
    case 2:
      return -a;
    case 1:
      return tlog(t, 2);
    case 0:
      return a * a * a;
    case -1:
      return -tlog(t, 4);
    case -2:
      return -std::pow(a, 5);
    case -3:
      return tlog(t, 6);
    default:
      return std::pow(a, 7);  // -4
  }
}

// Second and fourth derivatives of sw away from t = 0, for the Taylor form of sx below. At
// t = 0 the second derivative is its limit (0) for alpha <= 0; alpha 1 never asks there.
double sw2(double t, int alpha) {
  const double a = std::abs(t);
  if (a == 0.0) return 0.0;
  const double l = std::log(a);
  switch (alpha) {
    case 2:
      return 0.0;
    case 1:
      return 2.0 * l + 3.0;
    case 0:
      return 6.0 * a;
    case -1:
      return -(12.0 * l + 7.0) * t * t;
    case -2:
      return -20.0 * a * a * a;
    case -3:
      return (30.0 * l + 11.0) * std::pow(t, 4);
    default:
      return 42.0 * std::pow(a, 5);
  }
}
double sw4(double t, int alpha) {
  const double a = std::abs(t);
  const double l = std::log(a);
  switch (alpha) {
    case 2:
      return 0.0;
    case 1:
      return -2.0 / (t * t);
    case 0:
      return 0.0;
    case -1:
      return -(24.0 * l + 50.0);
    case -2:
      return -120.0 * a;
    case -3:
      return (360.0 * l + 342.0) * t * t;
    default:
      return 840.0 * a * a * a;
  }
}

// Generalised autocovariance of the phase averaged over windows of tau / F (t in units of
// tau): F^2 [2 sw(t) - sw(t - h) - sw(t + h)] with h = 1/F. F = 0 stands for infinity: point
// samples of the phase, which is what rate data give (x_k is the exact sum of the rates); it is
// -sw''. For large F the difference cancels catastrophically, so away from 0 it is replaced by
// its Taylor expansion -sw'' - h^2 sw^(4) / 12 (the next term, h^4 sw^(6) / 360, is under 1e-8
// relative at |t| > 100 h).
double sx(double t, double f, int alpha) {
  if (f == 0.0) return -sw2(t, alpha);
  const double h = 1.0 / f;
  if (std::abs(t) > 100.0 * h) return -sw2(t, alpha) - h * h / 12.0 * sw4(t, alpha);
  return f * f * (2.0 * sw(t, alpha) - sw(t - h, alpha) - sw(t + h, alpha));
}

// Weight (-1)^k C(2d, d + k): the autocorrelation of the d-th difference's binomial weights.
double binomial_weight(int d, int k) {
  const int a = std::abs(k);
  double c = 1.0;
  for (int i = 1; i <= d - a; ++i) c = c * (d + a + i) / i;
  return (a % 2 == 0) ? c : -c;
}

// Autocovariance at lag t (units of tau) of the estimator's d-th differences of the phase
// seen through sx.
double sz(double t, double f, int alpha, int d) {
  double sum = 0.0;
  for (int k = -d; k <= d; ++k) sum += binomial_weight(d, k) * sx(t + k, f, alpha);
  return sum;
}

// Up to this many lags the estimator's variance is summed term by term.
constexpr double kMaxDirectLags = 400.0;
// Up to this m the modified variance's kernel is built from the exact discrete average of m
// phase points; beyond, the continuous average (the paper's F = 1) is within a fraction of a
// per cent of it.
constexpr std::size_t kMaxDiscreteModified = 64;
// Bisections of the adaptive quadrature. The pieces are polynomials (exact at once) or carry an
// integrable log singularity at an end; 5 levels reach 1e-6 there. More only chases the
// relative error of pieces that are exactly zero.
constexpr unsigned kQuadratureDepth = 5;

// Autocovariance of the unmodified d-th phase difference (span m) of point samples at a lag of
// `lag` samples. White PM is discrete white phase noise: nonzero only at whole multiples of m.
// Flicker PM needs a bandwidth, taken as the sample rate (phase averaged over one sample,
// F = m), as Greenhall does.
double unmodified_kernel(double lag, std::size_t m, int alpha, int d) {
  const auto md = static_cast<double>(m);
  if (alpha == 2) {
    const double k = std::round(lag / md);
    if (std::abs(lag - k * md) > 1e-9 * md || std::abs(k) > d) return 0.0;
    return binomial_weight(d, static_cast<int>(k));
  }
  return sz(lag / md, alpha == 1 ? md : 0.0, alpha, d);
}

// 1/edf = (1/M) sum over |j| < J of (1 - |j|/M) rho(j)^2, j counting terms (stride samples
// apart), for a kernel of the lag in samples.
template <typename Kernel>
double inverse_edf_direct(const Kernel& kernel, double terms, double lags, double stride) {
  const double r0 = kernel(0.0);
  double sum = 1.0;
  for (double j = 1.0; j < lags; j += 1.0) {
    const double rho = kernel(j * stride) / r0;
    sum += 2.0 * (1.0 - j / terms) * rho * rho;
  }
  return sum / terms;
}

}  // namespace

int difference_order(AllanKind kind) {
  return kind == AllanKind::kHadamard || kind == AllanKind::kHadamardNonOverlapping ? 3 : 2;
}

int min_alpha(AllanKind kind) { return difference_order(kind) == 3 ? -4 : -2; }

double equivalent_dof(AllanKind kind, int alpha, std::size_t m, std::size_t samples) {
  if (alpha < min_alpha(kind) || alpha > kMaxAlpha) {
    throw core::InputError("alpha",
                           fmt::format("noise exponent {} is outside [{}, {}] where {} "
                                       "converges",
                                       alpha, min_alpha(kind), kMaxAlpha, to_string(kind)));
  }
  if (m == 0 || m > max_averaging_factor(kind, samples)) {
    throw core::InputError("m", fmt::format("averaging factor {} is outside [1, {}] for {} samples",
                                            m, max_averaging_factor(kind, samples), samples));
  }
  const int d = difference_order(kind);
  const bool modified = kind == AllanKind::kModified;
  const auto md = static_cast<double>(m);
  // Stride between terms, in samples: 1 for the overlapping estimators, m otherwise.
  const double stride = kind == AllanKind::kHadamardNonOverlapping ? md : 1.0;
  // Number of terms M (phase points N = samples + 1; filter length m (d + 1) for the modified
  // variance, m d + 1 otherwise) and J = min(M, support): lags beyond (d + 1) tau are ignored
  // (the kernel is zero there except for flicker noise, where the paper truncates too).
  const double n_phase = static_cast<double>(samples) + 1.0;
  const double length = modified ? md * (d + 1) : md * d + 1.0;
  const double terms = std::floor((n_phase - length) / stride) + 1.0;
  const double lags = std::min(terms, (d + 1) * md / stride);

  double inv_edf = 0.0;
  if (modified && m <= kMaxDiscreteModified) {
    // The modified difference is the sum of m consecutive unmodified ones: its kernel is the
    // unmodified kernel convolved with a triangle.
    const int mi = static_cast<int>(m);
    const auto kernel = [&](double lag) {
      double sum = 0.0;
      for (int u = 1 - mi; u < mi; ++u) {
        sum += (mi - std::abs(u)) * unmodified_kernel(lag + u, m, alpha, d);
      }
      return sum;
    };
    inv_edf = inverse_edf_direct(kernel, terms, lags, stride);
  } else if (!modified && alpha == 2) {
    // White PM's kernel lives on whole multiples of m only: sum just those lags.
    const double r0 = unmodified_kernel(0.0, m, alpha, d);
    double sum = 1.0;
    for (int k = 1; k <= d; ++k) {
      const double j = k * md / stride;  // lag in terms
      if (j >= lags) break;
      const double rho = unmodified_kernel(k * md, m, alpha, d) / r0;
      sum += 2.0 * (1.0 - j / terms) * rho * rho;
    }
    inv_edf = sum / terms;
  } else if (!modified && lags <= kMaxDirectLags) {
    inv_edf = inverse_edf_direct([&](double lag) { return unmodified_kernel(lag, m, alpha, d); },
                                 terms, lags, stride);
  } else {
    // Many lags, 1/m of tau apart (overlapping estimators only: the non-overlapping one has at
    // most d + 1): the sum is (m / M) times the integral over |t| < J/m, t in units of tau.
    const double f = modified ? 1.0 : (alpha == 1 ? md : 0.0);
    const double r = terms / md;
    const double upper = lags / md;
    const double s0 = sz(0.0, f, alpha, d);
    const auto integrand = [&](double t) {
      const double rho = sz(t, f, alpha, d) / s0;
      return (1.0 - t / r) * rho * rho;
    };
    double integral = 0.0;
    // Kinks and log singularities of the kernel sit at whole t: integrate piece by piece.
    for (double a = 0.0; a < upper; a += 1.0) {
      const double b = std::min(upper, a + 1.0);
      integral += boost::math::quadrature::gauss_kronrod<double, 31>::integrate(
          integrand, a, b, kQuadratureDepth, 1e-7);
    }
    inv_edf = 2.0 * integral / r;
  }
  return std::max(1.0, 1.0 / inv_edf);
}

DeviationInterval deviation_interval(double deviation, double edf, double confidence) {
  if (!(confidence > 0.0 && confidence < 1.0)) {
    throw core::InputError("confidence", fmt::format("must be in (0, 1), got {}", confidence));
  }
  if (!(edf > 0.0) || !std::isfinite(edf)) {
    throw core::InputError("edf", fmt::format("must be positive and finite, got {}", edf));
  }
  if (!(deviation >= 0.0)) {
    throw core::InputError("deviation", fmt::format("must be non-negative, got {}", deviation));
  }
  const boost::math::chi_squared_distribution<double> chi2(edf);
  const double var = deviation * deviation;
  const double upper_q = boost::math::quantile(chi2, 0.5 * (1.0 + confidence));
  const double lower_q = boost::math::quantile(chi2, 0.5 * (1.0 - confidence));
  return {std::sqrt(edf * var / upper_q), std::sqrt(edf * var / lower_q)};
}

}  // namespace calstand::solver
