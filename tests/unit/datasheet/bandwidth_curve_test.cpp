// The figures of a gain and phase curve and their bootstrap intervals, on curves of known
// truth: an analogue second-order Butterworth low-pass at 10 Hz behind a 5 ms delay, read at the
// library procedure's frequencies, exact or with Gaussian errors of known sigma.
#include "bandwidth_curve.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <cstdint>
#include <iostream>
#include <numbers>
#include <random>
#include <vector>

namespace calstand::analysis::detail {
namespace {

constexpr double kCutoffHz = 10.0;
constexpr double kDelayS = 0.005;
const std::vector<double> kFrequenciesHz = {1, 2, 4, 6, 8, 10, 12, 15};

// H(s) = 1 / (s^2 + sqrt(2) s + 1) at s = i f / fc, times exp(-i w delay).
std::vector<CurvePoint> truth_curve(double gain_sigma, double phase_sigma_rad) {
  std::vector<CurvePoint> curve;
  for (const double f : kFrequenciesHz) {
    const std::complex<double> s(0.0, f / kCutoffHz);
    const std::complex<double> h = 1.0 / (s * s + std::numbers::sqrt2 * s + 1.0);
    CurvePoint p;
    p.frequency_hz = f;
    p.gain = std::abs(h);
    p.phase_rad = std::arg(h) - 2.0 * std::numbers::pi * f * kDelayS;
    p.gain_sigma = gain_sigma;
    p.phase_sigma_rad = phase_sigma_rad;
    p.sigma_dof = 9.0;
    curve.push_back(p);
  }
  return curve;
}

TEST(BandwidthCurve, AnExactCurveGivesItsCutoffOrderAndDelay) {
  const CurveFigures f = read_curve(truth_curve(0.0, 0.0));
  ASSERT_TRUE(f.bandwidth_hz && f.delay_s);
  EXPECT_NEAR(*f.bandwidth_hz, kCutoffHz, 1e-6);
  EXPECT_EQ(f.low_pass_order, 2);
  EXPECT_NEAR(*f.delay_s, kDelayS, 1e-9);
  // Without sigmas there is no interval to give.
  const CurveIntervals i = bootstrap_curve(truth_curve(0.0, 0.0), 0.95, 1000, 1);
  EXPECT_FALSE(i.bandwidth_hz);
  EXPECT_FALSE(i.delay_s);
}

// Two hundred curves, each point's gain and phase off by a normal draw of its stated sigma (as
// large as the simulator's points at 1 Hz): the 95 % intervals should hold the truth about 190
// times (binomial sd 3); the bootstrap's Student-t draws with 9 degrees of freedom make them a
// little wider than a known sigma needs, so 180 to 200. The sigma of the draws is the scatter
// of the estimates within 20 %.
TEST(BandwidthCurve, NinetyFivePercentIntervalsHoldTheTruthNinetyFivePercentOfTheTime) {
  constexpr int kTrials = 200;
  constexpr double kGainSigma = 0.0015, kPhaseSigmaRad = 0.002;
  std::mt19937_64 engine(20261202);
  std::normal_distribution<double> normal;
  int fc_held = 0, delay_held = 0;
  double fc_sum = 0.0, fc_sq = 0.0, fc_sigma_sq = 0.0;
  double delay_sum = 0.0, delay_sq = 0.0, delay_sigma_sq = 0.0;
  for (int trial = 0; trial < kTrials; ++trial) {
    std::vector<CurvePoint> curve = truth_curve(kGainSigma, kPhaseSigmaRad);
    for (CurvePoint& p : curve) {
      p.gain += kGainSigma * normal(engine);
      p.phase_rad += kPhaseSigmaRad * normal(engine);
    }
    const CurveFigures f = read_curve(curve);
    const CurveIntervals i = bootstrap_curve(curve, 0.95, 2000, static_cast<std::uint64_t>(trial));
    ASSERT_TRUE(f.bandwidth_hz && f.delay_s && i.bandwidth_hz && i.delay_s) << "trial " << trial;
    EXPECT_LE(i.bandwidth_hz->lo, *f.bandwidth_hz);
    EXPECT_GE(i.bandwidth_hz->hi, *f.bandwidth_hz);
    if (i.bandwidth_hz->lo <= kCutoffHz && kCutoffHz <= i.bandwidth_hz->hi) ++fc_held;
    if (i.delay_s->lo <= kDelayS && kDelayS <= i.delay_s->hi) ++delay_held;
    fc_sum += *f.bandwidth_hz, fc_sq += *f.bandwidth_hz * *f.bandwidth_hz;
    delay_sum += *f.delay_s, delay_sq += *f.delay_s * *f.delay_s;
    fc_sigma_sq += i.bandwidth_hz->sigma * i.bandwidth_hz->sigma;
    delay_sigma_sq += i.delay_s->sigma * i.delay_s->sigma;
  }
  const auto scatter = [&](double sum, double sq) {
    const double mean = sum / kTrials;
    return std::sqrt((sq - kTrials * mean * mean) / (kTrials - 1));
  };
  const double fc_ratio = std::sqrt(fc_sigma_sq / kTrials) / scatter(fc_sum, fc_sq);
  const double delay_ratio = std::sqrt(delay_sigma_sq / kTrials) / scatter(delay_sum, delay_sq);
  std::cout << "held of " << kTrials << ": bandwidth " << fc_held << ", delay " << delay_held
            << "; stated sigma / scatter: bandwidth " << fc_ratio << ", delay " << delay_ratio
            << "\n";
  EXPECT_GE(fc_held, 180);
  EXPECT_GE(delay_held, 180);
  EXPECT_NEAR(fc_ratio, 1.0, 0.2);
  EXPECT_NEAR(delay_ratio, 1.0, 0.2);
}

TEST(BandwidthCurve, ACrossingTheDrawsLoseGivesNoBandwidthInterval) {
  // The last point barely below -3 dB with a sigma that puts it above in a third of the draws:
  // the crossing leaves the frequencies tested too often for a 95 % upper end.
  std::vector<CurvePoint> curve = truth_curve(0.001, 0.001);
  curve.resize(6);  // up to 10 Hz, where the gain is -3.01 dB
  curve.back().gain_sigma = 0.05;
  const CurveIntervals i = bootstrap_curve(curve, 0.95, 2000, 3);
  EXPECT_FALSE(i.bandwidth_hz);
}

}  // namespace
}  // namespace calstand::analysis::detail
