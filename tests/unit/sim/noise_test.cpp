#include "sim/noise.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <functional>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

// Each statistical check compares an estimate with theory within z = 4 standard errors of the
// estimate (plus any stated model error). The seeds are fixed, so the tests are deterministic;
// the tolerances say how far a correct implementation could stray for another seed (a 4-sigma
// excursion has probability ~6e-5 per check), while the wrong scaling, slope or correlation a
// bug would give lies many standard errors away.

namespace calstand::sim {
namespace {

constexpr double kZTolerance = 4.0;

// ---------------------------------------------------------------------------------------------
// Allan deviation helper (the production one will live in solver/).

/// Phase (integral) of a rate series sampled at dt: theta_0 = 0, theta_k = dt * sum_{i<k} y_i.
std::vector<double> integrate(const std::vector<double>& rate, double dt) {
  std::vector<double> theta(rate.size() + 1, 0.0);
  for (std::size_t k = 0; k < rate.size(); ++k) theta[k + 1] = theta[k] + rate[k] * dt;
  return theta;
}

/// Overlapping Allan deviation at averaging time m * dt from the phase series theta (IEEE Std
/// 952 / NIST SP 1065 eq. 14): avar = sum (theta_{k+2m} - 2 theta_{k+m} + theta_k)^2 /
/// (2 tau^2 (N - 2m)), N phase points.
double overlapping_adev(const std::vector<double>& theta, double dt, std::size_t m) {
  const std::size_t n = theta.size();
  const double tau = static_cast<double>(m) * dt;
  double sum = 0.0;
  for (std::size_t k = 0; k + 2 * m < n; ++k) {
    const double d = theta[k + 2 * m] - 2.0 * theta[k + m] + theta[k];
    sum += d * d;
  }
  return std::sqrt(sum / (2.0 * tau * tau * static_cast<double>(n - 2 * m)));
}

// Equivalent degrees of freedom of the overlapping Allan variance, the simple approximations of
// NIST SP 1065 (Riley 2008) table 12; n phase points, averaging factor m. The relative standard
// error of the Allan deviation is then 1 / sqrt(2 edf) (chi-square with edf degrees).
double edf_white_fm(double n, double m) {
  return (3.0 * (n - 1.0) / (2.0 * m) - 2.0 * (n - 2.0) / n) * 4.0 * m * m / (4.0 * m * m + 5.0);
}
double edf_flicker_fm(double n, double m) {
  return m == 1.0 ? 2.0 * (n - 2.0) / (2.3 * n - 4.9) : 5.0 * n * n / (4.0 * m * (n + 3.0 * m));
}
double edf_random_walk_fm(double n, double m) {
  return (n - 2.0) / (m * (n - 3.0) * (n - 3.0)) *
         ((n - 1.0) * (n - 1.0) - 3.0 * m * (n - 1.0) + 4.0 * m * m);
}
double adev_rel_error(double edf) { return 1.0 / std::sqrt(2.0 * edf); }

/// Least-squares slope of log(adev) against log(tau).
double log_log_slope(const std::vector<double>& taus, const std::vector<double>& adevs) {
  double sx = 0.0, sy = 0.0, sxx = 0.0, sxy = 0.0;
  const auto n = static_cast<double>(taus.size());
  for (std::size_t i = 0; i < taus.size(); ++i) {
    const double x = std::log(taus[i]);
    const double y = std::log(adevs[i]);
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

double variance_about_zero(const std::vector<double>& v) {
  double s = 0.0;
  for (const double x : v) s += x * x;
  return s / static_cast<double>(v.size());
}

double sample_std(const std::vector<double>& v) {
  double mean = 0.0;
  for (const double x : v) mean += x;
  mean /= static_cast<double>(v.size());
  double s = 0.0;
  for (const double x : v) s += (x - mean) * (x - mean);
  return std::sqrt(s / static_cast<double>(v.size() - 1));
}

double normal_cdf(double x) { return 0.5 * std::erfc(-x / std::numbers::sqrt2); }

// The message of the std::invalid_argument f throws, or "" when it throws none.
std::string invalid_argument_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

// ---------------------------------------------------------------------------------------------
// derive_seed and NormalSource

TEST(DeriveSeed, IsDeterministic) {
  EXPECT_EQ(derive_seed(42, "gyro.x.white", 3), derive_seed(42, "gyro.x.white", 3));
  EXPECT_EQ(derive_seed(0, "", 0), derive_seed(0, "", 0));
}

TEST(DeriveSeed, EveryInputChangesTheSeed) {
  const std::uint64_t base = derive_seed(42, "gyro.x.white", 3);
  EXPECT_NE(base, derive_seed(43, "gyro.x.white", 3));
  EXPECT_NE(base, derive_seed(42, "gyro.y.white", 3));
  EXPECT_NE(base, derive_seed(42, "gyro.x.white", 4));
  // Swapping the roles of seed and index must not collide.
  EXPECT_NE(derive_seed(3, "a", 5), derive_seed(5, "a", 3));
}

TEST(DeriveSeed, NeighbouringInputsGiveUnrelatedBits) {
  // For unrelated 64-bit values the Hamming distance is Binomial(64, 1/2): mean 32, sd 4. Over
  // 2000 neighbouring pairs the mean distance has sd 4/sqrt(2000) = 0.09, so +-0.5 is > 5 sd; a
  // weak mix (a plain sum or xor) gives distances of a few bits.
  double total = 0.0;
  int pairs = 0;
  for (std::uint64_t i = 0; i < 1000; ++i) {
    total += std::popcount(derive_seed(1, "imu", i) ^ derive_seed(1, "imu", i + 1));
    total += std::popcount(derive_seed(i, "imu", 0) ^ derive_seed(i + 1, "imu", 0));
    pairs += 2;
  }
  EXPECT_NEAR(total / pairs, 32.0, 0.5);
  // Names differing in one character.
  int distinct = 0;
  for (char c = 'a'; c <= 'z'; ++c) {
    const int d =
        std::popcount(derive_seed(7, std::string("accel.") + c, 0) ^ derive_seed(7, "accel.x", 0));
    if (c != 'x') {
      EXPECT_GE(d, 12) << c;  // 5 sd below 32
      ++distinct;
    }
  }
  EXPECT_EQ(distinct, 25);
}

TEST(DeriveSeed, StreamsFromDifferentNamesAreUncorrelated) {
  // Sample correlation of n independent pairs has sd 1/sqrt(n).
  constexpr int kN = 200'000;
  NormalSource a(derive_seed(1, "gyro.x"));
  NormalSource b(derive_seed(1, "gyro.y"));
  NormalSource c(derive_seed(1, "gyro.x", 1));
  double ab = 0.0, ac = 0.0;
  for (int i = 0; i < kN; ++i) {
    const double x = a.next();
    ab += x * b.next();
    ac += x * c.next();
  }
  EXPECT_LT(std::abs(ab / kN), kZTolerance / std::sqrt(kN));
  EXPECT_LT(std::abs(ac / kN), kZTolerance / std::sqrt(kN));
}

TEST(NormalSource, SameSeedSameSequence) {
  NormalSource a(5), b(5), c(6);
  bool any_different = false;
  for (int i = 0; i < 1000; ++i) {
    const double x = a.next();
    EXPECT_EQ(x, b.next());
    any_different = any_different || x != c.next();
  }
  EXPECT_TRUE(any_different);
}

TEST(NormalSource, MomentsAndDistributionAreStandardNormal) {
  // The ziggurat has a fast path, wedges and a tail beyond 3.654; a slip in any part shows up
  // in the CDF at the matching abscissa. The fraction below z has sd sqrt(p (1-p) / n).
  constexpr int kN = 2'000'000;
  NormalSource normal(derive_seed(11, "normal-test"));
  const std::vector<double> zs{
      -4.5, -3.6541528853610088, -3.0, -2.0, -1.0, -0.3, 0.0, 0.3, 1.0, 2.0, 3.0, 3.9, 4.5};
  std::vector<int> below(zs.size(), 0);
  double s1 = 0.0, s2 = 0.0, s4 = 0.0;
  for (int i = 0; i < kN; ++i) {
    const double x = normal.next();
    s1 += x;
    s2 += x * x;
    s4 += x * x * x * x;
    for (std::size_t j = 0; j < zs.size(); ++j) below[j] += x < zs[j] ? 1 : 0;
  }
  const double n = kN;
  EXPECT_NEAR(s1 / n, 0.0, kZTolerance / std::sqrt(n));
  EXPECT_NEAR(s2 / n, 1.0, kZTolerance * std::sqrt(2.0 / n));   // var(x^2) = 2
  EXPECT_NEAR(s4 / n, 3.0, kZTolerance * std::sqrt(96.0 / n));  // var(x^4) = 105 - 9 = 96
  for (std::size_t j = 0; j < zs.size(); ++j) {
    const double p = normal_cdf(zs[j]);
    EXPECT_NEAR(below[j] / n, p, kZTolerance * std::sqrt(p * (1.0 - p) / n) + 1.0 / n)
        << "z " << zs[j];
  }
}

// ---------------------------------------------------------------------------------------------
// White noise

TEST(WhiteNoise, SampleSigmaMatchesDensity) {
  // N = 0.01 unit/sqrt(Hz) at 100 Hz -> sigma 0.1 per sample. The sample sd of n draws has
  // relative sd 1/sqrt(2n) = 0.07 %.
  constexpr int kN = 1'000'000;
  WhiteNoise white(0.01, 100.0, derive_seed(1, "white"));
  EXPECT_DOUBLE_EQ(white.sigma(), 0.1);
  std::vector<double> y(kN);
  for (double& v : y) v = white.next();
  EXPECT_NEAR(sample_std(y), 0.1, 0.1 * kZTolerance / std::sqrt(2.0 * kN));
}

TEST(WhiteNoise, AllanDeviationIsDensityOverRootTau) {
  constexpr double kDensity = 0.01, kRate = 100.0, kDt = 1.0 / kRate;
  constexpr int kN = 1'000'000;
  WhiteNoise white(kDensity, kRate, derive_seed(2, "white"));
  std::vector<double> y(kN);
  for (double& v : y) v = white.next();
  const std::vector<double> theta = integrate(y, kDt);
  const auto n_phase = static_cast<double>(theta.size());
  std::vector<double> taus, adevs;
  for (const std::size_t m : {1UL, 10UL, 100UL, 1000UL}) {
    const double tau = static_cast<double>(m) * kDt;
    const double adev = overlapping_adev(theta, kDt, m);
    const double expected = kDensity / std::sqrt(tau);
    const double rel = adev_rel_error(edf_white_fm(n_phase, static_cast<double>(m)));
    EXPECT_NEAR(adev / expected, 1.0, kZTolerance * rel) << "tau " << tau;
    taus.push_back(tau);
    adevs.push_back(adev);
  }
  // The slope's error is dominated by the longest tau: ~rel(1000) / ln(1000) = 0.0026.
  EXPECT_NEAR(log_log_slope(taus, adevs), -0.5, 0.015);
}

// ---------------------------------------------------------------------------------------------
// Random walk

TEST(RandomWalk, VarianceGrowsAsKSquaredT) {
  // Across R realisations the variance (about the known zero mean) has relative sd
  // sqrt(2 / R) = 2.2 % for R = 4000.
  constexpr double kK = 0.5, kDt = 0.01;
  constexpr int kRealisations = 4000, kSteps = 1000;
  const std::vector<int> checkpoints{10, 100, 1000};
  std::vector<std::vector<double>> at(checkpoints.size(), std::vector<double>(kRealisations));
  for (int r = 0; r < kRealisations; ++r) {
    RandomWalk walk(kK, kDt, derive_seed(3, "walk", static_cast<std::uint64_t>(r)));
    EXPECT_EQ(walk.value(), 0.0);
    std::size_t c = 0;
    for (int k = 1; k <= kSteps; ++k) {
      walk.next();
      if (c < checkpoints.size() && k == checkpoints[c]) at[c++][r] = walk.value();
    }
  }
  for (std::size_t c = 0; c < checkpoints.size(); ++c) {
    const double t = checkpoints[c] * kDt;
    EXPECT_NEAR(variance_about_zero(at[c]) / (kK * kK * t), 1.0,
                kZTolerance * std::sqrt(2.0 / kRealisations))
        << "t " << t;
  }
}

TEST(RandomWalk, AllanDeviationIsKRootTauOverThree) {
  // The sampled walk's Allan variance is K^2 dt (2m^2 + 1) / (6m) = K^2 tau / 3 (1 + 1/(2m^2)),
  // so the continuous formula is exact to 5e-5 for m >= 100.
  constexpr double kK = 0.5, kDt = 0.01;
  constexpr int kN = 1'000'000;
  RandomWalk walk(kK, kDt, derive_seed(4, "walk"));
  std::vector<double> y(kN);
  for (double& v : y) v = walk.next();
  const std::vector<double> theta = integrate(y, kDt);
  const auto n_phase = static_cast<double>(theta.size());
  std::vector<double> taus, adevs, rels;
  for (const std::size_t m : {100UL, 1000UL, 10000UL}) {
    const double tau = static_cast<double>(m) * kDt;
    const double adev = overlapping_adev(theta, kDt, m);
    const double rel = adev_rel_error(edf_random_walk_fm(n_phase, static_cast<double>(m)));
    EXPECT_NEAR(adev / (kK * std::sqrt(tau / 3.0)), 1.0, kZTolerance * rel) << "tau " << tau;
    taus.push_back(tau);
    adevs.push_back(adev);
    rels.push_back(rel);
  }
  // Slope error ~ rel at the longest tau (7 %) over ln(100): 0.016 per sd.
  EXPECT_NEAR(log_log_slope(taus, adevs), 0.5, kZTolerance * rels.back() / std::log(100.0));
}

// ---------------------------------------------------------------------------------------------
// Gauss-Markov

TEST(GaussMarkov, CoefficientsAreTheExactDiscretisation) {
  GaussMarkov gm(2.0, 0.5, 0.01, 1);
  EXPECT_DOUBLE_EQ(gm.phi(), std::exp(-0.02));
  EXPECT_NEAR(gm.drive_sigma(), 2.0 * std::sqrt(1.0 - std::exp(-0.04)), 1e-15);
}

TEST(GaussMarkov, StationaryVarianceAndAutocorrelation) {
  constexpr double kSigma = 2.0, kTau = 0.5, kDt = 0.01;
  constexpr int kN = 1'000'000;
  GaussMarkov gm(kSigma, kTau, kDt, derive_seed(5, "gm"));
  std::vector<double> x(kN);
  for (double& v : x) v = gm.next();
  const double phi = std::exp(-kDt / kTau);
  double c0 = 0.0, c1 = 0.0, c50 = 0.0;
  for (int k = 0; k < kN; ++k) {
    c0 += x[k] * x[k];
    if (k >= 1) c1 += x[k] * x[k - 1];
    if (k >= 50) c50 += x[k] * x[k - 50];
  }
  // Variance of an AR(1) sample variance: (2 sigma^4 / n)(1 + phi^2)/(1 - phi^2), rel sd 1 %.
  const double var_rel = std::sqrt(2.0 * (1.0 + phi * phi) / (kN * (1.0 - phi * phi)));
  EXPECT_NEAR(c0 / kN / (kSigma * kSigma), 1.0, kZTolerance * var_rel);
  // Lag-1 sample autocorrelation of an AR(1): sd sqrt((1 - phi^2) / n) = 2e-4. Using dt twice
  // (phi = 0.961) or not at all would miss by ~100 sd.
  EXPECT_NEAR(c1 / c0, phi, kZTolerance * std::sqrt((1.0 - phi * phi) / kN));
  // Lag tau/dt = 50: exp(-1). Bartlett: var ~ ((1+phi^2)(1-phi^100)/(1-phi^2) - 100 phi^100)/n,
  // sd 0.0055.
  const double p100 = std::pow(phi, 100.0);
  const double sd50 =
      std::sqrt(((1.0 + phi * phi) * (1.0 - p100) / (1.0 - phi * phi) - 100.0 * p100) / kN);
  EXPECT_NEAR(c50 / c0, std::exp(-1.0), kZTolerance * sd50);
}

TEST(GaussMarkov, VarianceGrowsFromZeroOrStartsStationary) {
  // Relative sd of a variance about the known zero mean over R realisations: sqrt(2/R) = 2.2 %.
  constexpr double kSigma = 1.5, kTau = 1.0, kDt = 0.01;
  constexpr int kRealisations = 4000;
  const double tol = kZTolerance * std::sqrt(2.0 / kRealisations);
  const std::vector<int> checkpoints{10, 50, 100, 200};  // 0.1, 0.5, 1 and 2 tau
  std::vector<std::vector<double>> at(checkpoints.size(), std::vector<double>(kRealisations));
  std::vector<double> stationary_start(kRealisations), stationary_later(kRealisations);
  for (int r = 0; r < kRealisations; ++r) {
    const auto index = static_cast<std::uint64_t>(r);
    GaussMarkov gm(kSigma, kTau, kDt, derive_seed(6, "gm", index), false);
    EXPECT_EQ(gm.value(), 0.0);
    std::size_t c = 0;
    for (int k = 1; k <= checkpoints.back(); ++k) {
      gm.next();
      if (k == checkpoints[c]) at[c++][r] = gm.value();
    }
    GaussMarkov stationary(kSigma, kTau, kDt, derive_seed(6, "gm-stationary", index));
    stationary_start[r] = stationary.value();
    for (int k = 0; k < 10; ++k) stationary.next();
    stationary_later[r] = stationary.value();
  }
  for (std::size_t c = 0; c < checkpoints.size(); ++c) {
    const double t = checkpoints[c] * kDt;
    const double expected = kSigma * kSigma * (1.0 - std::exp(-2.0 * t / kTau));
    EXPECT_NEAR(variance_about_zero(at[c]) / expected, 1.0, tol) << "t " << t;
  }
  // Started stationary, the variance is sigma^2 from the first value on (a zero start would
  // give 0 and 0.18 sigma^2 here).
  EXPECT_NEAR(variance_about_zero(stationary_start) / (kSigma * kSigma), 1.0, tol);
  EXPECT_NEAR(variance_about_zero(stationary_later) / (kSigma * kSigma), 1.0, tol);
}

TEST(GaussMarkovAllanVariance, ClosedFormLimitsAndPeak) {
  constexpr double kSigma = 2.0, kTau = 10.0;
  const double var = kSigma * kSigma;
  // T << tau: 2 sigma^2 T / (3 tau) to leading order (next term -3x/4 relative).
  for (const double x : {1e-6, 1e-4, 3e-3}) {
    EXPECT_NEAR(gauss_markov_allan_variance(kSigma, kTau, x * kTau) / (2.0 * var * x / 3.0), 1.0, x)
        << x;
  }
  // Against the bracket's Taylor series summed to convergence (independent of the closed form
  // and of the truncated series the implementation switches to below x = 0.01), on both sides
  // of the switch: the two branches must agree to far better than any test needs.
  for (const double x : {1e-5, 1e-3, 0.0099, 0.0101, 0.1, 0.5, 1.0}) {
    double series = 0.0, term = 1.0;  // term = x^k / k!
    for (int k = 1; k < 60; ++k) {
      term *= x / k;
      if (k >= 3) series += ((k % 2 == 0) ? 1.0 : -1.0) * (2.0 - std::pow(2.0, k - 1)) * term;
    }
    const double expected = 2.0 * var / (x * x) * series;
    EXPECT_NEAR(gauss_markov_allan_variance(kSigma, kTau, x * kTau) / expected, 1.0, 1e-9) << x;
  }
  // T >> tau: 2 sigma^2 tau / T (1 - 3 tau / (2T)).
  EXPECT_NEAR(gauss_markov_allan_variance(kSigma, kTau, 1e4 * kTau) / (2.0 * var / 1e4), 1.0, 2e-4);
  // Peak near T = 1.89 tau at 0.3811 sigma^2 (the known maximum of the bracket).
  double best_t = 0.0, best = 0.0;
  for (double t = 0.5 * kTau; t < 5.0 * kTau; t += 0.001 * kTau) {
    const double a = gauss_markov_allan_variance(kSigma, kTau, t);
    if (a > best) best = a, best_t = t;
  }
  EXPECT_NEAR(best_t / kTau, 1.893, 0.005);
  EXPECT_NEAR(best / var, 0.3811, 0.0005);
}

TEST(GaussMarkovAllanVariance, MatchesSimulation) {
  // Sampled process against the continuous formula. Around the peak the process is neither
  // white nor random-walk FM, so the smaller of the two edf approximations is used: that
  // overstates the error, never understates it. m >= 50 keeps the sampling (point samples
  // instead of a continuous average) effect below 0.1 %.
  constexpr double kSigma = 1.0, kTau = 1.0, kDt = 0.01;
  constexpr int kN = 2'000'000;
  GaussMarkov gm(kSigma, kTau, kDt, derive_seed(7, "gm-allan"));
  std::vector<double> y(kN);
  for (double& v : y) v = gm.next();
  const std::vector<double> theta = integrate(y, kDt);
  const auto n_phase = static_cast<double>(theta.size());
  for (const std::size_t m : {50UL, 100UL, 189UL, 500UL, 2000UL, 10000UL}) {
    const double t = static_cast<double>(m) * kDt;
    const double md = static_cast<double>(m);
    const double edf = std::min(edf_white_fm(n_phase, md), edf_random_walk_fm(n_phase, md));
    const double expected = std::sqrt(gauss_markov_allan_variance(kSigma, kTau, t));
    EXPECT_NEAR(overlapping_adev(theta, kDt, m) / expected, 1.0,
                kZTolerance * adev_rel_error(edf) + 1e-3)
        << "T " << t;
  }
}

// ---------------------------------------------------------------------------------------------
// Bias instability

TEST(BiasInstability, FloorIsIeee952Coefficient) {
  BiasInstability bi(0.01, 0.01, 1, 0.1, 20.0);
  EXPECT_NEAR(bi.allan_floor(), 0.01 * std::sqrt(2.0 * std::log(2.0) / std::numbers::pi), 1e-15);
  EXPECT_NEAR(bi.allan_floor() / 0.01, 0.664, 0.0005);
}

TEST(BiasInstability, ModelIsFlatAcrossTheBand) {
  // Deterministic: the documented +-5 % model ripple over [2 tau_min, tau_max] for a short, the
  // default and a wide band; outside the band the flicker model must end (GM bank roll-off).
  for (const auto& [tmin, tmax] :
       {std::pair{0.1, 20.0}, std::pair{1.0, 3000.0}, std::pair{0.01, 1e4}, std::pair{1.0, 2.0}}) {
    BiasInstability bi(1.0, 0.001, 1, tmin, tmax);
    for (int j = 0; j <= 100; ++j) {
      const double t = 2.0 * tmin * std::pow(tmax / (2.0 * tmin), j / 100.0);
      EXPECT_NEAR(bi.model_allan_deviation(t) / bi.allan_floor(), 1.0, 0.05)
          << "band [" << tmin << ", " << tmax << "] T " << t;
    }
    EXPECT_LT(bi.model_allan_deviation(100.0 * tmax), 0.5 * bi.allan_floor());
    EXPECT_LT(bi.model_allan_deviation(0.01 * tmin), 0.5 * bi.allan_floor());
  }
}

TEST(BiasInstability, SimulatedAllanFloorIsFlat) {
  // Flicker-FM edf at the longest tau (m = 2000, n = 4e6): 2500, so 4 sd = 8 %; with the 5 %
  // model ripple a correct process stays within 13 % < 15 % of 0.664 B everywhere in the band.
  constexpr double kB = 0.01, kDt = 0.01;
  constexpr int kN = 4'000'000;
  BiasInstability bi(kB, kDt, derive_seed(8, "bias-instability"), 0.1, 20.0);
  std::vector<double> y(kN);
  for (double& v : y) v = bi.next();
  const std::vector<double> theta = integrate(y, kDt);
  const auto n_phase = static_cast<double>(theta.size());
  for (const std::size_t m : {20UL, 50UL, 100UL, 200UL, 500UL, 1000UL, 2000UL}) {
    const double t = static_cast<double>(m) * kDt;
    const double adev = overlapping_adev(theta, kDt, m);
    const double rel = adev_rel_error(edf_flicker_fm(n_phase, static_cast<double>(m)));
    EXPECT_NEAR(adev / bi.allan_floor(), 1.0, 0.15) << "T " << t;
    // The tighter check: against the model itself, within the statistical error.
    EXPECT_NEAR(adev / bi.model_allan_deviation(t), 1.0, kZTolerance * rel) << "T " << t;
  }
}

// ---------------------------------------------------------------------------------------------
// Quantizer

TEST(Quantizer, OutputsMultiplesOfLsbAndKeepsTheIntegral) {
  constexpr double kLsb = 0.01;
  Quantizer q(kLsb);
  NormalSource noise(derive_seed(9, "quantizer"));
  double sum_in = 0.0, sum_out = 0.0, max_gap = 0.0;
  for (int k = 0; k < 100'000; ++k) {
    // Slow sine plus noise of a few LSB: every rounding case occurs.
    const double x = 0.237 * std::sin(0.001 * k) + 0.03 * noise.next();
    const double y = q.apply(x);
    const double steps = y / kLsb;
    EXPECT_NEAR(steps, std::round(steps), 1e-9);
    sum_in += x;
    sum_out += y;
    max_gap = std::max(max_gap, std::abs(sum_out - sum_in));
  }
  // Residue carry: the running integrals differ by at most half an LSB (plus rounding of the
  // 1e5-term sums, ~1e-12); plain rounding would drift by ~sqrt(n) * lsb / sqrt(12) = 0.9.
  EXPECT_LE(max_gap, 0.5 * kLsb + 1e-9);
}

TEST(Quantizer, ConstantInputAveragesToItsValue) {
  // 0.0037 with a 0.01 LSB: the output is 0 or 0.01 but its mean over 1000 samples is exact to
  // lsb/1000 (the integral is exact to one LSB); without the carry it would be 0.
  Quantizer q(0.01);
  double sum = 0.0;
  for (int k = 0; k < 1000; ++k) sum += q.apply(0.0037);
  EXPECT_NEAR(sum / 1000.0, 0.0037, 0.01 / 1000.0);
}

TEST(Quantizer, NonPositiveLsbPassesThrough) {
  Quantizer zero(0.0), negative(-1.0);
  for (const double x : {0.123456789, -7.5, 1e-300}) {
    EXPECT_EQ(zero.apply(x), x);
    EXPECT_EQ(negative.apply(x), x);
  }
}

// ---------------------------------------------------------------------------------------------
// Butterworth low-pass

/// Amplitude of the steady-state response to a unit sine at f: RMS over whole periods after
/// the transient, times sqrt(2). fs/f times 300 must be a whole number of samples (it is for
/// every f used here), so the RMS of the sampled sine is exact.
double sine_gain(int order, double fc, double fs, double f) {
  ButterworthLowPass lp(order, fc, fs);
  const double w = 2.0 * std::numbers::pi * f / fs;
  // The slowest section (zeta = sin(pi/2n) >= 0.195) decays as exp(-zeta 2 pi fc t): after
  // 50/fc seconds the transient is below e^-61.
  const int settle = static_cast<int>(50.0 * fs / fc);
  const int measure = static_cast<int>(std::round(300.0 * fs / f));
  double sum = 0.0;
  for (int k = 0; k < settle + measure; ++k) {
    const double y = lp.filter(std::sin(w * k));
    if (k >= settle) sum += y * y;
  }
  return std::sqrt(2.0 * sum / measure);
}

/// |H(f)| of the pre-warped bilinear Butterworth.
double digital_butterworth_gain(int order, double fc, double fs, double f) {
  const double ratio = std::tan(std::numbers::pi * f / fs) / std::tan(std::numbers::pi * fc / fs);
  return 1.0 / std::sqrt(1.0 + std::pow(ratio, 2.0 * order));
}

TEST(ButterworthLowPass, DcGainIsOne) {
  for (const int order : {2, 4, 6, 8}) {
    ButterworthLowPass lp(order, 5.0, 1000.0);
    double y = 0.0;
    for (int k = 0; k < 20'000; ++k) y = lp.filter(1.0);
    EXPECT_NEAR(y, 1.0, 1e-9) << "order " << order;
  }
}

TEST(ButterworthLowPass, MinusThreeDecibelsAtCutoff) {
  // Whole periods, no transient left: the measurement is exact to rounding, so 1e-6 leaves
  // room only for that; an unwarped design would put -3 dB at 0.80 fc for fc = 300 Hz.
  for (const int order : {2, 4, 8}) {
    for (const double fc : {10.0, 100.0, 300.0}) {
      EXPECT_NEAR(sine_gain(order, fc, 1000.0, fc), 1.0 / std::numbers::sqrt2, 1e-6)
          << "order " << order << " fc " << fc;
      // And the shape, at an octave above (below the Nyquist frequency) or below.
      const double f = fc * 2.0 < 500.0 ? 2.0 * fc : 0.5 * fc;
      EXPECT_NEAR(sine_gain(order, fc, 1000.0, f), digital_butterworth_gain(order, fc, 1000.0, f),
                  1e-6)
          << "order " << order << " fc " << fc << " f " << f;
    }
  }
}

TEST(ButterworthLowPass, ResetStartsAtSteadyState) {
  ButterworthLowPass lp(4, 2.0, 100.0);
  lp.reset(3.0);
  for (int k = 0; k < 100; ++k) EXPECT_NEAR(lp.filter(3.0), 3.0, 1e-12);
}

TEST(ButterworthLowPass, NoiseEquivalentBandwidthFormula) {
  // Independent check of fc (pi/2n) / sin(pi/2n): integrate the analog |H|^2 =
  // 1 / (1 + (f/fc)^2n) numerically (substituting f = fc tan(u) maps [0, inf) to [0, pi/2)).
  for (const int order : {2, 4, 6, 8}) {
    const double fc = 3.0;
    ButterworthLowPass lp(order, fc, 1000.0);
    constexpr int kSteps = 200'000;
    double integral = 0.0;
    for (int i = 0; i < kSteps; ++i) {
      const double u = (i + 0.5) * (std::numbers::pi / 2.0) / kSteps;  // midpoint rule
      const double t = std::tan(u);
      integral += fc / (std::cos(u) * std::cos(u)) / (1.0 + std::pow(t, 2.0 * order));
    }
    integral *= (std::numbers::pi / 2.0) / kSteps;
    EXPECT_NEAR(lp.noise_equivalent_bandwidth_hz() / integral, 1.0, 1e-6) << "order " << order;
    // At fc/fs = 0.003 the bilinear warping is negligible (~(pi fc/fs)^2 = 1e-4), so the digital
    // power gain equals ENBW / (fs/2).
    EXPECT_NEAR(lp.white_noise_power_gain() * 500.0 / lp.noise_equivalent_bandwidth_hz(), 1.0, 5e-4)
        << "order " << order;
  }
}

TEST(ButterworthLowPass, PowerGainEqualsMeasuredVarianceRatio) {
  // White input of variance 1 through fc = 10 Hz at 1 kHz. The output's sample variance has
  // relative sd sqrt(2 sum rho_k^2 / n) = sqrt(2 * 0.75 / (n beta)) with beta = ENBW/(fs/2)
  // (sum rho^2 = integral |H|^4 / (integral |H|^2)^2 = (1 - 1/4)/beta for order 2): 0.58 %.
  constexpr int kN = 2'000'000;
  constexpr double kFs = 1000.0;
  ButterworthLowPass lp(2, 10.0, kFs);
  const double gain = lp.white_noise_power_gain();
  NormalSource normal(derive_seed(10, "butterworth"));
  double in_sq = 0.0, out_sq = 0.0;
  for (int k = 0; k < kN; ++k) {
    const double x = normal.next();
    const double y = lp.filter(x);
    in_sq += x * x;
    out_sq += y * y;
  }
  const double beta = lp.noise_equivalent_bandwidth_hz() / (0.5 * kFs);
  const double rel = std::sqrt(2.0 * 0.75 / (kN * beta)) + std::sqrt(2.0 / kN);
  EXPECT_NEAR(out_sq / in_sq / gain, 1.0, kZTolerance * rel);
  // Near Nyquist the bilinear zeros at fs/2 remove power: the digital gain at fc = fs/10 is below
  // the analog ENBW / (fs/2) (by 3.5 %), which is why the noise study's 100 Hz row reads low.
  ButterworthLowPass wide(2, 100.0, kFs);
  EXPECT_LT(wide.white_noise_power_gain(), 0.99 * wide.noise_equivalent_bandwidth_hz() / 500.0);
}

// ---------------------------------------------------------------------------------------------
// Argument validation

TEST(NoiseArguments, BadValuesThrowNamingTheArgument) {
  const double nan = std::nan("");
  struct Case {
    std::function<void()> make;
    const char* name;
  };
  const std::vector<Case> cases{
      {[] { WhiteNoise(-1.0, 100.0, 1); }, "density_per_sqrt_hz"},
      {[&] { WhiteNoise(nan, 100.0, 1); }, "density_per_sqrt_hz"},
      {[] { WhiteNoise(1.0, 0.0, 1); }, "sample_rate_hz"},
      {[] { RandomWalk(-0.1, 0.01, 1); }, "k_per_sqrt_s"},
      {[] { RandomWalk(0.1, -0.01, 1); }, "dt_s"},
      {[] { GaussMarkov(-1.0, 1.0, 0.01, 1); }, "sigma"},
      {[] { GaussMarkov(1.0, 0.0, 0.01, 1); }, "tau_s"},
      {[] { GaussMarkov(1.0, 1.0, 0.0, 1); }, "dt_s"},
      {[] { BiasInstability(-1.0, 0.01, 1); }, "coefficient"},
      {[] { BiasInstability(1.0, 0.0, 1); }, "dt_s"},
      {[] { BiasInstability(1.0, 0.01, 1, 0.005, 10.0); }, "tau_min_s"},
      {[] { BiasInstability(1.0, 0.01, 1, 1.0, 1.5); }, "tau_max_s"},
      {[&] { Quantizer{nan}; }, "lsb"},
      {[] { ButterworthLowPass(3, 10.0, 1000.0); }, "order"},
      {[] { ButterworthLowPass(10, 10.0, 1000.0); }, "order"},
      {[] { ButterworthLowPass(2, 500.0, 1000.0); }, "cutoff_hz"},
      {[] { ButterworthLowPass(2, 0.0, 1000.0); }, "cutoff_hz"},
      {[] { ButterworthLowPass(2, 10.0, -1.0); }, "sample_rate_hz"},
      {[] { gauss_markov_allan_variance(1.0, 1.0, 0.0); }, "averaging_time_s"},
  };
  for (const Case& c : cases) {
    const std::string message = invalid_argument_of(c.make);
    EXPECT_NE(message.find(c.name), std::string::npos) << "'" << message << "' lacks " << c.name;
    EXPECT_NE(message.find("got"), std::string::npos) << message;  // and the value
  }
  // Zero noise is allowed: a sensor model may switch a term off.
  EXPECT_NO_THROW(WhiteNoise(0.0, 100.0, 1));
  EXPECT_NO_THROW(BiasInstability(0.0, 0.01, 1));
}

}  // namespace
}  // namespace calstand::sim
