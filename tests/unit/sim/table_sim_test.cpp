#include "sim/table_sim.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "sim/noise.hpp"

namespace calstand::sim {
namespace {

constexpr double kDt = 1e-3;  // [s]

double wrap_180(double a) {
  double w = std::fmod(a + 180.0, 360.0);
  if (w < 0.0) w += 360.0;
  return w - 180.0;
}

/// Steps until in_position or `max_s` has passed; returns the time taken [s].
double run_until_settled(TableAxisSim& axis, double max_s, double dt = kDt) {
  double t = 0.0;
  while (!axis.state().in_position && t < max_s) {
    axis.step(dt);
    t += dt;
  }
  return t;
}

void run_axis_for(TableAxisSim& axis, double seconds, double dt = kDt) {
  const auto steps = static_cast<long>(std::llround(seconds / dt));
  for (long i = 0; i < steps; ++i) axis.step(dt);
}

TEST(TableAxisSim, PowersUpAtRestInPosition) {
  TableAxisSim axis;
  const auto s = axis.state();
  EXPECT_EQ(s.mode, core::AxisMode::kRest);
  EXPECT_TRUE(s.in_position);
  EXPECT_FALSE(s.fault);
  EXPECT_DOUBLE_EQ(s.angle_deg, 0.0);
  EXPECT_DOUBLE_EQ(s.rate_dps, 0.0);
}

TEST(TableAxisSim, PositionMoveLandsAndSettlesOnlyAfterSettleTime) {
  AxisLimits limits;
  TableAxisSim axis(limits);
  ASSERT_TRUE(axis.command_position(90.0));
  EXPECT_FALSE(axis.state().in_position) << "a new command must clear in_position";
  EXPECT_EQ(axis.state().mode, core::AxisMode::kPosition);

  double t = 0.0;
  double within_since = -1.0;  // start of the current stretch inside the tolerance
  while (!axis.state().in_position && t < 10.0) {
    axis.step(kDt);
    t += kDt;
    const bool within = std::abs(axis.true_angle_deg() - 90.0) < limits.position_tolerance_deg;
    if (!within) within_since = -1.0;
    if (within && within_since < 0.0) within_since = t - kDt;
  }
  ASSERT_TRUE(axis.state().in_position) << "never settled";
  ASSERT_GE(within_since, 0.0);
  // Settled exactly once the error has stayed in tolerance for settle_time_s, not earlier.
  EXPECT_NEAR(t - within_since, limits.settle_time_s, 1.5 * kDt);
  EXPECT_NEAR(axis.true_angle_deg(), 90.0, limits.position_tolerance_deg);
  EXPECT_NEAR(axis.state().angle_deg, 90.0, limits.position_tolerance_deg);

  // Holding: the error keeps shrinking and in_position stays.
  run_axis_for(axis, 1.0);
  EXPECT_TRUE(axis.state().in_position);
  EXPECT_NEAR(axis.true_angle_deg(), 90.0, 1e-9);
  EXPECT_NEAR(axis.true_rate_dps(), 0.0, 1e-9);
}

TEST(TableAxisSim, PositionMoveFromRestNeverOvershoots) {
  TableAxisSim axis;
  const double target = 123.4;
  ASSERT_TRUE(axis.command_position(target));
  double previous = axis.true_angle_deg();
  for (int i = 0; i < 5000; ++i) {
    axis.step(kDt);
    ASSERT_LE(axis.true_angle_deg(), target + 1e-9) << "overshoot at step " << i;
    ASSERT_GE(axis.true_angle_deg(), previous - 1e-12) << "moved backwards at step " << i;
    previous = axis.true_angle_deg();
  }
  EXPECT_NEAR(axis.true_angle_deg(), target, 1e-9);
}

TEST(TableAxisSim, TakesTheShortestWayRound) {
  TableAxisSim axis;
  ASSERT_TRUE(axis.command_position(170.0));
  run_until_settled(axis, 10.0);
  ASSERT_TRUE(axis.state().in_position);

  ASSERT_TRUE(axis.command_position(-170.0));
  const double start = axis.true_angle_deg();
  double lowest = start;
  run_until_settled(axis, 10.0);
  for (int i = 0; i < 100; ++i) {
    axis.step(kDt);
    lowest = std::min(lowest, axis.true_angle_deg());
  }
  ASSERT_TRUE(axis.state().in_position);
  // +20 deg through 180, not -340 deg back through 0.
  EXPECT_NEAR(axis.true_angle_deg() - start, 20.0, 1e-3);
  EXPECT_GE(lowest, start - 1e-9);
  EXPECT_NEAR(axis.state().angle_deg, -170.0, 1e-3);

  // Any wrap of the same angle is the same target.
  ASSERT_TRUE(axis.command_position(-170.0 + 720.0));
  run_axis_for(axis, 1.0);
  EXPECT_NEAR(axis.true_angle_deg() - start, 20.0, 1e-3);
}

/// Time until the true angle first comes within `tol` of the target [s].
double time_to_reach(TableAxisSim& axis, double target, double tol) {
  double t = 0.0;
  while (std::abs(axis.true_angle_deg() - target) >= tol && t < 60.0) {
    axis.step(kDt);
    t += kDt;
  }
  return t;
}

TEST(TableAxisSim, LongMoveTakesTheTrapezoidTime) {
  AxisLimits limits;
  limits.max_rate_dps = 50.0;
  limits.max_accel_dps2 = 100.0;
  TableAxisSim axis(limits);
  const double d = 170.0;
  ASSERT_TRUE(axis.command_position(d));
  const double t = time_to_reach(axis, d, 0.01);
  const double trapezoid = d / limits.max_rate_dps + limits.max_rate_dps / limits.max_accel_dps2;
  // The servo lag adds a few time constants at most; the profile itself is time optimal.
  EXPECT_GT(t, trapezoid);
  EXPECT_LT(t, trapezoid + 6.0 * limits.servo_time_constant_s);
}

TEST(TableAxisSim, ShortMoveTakesTheTriangleTime) {
  AxisLimits limits;
  limits.max_rate_dps = 300.0;
  limits.max_accel_dps2 = 100.0;
  TableAxisSim axis(limits);
  const double d = -10.0;  // peak rate 31.6 deg/s: never reaches the rate limit
  ASSERT_TRUE(axis.command_position(d));
  const double t = time_to_reach(axis, d, 0.01);
  const double triangle = 2.0 * std::sqrt(std::abs(d) / limits.max_accel_dps2);
  EXPECT_GT(t, triangle);
  EXPECT_LT(t, triangle + 6.0 * limits.servo_time_constant_s);
}

TEST(TableAxisSim, RateModeReachesTheRateAndTheAngleAdvances) {
  AxisLimits limits;
  TableAxisSim axis(limits);
  ASSERT_TRUE(axis.command_rate(-45.0));
  EXPECT_FALSE(axis.state().in_position);
  const double t = run_until_settled(axis, 5.0);
  ASSERT_TRUE(axis.state().in_position);
  EXPECT_EQ(axis.state().mode, core::AxisMode::kRate);
  // Ramp 0.225 s, lag to 1e-3 deg/s about 0.45 s, then the settle time.
  EXPECT_LT(t, 0.225 + 0.6 + limits.settle_time_s);
  EXPECT_NEAR(axis.state().rate_dps, -45.0, limits.rate_tolerance_dps);

  const double a0 = axis.true_angle_deg();
  run_axis_for(axis, 2.0);
  EXPECT_NEAR(axis.true_angle_deg() - a0, -90.0, 1e-6);
  EXPECT_NEAR(axis.true_rate_dps(), -45.0, 1e-9);
}

TEST(TableAxisSim, StopRampsDownAndHolds) {
  AxisLimits limits;
  TableAxisSim axis(limits);
  ASSERT_TRUE(axis.command_rate(100.0));
  run_axis_for(axis, 2.0);
  axis.stop();
  EXPECT_EQ(axis.state().mode, core::AxisMode::kRest);
  EXPECT_FALSE(axis.state().in_position);
  run_until_settled(axis, 5.0);
  ASSERT_TRUE(axis.state().in_position);
  const double held = axis.true_angle_deg();
  run_axis_for(axis, 1.0);
  // Settled means the rate is below tolerance; the servo lag still creeps the last nanodegrees.
  EXPECT_NEAR(axis.true_angle_deg(), held, 1e-6);
  EXPECT_NEAR(axis.true_rate_dps(), 0.0, 1e-9);
}

/// The required safety property: whatever is commanded, whenever, the true axis never turns
/// faster than max_rate_dps nor accelerates harder than max_accel_dps2.
void check_limits_under_random_commands(AxisLimits limits, std::uint64_t seed, bool vary_dt) {
  TableAxisSim axis(limits);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double rate_slack = limits.max_rate_dps * 1e-12;
  const double accel_slack = limits.max_accel_dps2 * 1e-9;
  double max_rate_seen = 0.0;
  double max_accel_seen = 0.0;
  long steps = 0;
  for (int command = 0; command < 400; ++command) {
    const double pick = unit(rng);
    if (pick < 0.35) {
      ASSERT_TRUE(axis.command_position(-720.0 + 1440.0 * unit(rng)) || axis.state().fault);
    } else if (pick < 0.70) {
      // Half of them at the full limit either way, so reversals from the limit happen often.
      const double fraction =
          unit(rng) < 0.5 ? (unit(rng) < 0.5 ? -1.0 : 1.0) : 2.0 * unit(rng) - 1.0;
      ASSERT_TRUE(axis.command_rate(limits.max_rate_dps * fraction) || axis.state().fault);
    } else if (pick < 0.80) {
      axis.stop();
    } else if (pick < 0.90) {
      axis.inject_fault("random trip");
    } else {
      axis.clear_fault();
    }
    // Often interrupts a motion mid-way, sometimes lets it reach full rate.
    const double hold_s = 3.0 * unit(rng);
    for (double t = 0.0; t < hold_s;) {
      const double dt = vary_dt ? 1e-4 + 4e-3 * unit(rng) : kDt;
      axis.step(dt);
      t += dt;
      ++steps;
      max_rate_seen = std::max(max_rate_seen, std::abs(axis.true_rate_dps()));
      max_accel_seen = std::max(max_accel_seen, std::abs(axis.true_accel_dps2()));
      ASSERT_LE(std::abs(axis.true_rate_dps()), limits.max_rate_dps + rate_slack)
          << "rate limit broken at step " << steps << " after command " << command;
      ASSERT_LE(std::abs(axis.true_accel_dps2()), limits.max_accel_dps2 + accel_slack)
          << "acceleration limit broken at step " << steps << " after command " << command;
      ASSERT_TRUE(std::isfinite(axis.true_angle_deg()));
    }
  }
  // The sequences must actually drive the axis to its limits, or the test proves nothing.
  EXPECT_GT(max_rate_seen, 0.9 * limits.max_rate_dps);
  EXPECT_GT(max_accel_seen, 0.9 * limits.max_accel_dps2);
}

TEST(TableAxisSim, NeverExceedsItsLimitsUnderRandomCommands) {
  AxisLimits limits;  // defaults: 300 deg/s, 200 deg/s^2, 50 ms servo
  check_limits_under_random_commands(limits, 1, false);
}

TEST(TableAxisSim, NeverExceedsItsLimitsWithAStiffServoAndVaryingDt) {
  AxisLimits limits;
  limits.max_rate_dps = 100.0;
  limits.max_accel_dps2 = 500.0;
  limits.servo_time_constant_s = 0.002;
  check_limits_under_random_commands(limits, 2, true);
}

TEST(TableAxisSim, NeverExceedsItsLimitsWithASlowServoAndVaryingDt) {
  AxisLimits limits;
  limits.max_rate_dps = 120.0;
  limits.max_accel_dps2 = 60.0;
  limits.servo_time_constant_s = 0.3;
  check_limits_under_random_commands(limits, 3, true);
}

TEST(TableAxisSim, ReportedAngleIsWrappedAndQuantized) {
  AxisLimits limits;
  limits.encoder_resolution_deg = 1e-3;
  TableAxisSim axis(limits);
  ASSERT_TRUE(axis.command_rate(123.456));
  bool saw_negative = false;
  bool saw_positive = false;
  for (int i = 0; i < 8000; ++i) {  // several turns
    axis.step(kDt);
    const double reported = axis.state().angle_deg;
    ASSERT_GE(reported, -180.0);
    ASSERT_LT(reported, 180.0);
    const double codes = reported / limits.encoder_resolution_deg;
    ASSERT_NEAR(codes, std::round(codes), 1e-6) << reported << " is not on an encoder code";
    // Within half a code of the true angle, modulo a turn.
    const double error = wrap_180(reported - axis.true_angle_deg());
    ASSERT_LE(std::abs(error), 0.5 * limits.encoder_resolution_deg + 1e-9);
    saw_negative |= reported < -90.0;
    saw_positive |= reported > 90.0;
  }
  EXPECT_GT(axis.true_angle_deg(), 360.0) << "the true angle is continuous";
  EXPECT_TRUE(saw_negative && saw_positive);
}

TEST(TableAxisSim, OutOfLimitCommandsAreRefusedNamingTheLimit) {
  AxisLimits limits;
  limits.max_rate_dps = 200.0;
  TableAxisSim axis(limits);

  const Status too_fast = axis.command_rate(250.0);
  EXPECT_FALSE(too_fast);
  EXPECT_NE(too_fast.message.find("250"), std::string::npos) << too_fast.message;
  EXPECT_NE(too_fast.message.find("200"), std::string::npos) << too_fast.message;
  EXPECT_FALSE(axis.command_rate(-200.5));
  EXPECT_FALSE(axis.command_rate(std::numeric_limits<double>::quiet_NaN()));
  EXPECT_FALSE(axis.command_rate(std::numeric_limits<double>::infinity()));
  EXPECT_FALSE(axis.command_position(std::numeric_limits<double>::quiet_NaN()));
  EXPECT_FALSE(axis.command_position(-std::numeric_limits<double>::infinity()));
  // Nothing moved and the mode is unchanged.
  run_axis_for(axis, 0.1);
  EXPECT_EQ(axis.state().mode, core::AxisMode::kRest);
  EXPECT_DOUBLE_EQ(axis.true_angle_deg(), 0.0);

  EXPECT_TRUE(axis.command_rate(-200.0)) << "the limit itself is allowed";
}

TEST(TableAxisSim, FaultBrakesToRestAndRefusesCommandsUntilCleared) {
  AxisLimits limits;
  TableAxisSim axis(limits);
  ASSERT_TRUE(axis.command_rate(200.0));
  run_axis_for(axis, 2.0);
  ASSERT_NEAR(axis.true_rate_dps(), 200.0, 1e-6);

  axis.inject_fault("amplifier trip");
  auto s = axis.state();
  EXPECT_EQ(s.mode, core::AxisMode::kFault);
  EXPECT_TRUE(s.fault);
  EXPECT_EQ(s.fault_text, "amplifier trip");
  EXPECT_FALSE(s.in_position);

  const Status refused = axis.command_position(10.0);
  EXPECT_FALSE(refused);
  EXPECT_NE(refused.message.find("amplifier trip"), std::string::npos) << refused.message;
  EXPECT_FALSE(axis.command_rate(0.0));
  axis.stop();
  EXPECT_EQ(axis.state().mode, core::AxisMode::kFault) << "stop() must not clear a fault";

  // Brakes at the acceleration limit: rest after v/a plus the servo lag.
  double t = 0.0;
  while (std::abs(axis.true_rate_dps()) > 1e-6 && t < 10.0) {
    axis.step(kDt);
    t += kDt;
  }
  const double brake_time = 200.0 / limits.max_accel_dps2;
  EXPECT_GT(t, brake_time);
  EXPECT_LT(t, brake_time + 20.0 * limits.servo_time_constant_s);
  run_axis_for(axis, 1.0);
  EXPECT_TRUE(axis.state().fault);
  EXPECT_FALSE(axis.state().in_position);

  axis.clear_fault();
  s = axis.state();
  EXPECT_EQ(s.mode, core::AxisMode::kRest);
  EXPECT_FALSE(s.fault);
  EXPECT_TRUE(s.fault_text.empty());
  const double held = axis.true_angle_deg();
  run_axis_for(axis, 1.0);
  EXPECT_NEAR(axis.true_angle_deg(), held, 1e-9) << "clear_fault holds where the axis is";
  EXPECT_TRUE(axis.state().in_position);
  EXPECT_TRUE(axis.command_position(0.0));
}

TEST(TableAxisSim, NonPositiveStepsAreIgnored) {
  TableAxisSim axis;
  ASSERT_TRUE(axis.command_rate(100.0));
  run_axis_for(axis, 0.5);
  const double angle = axis.true_angle_deg();
  const double rate = axis.true_rate_dps();
  axis.step(0.0);
  axis.step(-1e-3);
  axis.step(std::numeric_limits<double>::quiet_NaN());
  EXPECT_EQ(axis.true_angle_deg(), angle);
  EXPECT_EQ(axis.true_rate_dps(), rate);
}

TEST(TableAxisSim, NewTargetMidMoveStillLandsOnIt) {
  AxisLimits limits;
  TableAxisSim axis(limits);
  ASSERT_TRUE(axis.command_position(150.0));
  run_axis_for(axis, 0.8);  // at speed, moving positive
  ASSERT_GT(axis.true_rate_dps(), 100.0);
  ASSERT_TRUE(axis.command_position(20.0));  // behind it now: must brake, reverse, come back
  run_until_settled(axis, 10.0);
  ASSERT_TRUE(axis.state().in_position);
  EXPECT_NEAR(axis.true_angle_deg(), 20.0, limits.position_tolerance_deg);
}

TEST(TableSim, StepsBothAxesAndReportsThem) {
  AxisLimits outer;
  AxisLimits inner;
  inner.max_rate_dps = 100.0;
  TableSim table(outer, inner);
  ASSERT_TRUE(table.outer().command_position(-30.0));
  ASSERT_TRUE(table.inner().command_rate(10.0));
  for (int i = 0; i < 3000; ++i) table.step(kDt);
  const auto s = table.state(3.0);
  EXPECT_DOUBLE_EQ(s.time_s, 3.0);
  EXPECT_NEAR(s.outer.angle_deg, -30.0, 1e-3);
  EXPECT_NEAR(s.inner.rate_dps, 10.0, 1e-3);
  EXPECT_EQ(s.inner.mode, core::AxisMode::kRate);
}

}  // namespace
}  // namespace calstand::sim

namespace calstand::sim {
namespace {

// After hours at 300 deg/s the continuous angle is in the millions of degrees; rates and
// moves must still settle to their tolerances there.
TEST(TableAxisSim, RateStaysSettledAfterHoursOfTurning) {
  AxisLimits limits;
  limits.max_rate_dps = 400.0;
  limits.max_accel_dps2 = 300.0;
  TableAxisSim axis(limits);
  ASSERT_TRUE(axis.command_rate(300.0));
  const double dt = 1.0 / 400.0;
  for (int k = 0; k < 400 * 3600 * 3; ++k) axis.step(dt);  // 3 h: 3.2e6 deg of travel
  ASSERT_TRUE(axis.command_rate(-300.0));
  for (int k = 0; k < 400 * 10; ++k) axis.step(dt);
  EXPECT_TRUE(axis.state().in_position);
  EXPECT_NEAR(axis.true_rate_dps(), -300.0, 1e-6);
  ASSERT_TRUE(axis.command_position(45.0));
  for (int k = 0; k < 400 * 20; ++k) axis.step(dt);
  EXPECT_TRUE(axis.state().in_position);
  EXPECT_NEAR(axis.state().angle_deg, 45.0, 1e-3);
}

}  // namespace
}  // namespace calstand::sim

namespace calstand::sim {
namespace {

// Whatever the step lengths, a steady rate is exactly the command: the servo's discretisation
// must not turn uneven steps into rate ripple (it once did, by 4e-6 relative per 1e-7 s).
TEST(TableAxisSim, SteadyRateIsExactWithUnevenSteps) {
  AxisLimits limits;
  limits.max_rate_dps = 400.0;
  limits.max_accel_dps2 = 300.0;
  limits.servo_time_constant_s = 0.02;
  TableAxisSim axis(limits);
  ASSERT_TRUE(axis.command_rate(300.0));
  for (int k = 0; k < 4000; ++k) axis.step(0.0025);
  NormalSource jitter(3);
  double worst = 0.0;
  for (int k = 0; k < 4000; ++k) {
    // Steps from 1 us to 5 ms, as a control tick that splits a sample period would make.
    const double dt = k % 2 ? 1e-6 + 1e-3 * std::abs(jitter.next()) : 0.0025;
    axis.step(dt);
    worst = std::max(worst, std::abs(axis.true_rate_dps() - 300.0));
  }
  EXPECT_LT(worst, 1e-6);
  EXPECT_TRUE(axis.state().in_position);
}

// The sine goes about the commanded angle, and the true axis follows it through the servo's
// first-order lag: gain 1 / sqrt(1 + (w tau)^2) and phase -atan(w tau), seen on the angle and on
// the rate the encoder reports alike. A least-squares fit at the known frequency reads both.
TEST(TableAxisSim, SineFollowsTheProfileThroughTheServoLagAboutTheStartAngle) {
  AxisLimits limits;
  limits.max_rate_dps = 100.0;
  limits.max_accel_dps2 = 500.0;
  limits.servo_time_constant_s = 0.02;
  TableAxisSim axis(limits);
  ASSERT_TRUE(axis.command_position(30.0));
  run_until_settled(axis, 10.0);
  const double a = 2.0, f = 2.0, w = 2.0 * M_PI * f;  // 25 deg/s, 316 deg/s^2 peak
  ASSERT_TRUE(axis.command_sine(a, f));
  EXPECT_EQ(axis.state().mode, core::AxisMode::kSine);
  double t = 0.0;
  for (int i = 0; i < 1000; ++i) {  // one second: the start has died out
    axis.step(kDt);
    t += kDt;
  }
  double ss = 0, sc = 0, cc = 0, ys = 0, yc = 0, rs = 0, rc = 0, lo = 1e9, hi = -1e9;
  for (int i = 0; i < 2000; ++i) {  // four whole periods
    axis.step(kDt);
    t += kDt;
    const double s = std::sin(w * t), c = std::cos(w * t);
    ss += s * s, sc += s * c, cc += c * c;
    ys += (axis.true_angle_deg() - 30.0) * s, yc += (axis.true_angle_deg() - 30.0) * c;
    // The reported rate is the one at the step's end, like the angle.
    rs += axis.state().rate_dps * s, rc += axis.state().rate_dps * c;
    lo = std::min(lo, axis.state().angle_deg);
    hi = std::max(hi, axis.state().angle_deg);
  }
  // Whole periods on a fine grid: sin and cos are orthogonal, so the projections are the fit.
  EXPECT_NEAR(sc / ss, 0.0, 1e-3);
  const double gain = 1.0 / std::sqrt(1.0 + w * w * 0.02 * 0.02);
  const double lag = -std::atan(w * 0.02);
  EXPECT_NEAR(std::hypot(ys / ss, yc / cc) / a, gain, 2e-3);
  EXPECT_NEAR(std::atan2(yc / cc, ys / ss), lag, 2e-3);
  EXPECT_NEAR(std::hypot(rs / ss, rc / cc) / (w * a), gain, 2e-3);
  EXPECT_NEAR(std::atan2(rc / cc, rs / ss) - M_PI / 2, lag, 2e-3);
  EXPECT_NEAR(0.5 * (lo + hi), 30.0, 1e-3);  // about the start angle
  EXPECT_TRUE(axis.state().in_position);

  axis.stop();
  run_until_settled(axis, 10.0);
  EXPECT_EQ(axis.state().mode, core::AxisMode::kRest);
  EXPECT_NEAR(axis.true_rate_dps(), 0.0, 1e-9);
}

TEST(TableAxisSim, SineBeyondTheRateOrAccelerationLimitIsRefused) {
  AxisLimits limits;
  limits.max_rate_dps = 100.0;
  limits.max_accel_dps2 = 500.0;
  TableAxisSim axis(limits);
  const auto fast = axis.command_sine(1.0, 4.0);  // 632 deg/s^2
  EXPECT_FALSE(fast);
  EXPECT_NE(fast.message.find("deg/s^2"), std::string::npos) << fast.message;
  EXPECT_FALSE(axis.command_sine(20.0, 1.0));  // 126 deg/s
  EXPECT_FALSE(axis.command_sine(0.0, 1.0));
  EXPECT_EQ(axis.state().mode, core::AxisMode::kRest);
  axis.inject_fault("door");
  EXPECT_FALSE(axis.command_sine(0.1, 1.0));
}

}  // namespace
}  // namespace calstand::sim
