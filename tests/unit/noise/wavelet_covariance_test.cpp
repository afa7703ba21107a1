// The covariance of the Haar wavelet variances across scales (the GMWM's efficient weights)
// against two peers: the variances of the overlapping Allan variance by Greenhall and Riley's
// EDF (noise/edf, an exact finite-sample double sum, SP 1065 Table 5's source) on the diagonal,
// and a Monte Carlo of simulated records for the correlation of neighbouring scales.
#include "noise/wavelet_covariance.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "noise/edf.hpp"
#include "noise/wavelet_moments.hpp"

namespace calstand::solver {
namespace {

constexpr double kPiTest = 3.14159265358979323846;

// D(f) of unit white noise (variance 1 per sample) and of a random walk of unit increments.
double white_diff(double f) {
  const double s = std::sin(kPiTest * f);
  return 4.0 * s * s;
}
double walk_diff(double) { return 1.0; }

struct DiagonalCase {
  const char* name;
  double (*diff_psd)(double);
  int alpha;  // S_y ~ f^alpha: 0 white FM (white rate), -2 random-walk FM (random-walk rate)
  // nu^2 at half-scale m of the unit process
  double (*nu2)(double m);
  // The EDF's random-walk FM is the continuous-time power law; the discrete random walk of the
  // rate samples differs from it by 11 % and 10 % in this variance at m = 1 and 2, 3 % at 4.
  std::size_t first_m;
};

void PrintTo(const DiagonalCase& c, std::ostream* os) { *os << c.name; }

class WaveletCovarianceDiagonal : public ::testing::TestWithParam<DiagonalCase> {};

// Var(nu_hat) = 2 nu^4 / edf with the Allan variance's EDF: the large-sample integral agrees with
// the finite-sample sum where the record holds many filter lengths (m up to N / 64); at the
// longest scales it is larger (it leaves out the end effects), which is the safe side for weights.
TEST_P(WaveletCovarianceDiagonal, VarianceMatchesAllanEdf) {
  const DiagonalCase& c = GetParam();
  const std::size_t n = 1 << 14;
  std::vector<std::size_t> m;
  for (std::size_t k = 1; k <= n / 4; k *= 2) m.push_back(k);
  const Eigen::MatrixXd cov = wavelet_variance_covariance(m, n, c.diff_psd);
  for (std::size_t j = 0; j < m.size(); ++j) {
    const double nu2 = c.nu2(static_cast<double>(m[j]));
    const double edf = equivalent_dof(AllanKind::kAllan, c.alpha, m[j], n);
    const double peer = 2.0 * nu2 * nu2 / edf;
    const double ratio = cov(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(j)) / peer;
    if (m[j] < c.first_m) continue;
    if (m[j] <= n / 64) {
      EXPECT_NEAR(ratio, 1.0, 0.05) << "m = " << m[j];
    } else {
      EXPECT_GT(ratio, 0.95) << "m = " << m[j];
      EXPECT_LT(ratio, 1.5) << "m = " << m[j];
    }
  }
}

INSTANTIATE_TEST_SUITE_P(
    Noises, WaveletCovarianceDiagonal,
    ::testing::Values(DiagonalCase{"white", &white_diff, 0, [](double m) { return 0.5 / m; }, 1},
                      DiagonalCase{"random_walk", &walk_diff, -2,
                                   [](double m) { return (2.0 * m * m + 1.0) / (12.0 * m); }, 8}),
    [](const ::testing::TestParamInfo<DiagonalCase>& i) { return std::string(i.param.name); });

// The correlation between neighbouring scales of white + random walk against 400 simulated
// records: within four Monte Carlo standard errors (about 0.05 each).
TEST(WaveletCovariance, NeighbourCorrelationMatchesMonteCarlo) {
  const std::size_t n = 1 << 12;
  const double walk = 0.02;  // increment sigma per sample against unit white noise
  std::vector<std::size_t> m;
  for (std::size_t k = 1; k <= n / 4; k *= 2) m.push_back(k);
  const Eigen::MatrixXd cov =
      wavelet_variance_covariance(m, n, [&](double f) { return white_diff(f) + walk * walk; });
  const int records = 400;
  std::mt19937_64 rng(11);
  std::normal_distribution<double> g(0.0, 1.0);
  const auto J = static_cast<Eigen::Index>(m.size());
  Eigen::MatrixXd samples(records, J);
  for (int r = 0; r < records; ++r) {
    std::vector<double> y(n);
    double x = 0.0;
    for (double& v : y) {
      x += walk * g(rng);
      v = x + g(rng);
    }
    const WaveletMoments w = wavelet_moments(y, 1.0);
    for (Eigen::Index j = 0; j < J; ++j) samples(r, j) = w.variance[static_cast<std::size_t>(j)];
  }
  const Eigen::RowVectorXd mean = samples.colwise().mean();
  const Eigen::MatrixXd centred = samples.rowwise() - mean;
  const Eigen::MatrixXd mc = centred.transpose() * centred / (records - 1);
  int compared = 0;
  for (Eigen::Index j = 0; j + 1 < J - 3; ++j) {  // the last scales: too few dof for 400 records
    const double rho = cov(j, j + 1) / std::sqrt(cov(j, j) * cov(j + 1, j + 1));
    const double rho_mc = mc(j, j + 1) / std::sqrt(mc(j, j) * mc(j + 1, j + 1));
    EXPECT_NEAR(rho, rho_mc, 4.0 * (1.0 - rho_mc * rho_mc) / std::sqrt(records)) << "m = " << m[j];
    ++compared;
  }
  EXPECT_GE(compared, 5);
  // The walk's long scales are more strongly correlated than the white short ones: the weights
  // differ from diagonal ones most where the random walk is identified.
  const auto rho = [&](Eigen::Index j) {
    return cov(j, j + 1) / std::sqrt(cov(j, j) * cov(j + 1, j + 1));
  };
  EXPECT_GT(rho(J - 2), rho(0) + 0.1);
}

}  // namespace
}  // namespace calstand::solver
