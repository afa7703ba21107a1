// Switching a simulated IMU's supply (SimWorld::set_imu_power): the stream stops while off, and
// each cold start draws a new turn-on bias and runs the power-on transients.
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <vector>

#include "sim/sim_world.hpp"

namespace calstand::sim {
namespace {

// A unit with no noise and no error terms but a power-on bias transient, so that the transient
// is all that moves its gyro output at rest.
core::StationConfig transient_station(double tau_s) {
  core::StationConfig c = default_station();
  c.imus[0].model.clear();
  c.imus[0].truth = {{"format", "calstand-truth/1"},
                     {"output", {{"sample_rate_hz", 100}}},
                     {"power_on",
                      {{"gyro_bias_deg_per_h", {360.0, -180.0, 0.0}},
                       {"accel_bias_ug", {1000.0, 0.0, 0.0}},
                       {"time_constant_s", tau_s}}}};
  return c;
}

TEST(SimWorldPower, OffStopsTheStreamAndOnRestartsItFromSequenceZero) {
  SimWorld w(default_station());
  w.advance(1.0);
  ASSERT_FALSE(w.take_samples(0).empty());
  w.set_imu_power(0, false);
  EXPECT_FALSE(w.imu_powered(0));
  w.advance(5.0);
  EXPECT_TRUE(w.take_samples(0).empty()) << "an unpowered unit produced samples";
  w.set_imu_power(0, true);
  w.advance(1.0);
  const auto after = w.take_samples(0);
  const double rate = w.imu(0).truth().sample_rate_hz;
  ASSERT_NEAR(static_cast<double>(after.size()), rate, 1.0);
  EXPECT_EQ(after.front().sequence, 0u);
  EXPECT_LT(after.front().device_time_s, 2.0 / rate) << "the device clock restarts at power-up";
  // Switching to the state it is in is no power cycle.
  const double bias = w.imu(0).turn_on_gyro_bias().x();
  w.set_imu_power(0, true);
  EXPECT_EQ(w.imu(0).turn_on_gyro_bias().x(), bias);
}

// The LN200 sheet's bias repeatability (3 deg/h gyro, 500 ug accel, 1 sigma) is the spread of
// the turn-on bias over power cycles. 200 cycles x 3 axes: the sample sigma lies within the
// chi-square interval of the sheet's figure (normal approximation, z = 3.29: 99.9 %).
TEST(SimWorldPower, TurnOnBiasSpreadOverPowerCyclesMatchesTheSpecSheet) {
  SimWorld w(default_station());
  constexpr int kCycles = 200;
  std::vector<double> gyro;
  std::vector<double> accel;
  double previous = w.imu(0).turn_on_gyro_bias().x();
  int repeated = 0;
  for (int k = 0; k < kCycles; ++k) {
    w.set_imu_power(0, false);
    w.advance(0.05);
    w.set_imu_power(0, true);
    w.advance(0.05);
    const auto& g = w.imu(0).turn_on_gyro_bias();
    const auto& a = w.imu(0).turn_on_accel_bias();
    if (g.x() == previous) ++repeated;
    previous = g.x();
    for (int i = 0; i < 3; ++i) {
      gyro.push_back(g[i] * 3600.0);          // deg/h
      accel.push_back(a[i] / 9.80665 * 1e6);  // ug
    }
  }
  EXPECT_EQ(repeated, 0) << "a power-up kept the previous turn-on bias";
  const auto sigma = [](const std::vector<double>& v) {
    const double n = static_cast<double>(v.size());
    const double mean = std::accumulate(v.begin(), v.end(), 0.0) / n;
    double ss = 0.0;
    for (double x : v) ss += (x - mean) * (x - mean);
    return std::sqrt(ss / (n - 1.0));
  };
  const double n = static_cast<double>(gyro.size());
  const double half = 3.29 * std::sqrt(2.0 / (n - 1.0));
  const double lo = std::sqrt(1.0 - half);
  const double hi = std::sqrt(1.0 + half);
  EXPECT_GT(sigma(gyro), 3.0 * lo);
  EXPECT_LT(sigma(gyro), 3.0 * hi);
  EXPECT_GT(sigma(accel), 500.0 * lo);
  EXPECT_LT(sigma(accel), 500.0 * hi);
}

TEST(SimWorldPower, TurnOnBiasesAreSeededByTheStation) {
  const auto cycle = [](std::uint64_t seed) {
    core::StationConfig c = default_station();
    c.seed = seed;
    SimWorld w(c);
    w.set_imu_power(0, false);
    w.set_imu_power(0, true);
    return w.imu(0).turn_on_gyro_bias();
  };
  EXPECT_EQ(cycle(7), cycle(7));
  EXPECT_NE(cycle(7), cycle(8));
}

// Fits the decay of the bias transient: log(reading - settled) against time is a line of
// slope -1 / tau.
TEST(SimWorldPower, BiasTransientDecaysWithTheTruthsTimeConstant) {
  constexpr double kTau = 40.0;
  SimWorld w(transient_station(kTau));
  w.advance(1.0);
  w.take_samples(0);
  // The unit the world starts with is warm: no transient.
  EXPECT_EQ(w.imu(0).power_on_transient(w.now_s()).first.x(), 0.0);
  w.set_imu_power(0, false);
  w.advance(10.0);
  const double t_on = w.now_s();
  w.set_imu_power(0, true);
  w.advance(12.0 * kTau);
  const auto samples = w.take_samples(0);
  ASSERT_GT(samples.size(), 1000u);
  // Settled: the mean of the last 10 s, twelve time constants on.
  double settled = 0.0;
  int n_settled = 0;
  for (const auto& s : samples) {
    if (s.receive_time_s > w.now_s() - 10.0) {
      settled += s.gyro_dps.x();
      ++n_settled;
    }
  }
  settled /= n_settled;
  double st = 0, sy = 0, stt = 0, sty = 0, n = 0;
  double first = 0.0;
  for (const auto& s : samples) {
    const double t = s.receive_time_s - t_on;
    if (first == 0.0) first = s.gyro_dps.x() - settled;
    if (t > 3.0 * kTau) break;
    const double y = std::log(s.gyro_dps.x() - settled);
    st += t, sy += y, stt += t * t, sty += t * y, n += 1;
  }
  const double slope = (n * sty - st * sy) / (n * stt - st * st);
  EXPECT_NEAR(-1.0 / slope, kTau, 0.02 * kTau);
  EXPECT_NEAR(first, 360.0 / 3600.0, 0.01 * 360.0 / 3600.0) << "amplitude at power-up";
}

// After a power-up the unit's own temperature starts near the air's and climbs to the chamber
// model's self-heating with its time constant (default station: 3 degC, 600 s).
TEST(SimWorldPower, SelfHeatingSettlesAfterPowerUp) {
  core::StationConfig c = default_station();
  c.chamber.imu_time_constant_s = 100.0;
  SimWorld w(c);
  w.advance(1000.0);  // the chamber model's IMU starts at the air's temperature, then warms
  const double warm = w.imu_temperature_c(0);
  ASSERT_NEAR(warm, c.chamber.ambient_c + c.chamber.imu_self_heating_c, 0.1);
  w.set_imu_power(0, false);
  w.advance(1000.0);  // ten time constants off: cold
  EXPECT_NEAR(w.imu_temperature_c(0), warm - c.chamber.imu_self_heating_c, 0.01);
  w.set_imu_power(0, true);
  w.advance(100.0);  // one time constant on: 1 - 1/e of the self-heating is back
  const double deficit = warm - w.imu_temperature_c(0);
  EXPECT_NEAR(deficit, c.chamber.imu_self_heating_c * std::exp(-1.0), 0.02);
  const auto samples = w.take_samples(0);
  ASSERT_FALSE(samples.empty());
  EXPECT_NEAR(samples.back().temperature_c, w.imu_temperature_c(0), 0.01)
      << "the samples carry the unit's own temperature";
  w.advance(1000.0);
  // (The air itself wanders by the chamber's control noise, 0.02 degC.)
  EXPECT_NEAR(w.imu_temperature_c(0), warm, 0.06);
}

}  // namespace
}  // namespace calstand::sim
