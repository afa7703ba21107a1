// The covariance of Haar wavelet variances across scales from a spectrum (the GMWM's efficient
// weighting), by quadrature in frequency.
#include "noise/wavelet_covariance.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace calstand::solver {
namespace {

constexpr double kPiWc = 3.14159265358979323846;
// Periods of the slower filter's oscillation integrated point by point before its mean is
// used, and quadrature points per period of the faster one.
constexpr double kExactPeriods = 16.0;
constexpr double kPointsPerPeriod = 8.0;
constexpr int kLogPoints = 256;

// The Haar filter's squared gain over the difference's: |H(f)|^2 / (4 sin^2(pi f)) =
// sin^4(pi f m) / (4 m^2 sin^4(pi f)), so that |H|^2 S = A(f) D(f).
double haar_over_diff(double f, double m) {
  const double s = std::sin(kPiWc * f * m);
  const double d = std::sin(kPiWc * f);
  const double r = s * s / (d * d);
  return r * r / (4.0 * m * m);
}

// The mean of sin^4(x) sin^4(2^a x) over a period: the product of two filters' oscillations
// when both are averaged out (a = log2 of the ratio of their half-scales). Beyond a = 5 the
// two are independent to 1e-3: (3/8)^2.
double oscillation_mean(int a) {
  static const std::array<double, 6> table = [] {
    std::array<double, 6> t{};
    const int n = 1 << 14;
    for (int k = 0; k < 6; ++k) {
      double sum = 0.0;
      for (int i = 0; i < n; ++i) {
        const double x = kPiWc * (i + 0.5) / n;
        const double s = std::sin(x), t2 = std::sin(std::ldexp(x, k));
        sum += s * s * s * s * t2 * t2 * t2 * t2;
      }
      t[static_cast<std::size_t>(k)] = sum / n;
    }
    return t;
  }();
  return a < 6 ? table[static_cast<std::size_t>(a)] : 9.0 / 64.0;
}

// int_0^{1/2} A_j A_k D^2 df for half-scales mj <= mk.
double pair_integral(double mj, double mk, const std::function<double(double)>& diff_psd) {
  const int a = static_cast<int>(std::lround(std::log2(mk / mj)));
  double sum = 0.0;
  // 1: both filters point by point, up to 16 periods of the slower one (or of the faster one
  // 2^5 times that, when the two are far apart).
  const double f1 = std::min(0.5, kExactPeriods * std::ldexp(1.0, std::min(a, 5)) / mk);
  {
    const double h0 = 1.0 / (kPointsPerPeriod * mk);
    const auto n = static_cast<std::size_t>(std::ceil(f1 / h0));
    const double h = f1 / static_cast<double>(n);
    for (std::size_t i = 0; i < n; ++i) {
      const double f = (static_cast<double>(i) + 0.5) * h;
      const double d = diff_psd(f);
      sum += haar_over_diff(f, mj) * haar_over_diff(f, mk) * d * d * h;
    }
  }
  // 2: the faster filter averaged (3/8 of its envelope), the slower one point by point.
  double f2 = f1;
  if (a > 5 && f1 < 0.5) {
    f2 = std::min(0.5, kExactPeriods / mj);
    const double h0 = 1.0 / (kPointsPerPeriod * mj);
    const auto n = static_cast<std::size_t>(std::ceil((f2 - f1) / h0));
    if (n > 0) {
      const double h = (f2 - f1) / static_cast<double>(n);
      for (std::size_t i = 0; i < n; ++i) {
        const double f = f1 + (static_cast<double>(i) + 0.5) * h;
        const double d = diff_psd(f);
        const double sk = std::sin(kPiWc * f);
        const double env_k = 0.375 / (4.0 * mk * mk * sk * sk * sk * sk);
        sum += haar_over_diff(f, mj) * env_k * d * d * h;
      }
    }
  }
  // 3: both averaged; the envelope D^2 / (16 mj^2 mk^2 sin^8) on a logarithmic grid.
  if (f2 < 0.5) {
    const double c = oscillation_mean(a);
    const double l0 = std::log(f2), l1 = std::log(0.5);
    const double h = (l1 - l0) / kLogPoints;
    for (int i = 0; i < kLogPoints; ++i) {
      const double f = std::exp(l0 + (i + 0.5) * h);
      const double d = diff_psd(f);
      const double s = std::sin(kPiWc * f);
      const double s2 = s * s, s4 = s2 * s2;
      sum += c * d * d / (16.0 * mj * mj * mk * mk * s4 * s4) * f * h;
    }
  }
  return sum;
}

}  // namespace

Eigen::MatrixXd wavelet_variance_covariance(const std::vector<std::size_t>& m, std::size_t samples,
                                            const std::function<double(double)>& diff_psd) {
  const auto J = static_cast<Eigen::Index>(m.size());
  Eigen::MatrixXd cov(J, J);
  const double n = static_cast<double>(samples);
  for (Eigen::Index j = 0; j < J; ++j) {
    for (Eigen::Index k = j; k < J; ++k) {
      const double mj = static_cast<double>(m[static_cast<std::size_t>(j)]);
      const double mk = static_cast<double>(m[static_cast<std::size_t>(k)]);
      const double count = std::sqrt(std::max(1.0, n + 1.0 - 2.0 * mj) *
                                      std::max(1.0, n + 1.0 - 2.0 * mk));
      // Two-sided integral = twice the one over (0, 1/2].
      cov(j, k) = cov(k, j) = 2.0 / count * 2.0 * pair_integral(mj, mk, diff_psd);
    }
  }
  return cov;
}

}  // namespace calstand::solver
