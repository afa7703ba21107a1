#include "sim/chamber_sim.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

namespace calstand::sim {
namespace {

constexpr std::uint64_t kSeed = 42;

ChamberParams quiet_params() {
  ChamberParams p;
  p.control_noise_c = 0.0;  // compare with the noise-free model exactly
  return p;
}

void run_for(ChamberSim& chamber, double seconds, double dt = 1.0) {
  const auto steps = static_cast<long>(std::llround(seconds / dt));
  for (long i = 0; i < steps; ++i) chamber.step(dt);
}

TEST(ChamberSim, PowersUpInStandbyAtAmbient) {
  const ChamberParams p = quiet_params();
  ChamberSim chamber(p, kSeed);
  const auto s = chamber.state(1.5);
  EXPECT_DOUBLE_EQ(s.time_s, 1.5);
  EXPECT_EQ(s.mode, core::ChamberMode::kStandby);
  EXPECT_FALSE(s.fault);
  EXPECT_DOUBLE_EQ(s.air_temperature_c, p.ambient_c);
  EXPECT_DOUBLE_EQ(s.setpoint_c, p.ambient_c);
  EXPECT_DOUBLE_EQ(chamber.imu_temperature_c(), p.ambient_c);
}

TEST(ChamberSim, AirFollowsAFirstOrderLag) {
  ChamberParams p = quiet_params();
  p.max_ramp_c_per_min = 6000.0;  // ramp and rate limit never bind on a 10 degC step
  ChamberSim chamber(p, kSeed);
  const double step_c = 10.0;
  ASSERT_TRUE(chamber.set_setpoint(p.ambient_c + step_c));
  const double dt = 0.01;
  // The working setpoint takes 0.1 s to get there: shift the expected curve by half of that.
  run_for(chamber, p.air_time_constant_s, dt);
  const double covered = (chamber.air_temperature_c() - p.ambient_c) / step_c;
  EXPECT_NEAR(covered, 1.0 - std::exp(-(p.air_time_constant_s - 0.05) / p.air_time_constant_s),
              1e-3);
  EXPECT_NEAR(covered, 0.632, 0.005);
  run_for(chamber, p.air_time_constant_s, dt);
  EXPECT_NEAR((chamber.air_temperature_c() - p.ambient_c) / step_c, 0.865, 0.005);
}

TEST(ChamberSim, AirNeverChangesFasterThanTheRampLimit) {
  const ChamberParams p = quiet_params();
  ChamberSim chamber(p, kSeed);
  // Hot at the fastest ramp, then a drop to standby: an uncapped lag would fall at
  // (150 - 23) / 90 s = 85 degC/min.
  ASSERT_TRUE(chamber.set_setpoint(p.max_c, 100.0));  // capped at max_ramp_c_per_min
  double max_rate = 0.0;
  double max_standby_rate = 0.0;
  double previous = chamber.air_temperature_c();
  const std::vector<double> dts = {1.0, 0.25, 3.0, 0.5};
  double t = 0.0;
  for (int i = 0; t < 3600.0; ++i) {
    if (t >= 2400.0 && chamber.state(t).mode == core::ChamberMode::kActive) chamber.standby();
    const double dt = dts[i % dts.size()];
    chamber.step(dt);
    t += dt;
    const double rate = std::abs(chamber.air_temperature_c() - previous) / dt * 60.0;
    previous = chamber.air_temperature_c();
    max_rate = std::max(max_rate, rate);
    if (t > 2400.0) max_standby_rate = std::max(max_standby_rate, rate);
  }
  EXPECT_LE(max_rate, p.max_ramp_c_per_min * (1.0 + 1e-9));
  EXPECT_NEAR(max_standby_rate, p.max_ramp_c_per_min, 1e-6) << "the rate limit must bind";
}

TEST(ChamberSim, FollowsTheRequestedRamp) {
  const ChamberParams p = quiet_params();
  ChamberSim chamber(p, kSeed);
  ASSERT_TRUE(chamber.set_setpoint(60.0, 1.0));
  EXPECT_DOUBLE_EQ(chamber.state(0.0).setpoint_c, 60.0);
  run_for(chamber, 600.0);
  EXPECT_NEAR(chamber.working_setpoint_c(), p.ambient_c + 10.0, 1e-9);
  const double before = chamber.air_temperature_c();
  run_for(chamber, 60.0);
  EXPECT_NEAR(chamber.air_temperature_c() - before, 1.0, 0.01);
  // Lags the ramp by ramp * tau once the transient is gone.
  EXPECT_NEAR(chamber.working_setpoint_c() - chamber.air_temperature_c(),
              1.0 / 60.0 * p.air_time_constant_s, 0.01);

  // A ramp above the chamber's limit is capped, not refused.
  ASSERT_TRUE(chamber.set_setpoint(p.max_c, 50.0));
  const double ws = chamber.working_setpoint_c();
  run_for(chamber, 60.0);
  EXPECT_NEAR(chamber.working_setpoint_c() - ws, p.max_ramp_c_per_min, 1e-9);

  // And the target is reached and held.
  run_for(chamber, 3600.0);
  EXPECT_NEAR(chamber.air_temperature_c(), p.max_c, 1e-6);
}

TEST(ChamberSim, ImuLagsTheAirAndSettlesAboveIt) {
  ChamberParams p = quiet_params();
  p.max_ramp_c_per_min = 6000.0;
  p.air_time_constant_s = 1.0;  // the air is a near step for the IMU
  ChamberSim chamber(p, kSeed);
  const double setpoint = p.ambient_c + 10.0;
  ASSERT_TRUE(chamber.set_setpoint(setpoint));
  run_for(chamber, p.imu_time_constant_s, 0.1);
  // Two lags in cascade (tau 600 s and 1 s) from ambient to setpoint + self-heating.
  const double span = setpoint + p.imu_self_heating_c - p.ambient_c;
  const double tau = p.imu_time_constant_s;
  const double expected = 1.0 - (tau * std::exp(-1.0) - 1.0 * std::exp(-tau)) / (tau - 1.0);
  EXPECT_NEAR((chamber.imu_temperature_c() - p.ambient_c) / span, expected, 2e-3);
  // The reported rate is the lag's derivative.
  EXPECT_NEAR(chamber.imu_temperature_rate_c_per_min(),
              (setpoint + p.imu_self_heating_c - chamber.imu_temperature_c()) / tau * 60.0, 1e-6);
  EXPECT_GT(chamber.imu_temperature_rate_c_per_min(), 0.0);

  run_for(chamber, 12.0 * tau, 1.0);
  EXPECT_NEAR(chamber.imu_temperature_c(), setpoint + p.imu_self_heating_c, 1e-3);
  EXPECT_NEAR(chamber.imu_temperature_rate_c_per_min(), 0.0, 1e-4);
}

TEST(ChamberSim, ImuWarmsUpFromAmbientInStandby) {
  const ChamberParams p = quiet_params();
  ChamberSim chamber(p, kSeed);
  run_for(chamber, p.imu_time_constant_s);
  EXPECT_NEAR(chamber.imu_temperature_c() - p.ambient_c,
              p.imu_self_heating_c * (1.0 - std::exp(-1.0)), 1e-6);
  EXPECT_DOUBLE_EQ(chamber.air_temperature_c(), p.ambient_c);
}

TEST(ChamberSim, StandbyDriftsToAmbient) {
  const ChamberParams p;  // with the controller noise
  ChamberSim chamber(p, kSeed);
  ASSERT_TRUE(chamber.set_setpoint(40.0));
  run_for(chamber, 1800.0);
  ASSERT_NEAR(chamber.air_temperature_c(), 40.0, 0.1);
  chamber.standby();
  EXPECT_EQ(chamber.state(0.0).mode, core::ChamberMode::kStandby);
  run_for(chamber, 60.0);
  EXPECT_LT(chamber.air_temperature_c(), 40.0 - 3.0) << "drifting at the ramp limit";
  run_for(chamber, 1800.0);
  EXPECT_NEAR(chamber.air_temperature_c(), p.ambient_c, 5.0 * p.control_noise_c);
  // A new setpoint ramps from where the air is, not from the old working setpoint.
  EXPECT_NEAR(chamber.working_setpoint_c(), p.ambient_c, 1e-6);
}

TEST(ChamberSim, SetpointsOutsideTheLimitsAreRefused) {
  const ChamberParams p = quiet_params();
  ChamberSim chamber(p, kSeed);
  const Status too_hot = chamber.set_setpoint(151.0);
  EXPECT_FALSE(too_hot);
  EXPECT_NE(too_hot.message.find("151"), std::string::npos) << too_hot.message;
  EXPECT_NE(too_hot.message.find("150"), std::string::npos) << too_hot.message;
  const Status too_cold = chamber.set_setpoint(-60.5);
  EXPECT_FALSE(too_cold);
  EXPECT_NE(too_cold.message.find("-60"), std::string::npos) << too_cold.message;
  EXPECT_FALSE(chamber.set_setpoint(std::numeric_limits<double>::quiet_NaN()));
  EXPECT_FALSE(chamber.set_setpoint(std::numeric_limits<double>::infinity()));
  EXPECT_FALSE(chamber.set_setpoint(50.0, 0.0));
  EXPECT_FALSE(chamber.set_setpoint(50.0, -1.0));
  EXPECT_FALSE(chamber.set_setpoint(50.0, std::numeric_limits<double>::quiet_NaN()));
  EXPECT_EQ(chamber.state(0.0).mode, core::ChamberMode::kStandby);
  EXPECT_DOUBLE_EQ(chamber.state(0.0).setpoint_c, p.ambient_c);

  EXPECT_TRUE(chamber.set_setpoint(p.max_c));
  EXPECT_TRUE(chamber.set_setpoint(p.min_c, 0.5));
  EXPECT_EQ(chamber.state(0.0).mode, core::ChamberMode::kActive);
}

TEST(ChamberSim, FaultStopsControlAndRefusesSetpointsUntilCleared) {
  const ChamberParams p = quiet_params();
  ChamberSim chamber(p, kSeed);
  ASSERT_TRUE(chamber.set_setpoint(80.0));
  run_for(chamber, 1200.0);
  const double hot = chamber.air_temperature_c();
  ASSERT_GT(hot, 70.0);

  chamber.inject_fault("compressor alarm");
  auto s = chamber.state(0.0);
  EXPECT_EQ(s.mode, core::ChamberMode::kFault);
  EXPECT_TRUE(s.fault);
  EXPECT_EQ(s.fault_text, "compressor alarm");
  const Status refused = chamber.set_setpoint(50.0);
  EXPECT_FALSE(refused);
  EXPECT_NE(refused.message.find("compressor alarm"), std::string::npos) << refused.message;
  chamber.standby();
  EXPECT_EQ(chamber.state(0.0).mode, core::ChamberMode::kFault) << "standby must not clear";

  run_for(chamber, 600.0);
  EXPECT_LT(chamber.air_temperature_c(), hot - 20.0) << "controller off: drifts to ambient";
  run_for(chamber, 3600.0);
  EXPECT_NEAR(chamber.air_temperature_c(), p.ambient_c, 1e-6);

  chamber.clear_fault();
  s = chamber.state(0.0);
  EXPECT_EQ(s.mode, core::ChamberMode::kStandby);
  EXPECT_FALSE(s.fault);
  EXPECT_TRUE(s.fault_text.empty());
  EXPECT_TRUE(chamber.set_setpoint(50.0));
}

TEST(ChamberSim, NoiseIsDeterministicForASeed) {
  const ChamberParams p;
  ChamberSim a(p, 7);
  ChamberSim b(p, 7);
  ChamberSim c(p, 8);
  bool differs = false;
  for (int i = 0; i < 200; ++i) {
    a.step(0.5);
    b.step(0.5);
    c.step(0.5);
    ASSERT_EQ(a.air_temperature_c(), b.air_temperature_c());
    ASSERT_EQ(a.imu_temperature_c(), b.imu_temperature_c());
    differs |= a.air_temperature_c() != c.air_temperature_c();
  }
  EXPECT_TRUE(differs);
}

/// Sample standard deviation and lag-`lag` autocorrelation of the noise on a steady air.
void noise_stats(const std::vector<double>& dts, double& sigma, double& corr_at_tau, double tau_s) {
  const ChamberParams p;  // standby at ambient: the air itself stays at ambient exactly
  ChamberSim chamber(p, 11);
  std::vector<double> samples;
  std::vector<double> times;
  double t = 0.0;
  for (int i = 0; t < 40000.0; ++i) {
    chamber.step(dts[i % dts.size()]);
    t += dts[i % dts.size()];
    samples.push_back(chamber.air_temperature_c() - p.ambient_c);
    times.push_back(t);
  }
  double sum2 = 0.0;
  for (double x : samples) sum2 += x * x;
  sigma = std::sqrt(sum2 / static_cast<double>(samples.size()));
  // Correlation of samples one tau apart (pairs found by time, as dt varies).
  double cross = 0.0;
  double norm = 0.0;
  std::size_t j = 0;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    while (j < samples.size() && times[j] < times[i] + tau_s - 1e-9) ++j;
    if (j >= samples.size()) break;
    cross += samples[i] * samples[j];
    norm += samples[i] * samples[i];
  }
  corr_at_tau = cross / norm;
}

TEST(ChamberSim, NoiseHasItsSigmaAndCorrelationTimeWhateverTheStep) {
  const ChamberParams p;
  for (const std::vector<double>& dts :
       {std::vector<double>{1.0}, std::vector<double>{0.5, 2.0, 0.25}}) {
    double sigma = 0.0;
    double corr = 0.0;
    noise_stats(dts, sigma, corr, p.control_noise_tau_s);
    EXPECT_NEAR(sigma, p.control_noise_c, 0.1 * p.control_noise_c);
    EXPECT_NEAR(corr, std::exp(-1.0), 0.08);
  }
}

TEST(ChamberSim, NonPositiveStepsAreIgnored) {
  const ChamberParams p;
  ChamberSim chamber(p, kSeed);
  ASSERT_TRUE(chamber.set_setpoint(60.0));
  run_for(chamber, 100.0);
  const double air = chamber.air_temperature_c();
  const double imu = chamber.imu_temperature_c();
  chamber.step(0.0);
  chamber.step(-1.0);
  chamber.step(std::numeric_limits<double>::quiet_NaN());
  EXPECT_EQ(chamber.air_temperature_c(), air);
  EXPECT_EQ(chamber.imu_temperature_c(), imu);
}

}  // namespace
}  // namespace calstand::sim
