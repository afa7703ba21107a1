// Welch PSD and FFT autocorrelation on white noise, a sine and a Gauss-Markov process.
#include "noise/psd.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "core/error.hpp"
#include "sim/noise.hpp"

namespace calstand::solver {
namespace {

TEST(Psd, WhiteNoiseIsTwoSigmaSquaredOverFs) {
  const double fs = 200.0;
  sim::WhiteNoise white(0.3, fs, 11);  // sigma = 0.3 sqrt(200) per sample
  std::vector<double> y(1 << 18);
  for (double& v : y) v = 5.0 + white.next();  // an offset: each segment's mean is removed
  WelchOptions o;
  o.segment_length = 1024;
  const Psd p = welch_psd(y, fs, o);
  ASSERT_EQ(p.frequency_hz.size(), 513u);
  EXPECT_DOUBLE_EQ(p.frequency_hz.back(), 100.0);
  EXPECT_EQ(p.segments, (y.size() - 1024) / 512 + 1);
  const double expected = 2.0 * white.sigma() * white.sigma() / fs;  // = 2 N^2
  // Mean over the band: 511 bins of ~2 x 511 segments each (Hann neighbours correlate, so
  // fewer independent ones); well within 2 %.
  double sum = 0.0;
  for (std::size_t k = 1; k + 1 < p.density.size(); ++k) sum += p.density[k];
  EXPECT_NEAR(sum / 511.0, expected, 0.02 * expected);
  // Each bin averages 511 segments: within 6 standard errors of ~1/sqrt(300).
  for (std::size_t k = 1; k + 1 < p.density.size(); ++k) {
    EXPECT_NEAR(p.density[k], expected, 0.35 * expected) << "f " << p.frequency_hz[k];
  }
  // The one-sided density integrates to the variance.
  double variance = 0.0;
  for (const double d : p.density) variance += d * p.resolution_hz;
  EXPECT_NEAR(variance, white.sigma() * white.sigma(), 0.03 * variance);
}

TEST(Psd, SineShowsAPeakAtItsFrequency) {
  const double fs = 100.0, f0 = 12.5, amplitude = 2.0;
  sim::WhiteNoise white(0.01, fs, 3);
  std::vector<double> y(1 << 16);
  for (std::size_t i = 0; i < y.size(); ++i) {
    y[i] = amplitude * std::sin(2.0 * std::numbers::pi * f0 * static_cast<double>(i) / fs) +
           white.next();
  }
  const Psd p = welch_psd(y, fs);
  std::size_t peak = 0;
  for (std::size_t k = 0; k < p.density.size(); ++k) {
    if (p.density[k] > p.density[peak]) peak = k;
  }
  EXPECT_NEAR(p.frequency_hz[peak], f0, p.resolution_hz);
  // The peak's power (summed over the window's main lobe) is the sine's variance A^2 / 2.
  double power = 0.0;
  for (std::size_t k = peak - 2; k <= peak + 2; ++k) power += p.density[k] * p.resolution_hz;
  EXPECT_NEAR(power, amplitude * amplitude / 2.0, 0.02 * amplitude * amplitude);
}

TEST(Psd, AutocorrelationOfGaussMarkovDecaysExponentially) {
  const double fs = 10.0, tau = 5.0;
  sim::GaussMarkov gm(1.0, tau, 1.0 / fs, 21);
  std::vector<double> y(400000);  // 8000 correlation times
  for (double& v : y) v = gm.next();
  const Autocorrelation a = autocorrelation(y, fs, 200);
  ASSERT_EQ(a.correlation.size(), 201u);
  EXPECT_DOUBLE_EQ(a.correlation[0], 1.0);
  EXPECT_NEAR(a.covariance[0], 1.0, 0.05);  // stationary variance sigma^2
  // The estimate at lag k of a process with 8000 correlation times scatters by about
  // sqrt(2 tau / T) ~ 0.016: within 0.05 of exp(-lag / tau) out to 4 tau.
  for (std::size_t k = 0; k <= 200; k += 10) {
    EXPECT_NEAR(a.correlation[k], std::exp(-a.lag_s[k] / tau), 0.05) << "lag " << a.lag_s[k];
  }
}

TEST(Psd, AutocorrelationMatchesDirectSum) {
  const std::vector<double> y = {1.0, 3.0, -2.0, 0.5, 4.0, -1.0, 2.0};
  const Autocorrelation a = autocorrelation(y, 2.0, 10);
  ASSERT_EQ(a.covariance.size(), 7u);  // clamped to n - 1
  double mean = 0.0;
  for (const double v : y) mean += v;
  mean /= 7.0;
  for (std::size_t k = 0; k < 7; ++k) {
    double c = 0.0;
    for (std::size_t i = 0; i + k < 7; ++i) c += (y[i] - mean) * (y[i + k] - mean);
    EXPECT_NEAR(a.covariance[k], c / 7.0, 1e-12);
    EXPECT_DOUBLE_EQ(a.lag_s[k], static_cast<double>(k) / 2.0);
  }
}

TEST(Psd, BadInput) {
  const std::vector<double> empty;
  EXPECT_THROW(welch_psd(empty, 1.0), core::InputError);
  EXPECT_THROW(autocorrelation(empty, 1.0, 3), core::InputError);
  const std::vector<double> y(100, 0.5);
  EXPECT_THROW(welch_psd(y, 0.0), core::InputError);
  EXPECT_THROW(autocorrelation(y, -1.0, 3), core::InputError);
  EXPECT_THROW(autocorrelation(y, 1.0, 3), core::InputError);  // constant
  WelchOptions o;
  o.segment_length = 256;  // longer than the data
  EXPECT_THROW(welch_psd(y, 1.0, o), core::InputError);
  o.segment_length = 0;
  o.overlap = 1.0;
  EXPECT_THROW(welch_psd(y, 1.0, o), core::InputError);
}

}  // namespace
}  // namespace calstand::solver
