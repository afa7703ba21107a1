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
// sin^4(pi f m) / (4 m^2 sin^4(pi f)), so that |H|^2 S = A(f) D(f) (haar_over_diff_s below).

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

// The quadrature nodes of one scale: the dense midpoint grid of the pairs it is the slower
// filter of (step 1 / (8 m), up to 16 * 32 of its periods or 1/2) and the logarithmic grid from
// 16 periods of m to 1/2, with D^2 and sin(pi f) at each node.
struct ScaleNodes {
  double m = 1.0;
  double step = 0.0;
  std::vector<double> f, d2, s;  // dense grid
  double log_from = 0.5, log_step = 0.0;
  std::vector<double> lf, ld2, ls;  // logarithmic grid
};

ScaleNodes scale_nodes(double m, const std::function<double(double)>& diff_psd) {
  ScaleNodes n;
  n.m = m;
  n.step = 1.0 / (kPointsPerPeriod * m);
  const double top = std::min(0.5, kExactPeriods * 32.0 / m);
  const auto count = static_cast<std::size_t>(std::lround(top / n.step));
  for (std::size_t i = 0; i < count; ++i) {
    const double f = (static_cast<double>(i) + 0.5) * n.step;
    const double d = diff_psd(f);
    n.f.push_back(f);
    n.d2.push_back(d * d);
    n.s.push_back(std::sin(kPiWc * f));
  }
  n.log_from = std::min(0.5, kExactPeriods / m);
  if (n.log_from < 0.5) {
    n.log_step = (std::log(0.5) - std::log(n.log_from)) / kLogPoints;
    for (int i = 0; i < kLogPoints; ++i) {
      const double f = std::exp(std::log(n.log_from) + (i + 0.5) * n.log_step);
      const double d = diff_psd(f);
      n.lf.push_back(f);
      n.ld2.push_back(d * d);
      n.ls.push_back(std::sin(kPiWc * f));
    }
  }
  return n;
}

// A_m(f) from sin(pi f) given.
double haar_over_diff_s(double f, double m, double sin_pi_f) {
  const double s = std::sin(kPiWc * f * m);
  const double r = s * s / (sin_pi_f * sin_pi_f);
  return r * r / (4.0 * m * m);
}

// int_0^{1/2} A_j A_k D^2 df for the scales nj (slower, m_j <= m_k) and nk.
double pair_integral(const ScaleNodes& nj, const ScaleNodes& nk) {
  const double mj = nj.m, mk = nk.m;
  const int a = static_cast<int>(std::lround(std::log2(mk / mj)));
  double sum = 0.0;
  // 1: both filters point by point on the faster one's grid, up to 16 periods of the slower.
  const double f1 = std::min(0.5, kExactPeriods / mj);
  if (a <= 5) {
    const auto count = std::min(nk.f.size(), static_cast<std::size_t>(std::lround(f1 / nk.step)));
    for (std::size_t i = 0; i < count; ++i) {
      const double f = nk.f[i];
      sum += haar_over_diff_s(f, mj, nk.s[i]) * haar_over_diff_s(f, mk, nk.s[i]) * nk.d2[i];
    }
    sum *= nk.step;
  } else {
    // The faster filter point by point up to 16 of its periods (the slower one is smooth
    // there), then its oscillation averaged (3/8 of its envelope) on the slower one's grid.
    const double f0 = kExactPeriods / mk;
    const auto c1 = std::min(nk.f.size(), static_cast<std::size_t>(std::lround(f0 / nk.step)));
    double s1 = 0.0;
    for (std::size_t i = 0; i < c1; ++i) {
      const double f = nk.f[i];
      s1 += haar_over_diff_s(f, mj, nk.s[i]) * haar_over_diff_s(f, mk, nk.s[i]) * nk.d2[i];
    }
    sum += s1 * nk.step;
    const auto c2 = std::min(nj.f.size(), static_cast<std::size_t>(std::lround(f1 / nj.step)));
    double s2 = 0.0;
    for (std::size_t i = 0; i < c2; ++i) {
      const double f = nj.f[i];
      if (f < f0) continue;
      const double sk = nj.s[i];
      const double env_k = 0.375 / (4.0 * mk * mk * sk * sk * sk * sk);
      s2 += haar_over_diff_s(f, mj, sk) * env_k * nj.d2[i];
    }
    sum += s2 * nj.step;
  }
  // 2: both averaged beyond 16 periods of the slower filter; the envelope D^2 / (16 mj^2 mk^2
  // sin^8) on the logarithmic grid.
  if (!nj.lf.empty()) {
    const double c = oscillation_mean(a);
    double s3 = 0.0;
    for (std::size_t i = 0; i < nj.lf.size(); ++i) {
      const double s2 = nj.ls[i] * nj.ls[i], s4 = s2 * s2;
      s3 += c * nj.ld2[i] / (16.0 * mj * mj * mk * mk * s4 * s4) * nj.lf[i];
    }
    sum += s3 * nj.log_step;
  }
  return sum;
}

}  // namespace

Eigen::MatrixXd wavelet_variance_covariance(const std::vector<std::size_t>& m, std::size_t samples,
                                            const std::function<double(double)>& diff_psd) {
  const auto J = static_cast<Eigen::Index>(m.size());
  Eigen::MatrixXd cov(J, J);
  const double n = static_cast<double>(samples);
  std::vector<ScaleNodes> nodes;
  for (std::size_t mm : m) nodes.push_back(scale_nodes(static_cast<double>(mm), diff_psd));
  for (Eigen::Index j = 0; j < J; ++j) {
    for (Eigen::Index k = j; k < J; ++k) {
      const double mj = static_cast<double>(m[static_cast<std::size_t>(j)]);
      const double mk = static_cast<double>(m[static_cast<std::size_t>(k)]);
      const double count =
          std::sqrt(std::max(1.0, n + 1.0 - 2.0 * mj) * std::max(1.0, n + 1.0 - 2.0 * mk));
      // Two-sided integral = twice the one over (0, 1/2].
      cov(j, k) = cov(k, j) =
          2.0 / count * 2.0 *
          pair_integral(nodes[static_cast<std::size_t>(j)], nodes[static_cast<std::size_t>(k)]);
    }
  }
  return cov;
}

}  // namespace calstand::solver
