#include "sim/imu_sim.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <vector>

#include "core/rotation.hpp"

namespace calstand::sim {
namespace {

core::Site test_site() {
  core::Site s;
  s.latitude_deg = 30.0;
  s.gravity_mps2 = 9.79;
  return s;
}

const Eigen::Vector2d kLevel = Eigen::Vector2d::Zero();

ImuTruth quiet_truth() {
  ImuTruth t;
  t.sample_rate_hz = 100.0;
  t.set_parameter("gyro_bias.x", 0.01);
  t.set_parameter("accel_scale.z", 500.0);
  return t;
}

TEST(ImuSim, NoiseFreeOutputIsInputPlusDeterministicErrors) {
  const ImuTruth truth = quiet_truth();
  ImuSim imu(truth, {}, test_site(), kLevel, 7);
  imu.power_on(0.0);
  TableKinematics k;
  k.outer_deg = 10.0;
  k.inner_rate_dps = 20.0;
  const auto s = imu.sample(1.0, k, 30.0);
  const ImuInputs in = imu_inputs(truth, {}, test_site(), kLevel, k, 30.0);
  const auto [eg, ea] = deterministic_errors(truth, in);
  EXPECT_NEAR((s.gyro_dps - (in.rate_dps + eg)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((s.accel_mps2 - (in.force_mps2 + ea)).norm(), 0.0, 1e-12);
  EXPECT_DOUBLE_EQ(s.temperature_c, 30.0);
}

TEST(ImuSim, SequenceCounterWrapsAtItsModulus) {
  ImuTruth truth = quiet_truth();
  truth.sequence_modulus = 4;
  ImuSim imu(truth, {}, test_site(), kLevel, 7);
  imu.power_on(0.0);
  std::vector<std::uint32_t> seq;
  for (int k = 0; k < 6; ++k) seq.push_back(imu.sample(k * 0.01, {}, 25.0).sequence);
  EXPECT_EQ(seq, (std::vector<std::uint32_t>{0, 1, 2, 3, 0, 1}));
}

TEST(ImuSim, DeviceClockDriftsAndReceiveTimeLags) {
  ImuTruth truth = quiet_truth();
  truth.clock_drift_ppm = 50.0;
  truth.latency_s = 0.004;
  ImuSim imu(truth, {}, test_site(), kLevel, 7);
  imu.power_on(100.0);
  const auto s = imu.sample(1100.0, {}, 25.0);
  EXPECT_NEAR(s.device_time_s, 1000.0 * (1.0 + 50e-6), 1e-9);  // device clock starts at power-on
  EXPECT_DOUBLE_EQ(s.receive_time_s, 1100.004);
}

TEST(ImuSim, TurnOnBiasIsConstantWithinAPowerUpAndNewAtEach) {
  ImuTruth truth = quiet_truth();
  truth.gyro_noise.turn_on_bias = Eigen::Vector3d(1e-3, 2e-3, 3e-3);  // deg/s
  ImuSim imu(truth, {}, test_site(), kLevel, 11);
  const int cycles = 2000;
  std::vector<double> z;
  for (int c = 0; c < cycles; ++c) {
    imu.power_on(0.0);
    const double a = imu.sample(0.0, {}, 25.0).gyro_dps.z();
    const double b = imu.sample(0.01, {}, 25.0).gyro_dps.z();
    ASSERT_DOUBLE_EQ(a, b);  // no other noise: constant within the power-up
    z.push_back(imu.turn_on_gyro_bias().z());
  }
  const double mean = std::accumulate(z.begin(), z.end(), 0.0) / cycles;
  double var = 0.0;
  for (double v : z) var += (v - mean) * (v - mean);
  const double sigma = std::sqrt(var / (cycles - 1));
  // Sample sigma of 2000 normal draws: relative standard error 1/sqrt(2*2000) = 1.6 %.
  EXPECT_NEAR(sigma, 3e-3, 3e-3 * 0.06);
  EXPECT_NEAR(mean, 0.0, 4.0 * 3e-3 / std::sqrt(cycles));
  EXPECT_EQ(imu.power_cycles(), cycles);
}

TEST(ImuSim, WhiteNoiseDensityGivesTheDatasheetArw) {
  ImuTruth truth;
  truth.sample_rate_hz = 200.0;
  truth.gyro_noise.white.setConstant(0.3 / 60.0);  // 0.3 deg/sqrt(h) in deg/s/sqrt(Hz)
  ImuSim imu(truth, {}, test_site(), kLevel, 3);
  imu.power_on(0.0);
  // Averages over 1 s have sigma N / sqrt(1 s) = 0.005 deg/s (the ARW definition).
  const int seconds = 2000;
  std::vector<double> means;
  const Eigen::Vector3d truth_rate = imu_inputs(truth, {}, test_site(), kLevel, {}, 25).rate_dps;
  for (int s = 0; s < seconds; ++s) {
    double sum = 0.0;
    for (int k = 0; k < 200; ++k) sum += imu.sample(s + k / 200.0, {}, 25.0).gyro_dps.x();
    means.push_back(sum / 200.0 - truth_rate.x());
  }
  double var = 0.0;
  for (double m : means) var += m * m;
  const double sigma = std::sqrt(var / seconds);
  EXPECT_NEAR(sigma, 0.005, 0.005 * 0.05);  // 2000 samples: 1.6 % standard error
}

TEST(ImuSim, QuantizedOutputIsOnTheLsbGrid) {
  ImuTruth truth;
  truth.gyro_noise.white.setConstant(0.01);
  truth.gyro_noise.quantization = 1e-3;
  ImuSim imu(truth, {}, test_site(), kLevel, 5);
  imu.power_on(0.0);
  for (int k = 0; k < 100; ++k) {
    const double v = imu.sample(k * 0.01, {}, 25.0).gyro_dps.y();
    EXPECT_NEAR(v / 1e-3, std::round(v / 1e-3), 1e-6);
  }
}

// Sum over all lags of the squared autocorrelation of a filter's output for white input:
// the mean square of n output samples then has relative variance 2 * this / n.
double squared_autocorrelation_sum(const ButterworthLowPass& prototype) {
  ButterworthLowPass lp = prototype;
  lp.reset(0.0);
  std::vector<double> h;
  for (int k = 0; k < 20000; ++k) h.push_back(lp.filter(k == 0 ? 1.0 : 0.0));
  double r0 = 0.0;
  for (const double v : h) r0 += v * v;
  double sum = 0.0;
  for (std::size_t lag = 0; lag < h.size(); ++lag) {
    double r = 0.0;
    for (std::size_t i = 0; i + lag < h.size(); ++i) r += h[i] * h[i + lag];
    if (lag > 0 && std::abs(r) < 1e-9 * r0) break;
    sum += (lag == 0 ? 1.0 : 2.0) * (r / r0) * (r / r0);
  }
  return sum;
}

TEST(ImuSim, EachSensorsOutputFilterHasItsOwnBandwidth) {
  ImuTruth truth;
  truth.sample_rate_hz = 1000.0;
  truth.gyro_bandwidth_hz = 50.0;
  truth.accel_bandwidth_hz = 20.0;
  truth.gyro_noise.white.setConstant(1e-3);   // deg/s/sqrt(Hz)
  truth.accel_noise.white.setConstant(2e-3);  // m/s^2/sqrt(Hz)
  ImuSim imu(truth, {}, test_site(), kLevel, 9);
  imu.power_on(0.0);
  const Eigen::Vector3d reference = imu_inputs(truth, {}, test_site(), kLevel, {}, 25.0).rate_dps;
  const int n = 200000;
  double gyro_sq = 0.0, accel_sq = 0.0;
  for (int k = 0; k < n; ++k) {
    const auto s = imu.sample(k * 1e-3, {}, 25.0);
    gyro_sq += std::pow(s.gyro_dps.x() - reference.x(), 2);
    accel_sq += std::pow(s.accel_mps2.x(), 2);  // body x is level: no gravity
  }
  // Filtered white noise of per-sample sigma N sqrt(fs) has variance sigma^2 * sum h_k^2.
  struct Case {
    const char* sensor;
    double mean_square, density, bandwidth_hz;
  };
  for (const Case& c :
       {Case{"gyro", gyro_sq / n, 1e-3, 50.0}, Case{"accel", accel_sq / n, 2e-3, 20.0}}) {
    const ButterworthLowPass lp(truth.filter_order, c.bandwidth_hz, truth.sample_rate_hz);
    const double want = c.density * c.density * truth.sample_rate_hz * lp.white_noise_power_gain();
    // Statistical tolerance: 4 standard errors of the mean square of n correlated samples, plus
    // the settling of the filter primed on the first (noisy) sample, at most ~1/ENBW seconds of
    // one sample's variance.
    const double sd = std::sqrt(2.0 * squared_autocorrelation_sum(lp) / n);
    const double priming = truth.sample_rate_hz / lp.noise_equivalent_bandwidth_hz() /
                           (n * lp.white_noise_power_gain());
    EXPECT_NEAR(c.mean_square / want, 1.0, 4.0 * sd + priming) << c.sensor;
  }
}

// Flicker noise has a flat Allan deviation at every averaging time, so with white noise the
// curve is sqrt(N^2 / tau + floor^2) and never dips below the floor. An ADIS16488-class
// accelerometer's white noise (0.029 m/s/sqrt(h)) meets its 0.1 mg floor at 0.24 s; the
// simulated flicker once started its band at 1 s, was flat only from 2 s, and the curve fell
// 10-20 % under that line between 0.5 and 2 s (a false minimum at 1 s, 142 ug as min / 0.664).
TEST(ImuSim, FlickerReachesBelowWhereItMeetsTheWhiteNoise) {
  ImuTruth truth;
  truth.sample_rate_hz = 100.0;
  const double white = 0.029 / 60.0;           // m/s^2/sqrt(Hz)
  const double floor = 1e-4 * 9.80665;         // m/s^2
  truth.accel_noise.white.setConstant(white);  //
  truth.accel_noise.bias_instability.setConstant(floor / kFlickerAllanFloorPerCoefficient);
  ImuSim imu(truth, {}, test_site(), kLevel, 5);
  imu.power_on(0.0);
  const int seconds = 4000;
  std::vector<double> x;
  x.reserve(static_cast<std::size_t>(seconds * 100));
  for (int k = 0; k < seconds * 100; ++k)
    x.push_back(imu.sample(k / 100.0, {}, 25.0).accel_mps2.x());
  for (const int m : {50, 100, 200}) {  // tau 0.5, 1, 2 s
    // Non-overlapping Allan variance: half the mean squared difference of adjacent averages.
    std::vector<double> means;
    for (std::size_t i = 0; i + static_cast<std::size_t>(m) <= x.size(); i += m) {
      means.push_back(std::accumulate(x.begin() + static_cast<std::ptrdiff_t>(i),
                                      x.begin() + static_cast<std::ptrdiff_t>(i) + m, 0.0) /
                      m);
    }
    double sum = 0.0;
    for (std::size_t i = 1; i < means.size(); ++i) sum += std::pow(means[i] - means[i - 1], 2);
    const double adev = std::sqrt(0.5 * sum / static_cast<double>(means.size() - 1));
    const double tau = m / 100.0;
    const double want = std::sqrt(white * white / tau + floor * floor);
    // 2000 or more differences: a standard error of at most 1.6 % on the deviation; 5 % is
    // three of them, and half the dip the band-limited flicker made.
    EXPECT_NEAR(adev / want, 1.0, 0.05) << "tau " << tau << " s";
  }
}

TEST(ImuSim, SameSeedSameSamplesOtherSeedOtherSamples) {
  ImuTruth truth;
  truth.gyro_noise.white.setConstant(1e-3);
  truth.accel_noise.gauss_markov_sigma.setConstant(1e-3);
  truth.gyro_noise.turn_on_bias.setConstant(1e-3);
  auto run = [&](std::uint64_t seed) {
    ImuSim imu(truth, {}, test_site(), kLevel, seed);
    imu.power_on(0.0);
    std::vector<double> v;
    for (int k = 0; k < 50; ++k) {
      const auto s = imu.sample(k * 0.01, {}, 25.0);
      v.push_back(s.gyro_dps.x());
      v.push_back(s.accel_mps2.z());
    }
    return v;
  };
  EXPECT_EQ(run(42), run(42));
  EXPECT_NE(run(42), run(43));
}

}  // namespace
}  // namespace calstand::sim
