#include "sim/table_sim.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

namespace calstand::sim {
namespace {

/// `angle_deg` wrapped to [-180, 180) [deg].
double wrap_180(double angle_deg) {
  double wrapped = std::fmod(angle_deg + 180.0, 360.0);
  if (wrapped < 0.0) wrapped += 360.0;
  wrapped -= 180.0;
  // fmod is exact, but the shifts round: a value a hair below -180 can come back as 180.
  return wrapped >= 180.0 ? wrapped - 360.0 : wrapped;
}

/// The braking rate for a remaining distance: the largest rate from which a profile that
/// slows by `dv` every step of `dt` (rates v, v - dv, v - 2 dv, ..., down to the last partial
/// step) covers exactly `distance`. Following it step by step lands on the target exactly, with
/// every rate change within dv; a continuous v = sqrt(2 a d) would leave a residue at the end
/// that needs a jump beyond the acceleration limit. Signed like `distance`. `last_step` is set
/// when a single step at this rate covers the whole distance.
double braking_rate(double distance, double dv, double dt, bool& last_step) {
  // With v = (m + f) dv, m integer, f in [0, 1), the steps cover
  // dv dt [(m + 1) f + m (m + 1) / 2].
  const double units = std::abs(distance) / (dv * dt);
  double m = std::floor((std::sqrt(1.0 + 8.0 * units) - 1.0) / 2.0);
  // The square root can round across an integer; put m back in its bracket.
  if (m > 0.0 && m * (m + 1.0) / 2.0 > units) m -= 1.0;
  if ((m + 1.0) * (m + 2.0) / 2.0 <= units) m += 1.0;
  const double f = std::clamp((units - m * (m + 1.0) / 2.0) / (m + 1.0), 0.0, 1.0);
  last_step = m == 0.0;
  return std::copysign((m + f) * dv, distance);
}

}  // namespace

TableAxisSim::TableAxisSim(AxisLimits limits) : limits_(limits) {}

Status TableAxisSim::command_position(double angle_deg) {
  if (mode_ == core::AxisMode::kFault) {
    return Status::refused(fmt::format("axis in fault ({}): clear the fault first", fault_text_));
  }
  if (!std::isfinite(angle_deg)) {
    return Status::refused(fmt::format("position {} deg is not a finite angle", angle_deg));
  }
  // Slip rings allow unbounded travel, so the equivalent angle nearest the profile is the
  // shortest way round; exactly half a turn away goes the negative way.
  target_angle_deg_ = profile_angle_deg_ + wrap_180(angle_deg - profile_angle_deg_);
  mode_ = core::AxisMode::kPosition;
  restart_settling();
  return Status::success();
}

Status TableAxisSim::command_rate(double rate_dps) {
  if (mode_ == core::AxisMode::kFault) {
    return Status::refused(fmt::format("axis in fault ({}): clear the fault first", fault_text_));
  }
  if (!std::isfinite(rate_dps)) {
    return Status::refused(fmt::format("rate {} deg/s is not finite", rate_dps));
  }
  if (std::abs(rate_dps) > limits_.max_rate_dps) {
    return Status::refused(fmt::format("rate {} deg/s exceeds the axis limit {} deg/s", rate_dps,
                                       limits_.max_rate_dps));
  }
  target_rate_dps_ = rate_dps;
  mode_ = core::AxisMode::kRate;
  restart_settling();
  return Status::success();
}

Status TableAxisSim::command_sine(double amplitude_deg, double frequency_hz) {
  if (mode_ == core::AxisMode::kFault) {
    return Status::refused(fmt::format("axis in fault ({}): clear the fault first", fault_text_));
  }
  if (!(amplitude_deg > 0.0) || !std::isfinite(amplitude_deg) || !(frequency_hz > 0.0) ||
      !std::isfinite(frequency_hz)) {
    return Status::refused(fmt::format("sine {} deg at {} Hz: both must be positive and finite",
                                       amplitude_deg, frequency_hz));
  }
  const double w = 2.0 * std::numbers::pi * frequency_hz;
  if (w * amplitude_deg > limits_.max_rate_dps) {
    return Status::refused(
        fmt::format("sine {} deg at {} Hz peaks at {} deg/s, beyond the axis "
                    "limit {} deg/s",
                    amplitude_deg, frequency_hz, w * amplitude_deg, limits_.max_rate_dps));
  }
  if (w * w * amplitude_deg > limits_.max_accel_dps2) {
    return Status::refused(
        fmt::format("sine {} deg at {} Hz peaks at {} deg/s^2, beyond the axis "
                    "limit {} deg/s^2",
                    amplitude_deg, frequency_hz, w * w * amplitude_deg, limits_.max_accel_dps2));
  }
  // About the commanded angle, not the servo's: a settled axis stands there, and the centre
  // must not depend on the servo's residual error at the instant of the command.
  sine_center_deg_ = mode_ == core::AxisMode::kPosition ? target_angle_deg_ : profile_angle_deg_;
  sine_amplitude_deg_ = amplitude_deg;
  sine_frequency_hz_ = frequency_hz;
  sine_time_s_ = 0.0;
  mode_ = core::AxisMode::kSine;
  restart_settling();
  return Status::success();
}

void TableAxisSim::stop() {
  // A fault already brakes to rest; stopping must not clear it.
  if (mode_ == core::AxisMode::kFault) return;
  mode_ = core::AxisMode::kRest;
  restart_settling();
}

void TableAxisSim::inject_fault(std::string why) {
  mode_ = core::AxisMode::kFault;
  fault_text_ = why.empty() ? std::string("unspecified fault") : std::move(why);
  restart_settling();
}

void TableAxisSim::clear_fault() {
  if (mode_ != core::AxisMode::kFault) return;
  // kRest keeps braking if the axis is still turning and then holds wherever it stops.
  mode_ = core::AxisMode::kRest;
  fault_text_.clear();
  restart_settling();
}

void TableAxisSim::step(double dt_s) {
  if (!(dt_s > 0.0) || !std::isfinite(dt_s)) return;
  const double profile_before_deg = profile_angle_deg_;
  step_profile(dt_s);
  step_servo(dt_s, profile_before_deg);
  step_settling(dt_s);
}

void TableAxisSim::step_profile(double dt_s) {
  const double dv = limits_.max_accel_dps2 * dt_s;  // largest rate change in one step
  const double previous_rate = profile_rate_dps_;
  const auto limit_rate = [&](double wanted) {
    return std::clamp(std::clamp(wanted, previous_rate - dv, previous_rate + dv),
                      -limits_.max_rate_dps, limits_.max_rate_dps);
  };

  switch (mode_) {
    case core::AxisMode::kPosition: {
      const double distance = target_angle_deg_ - profile_angle_deg_;
      bool last_step = false;
      const double wanted = braking_rate(distance, dv, dt_s, last_step);
      const double rate = limit_rate(wanted);
      profile_rate_dps_ = rate;
      if (last_step && rate == wanted) {
        // Land on the target itself rather than on target - distance + rate * dt, which
        // rounding would leave a few ulps off for ever.
        profile_angle_deg_ = target_angle_deg_;
      } else {
        // Either accelerating/cruising (rate below the braking rate) or, after a new target
        // arrived too late to brake for, overshooting at full deceleration and coming back.
        profile_angle_deg_ += rate * dt_s;
      }
      return;
    }
    case core::AxisMode::kRate:
      profile_rate_dps_ = limit_rate(target_rate_dps_);
      break;
    case core::AxisMode::kSine: {
      // The sine itself, not rate-limited step by step: command_sine() refused one beyond the
      // limits, and the servo's clamps catch the start (the rate jumps from 0 to 2 pi f A).
      sine_time_s_ += dt_s;
      const double next = sine_center_deg_ +
                          sine_amplitude_deg_ *
                              std::sin(2.0 * std::numbers::pi * sine_frequency_hz_ * sine_time_s_);
      profile_rate_dps_ = (next - profile_angle_deg_) / dt_s;
      profile_angle_deg_ = next;
      return;
    }
    case core::AxisMode::kRest:
    case core::AxisMode::kFault:
      profile_rate_dps_ = limit_rate(0.0);
      break;
  }
  profile_angle_deg_ += profile_rate_dps_ * dt_s;
}

void TableAxisSim::step_servo(double dt_s, double profile_before_deg) {
  // The world steps on a sample grid whose dt differs only by rounding from step to step;
  // reuse the decay unless dt really changed. The first-order-hold solution below keeps a
  // steady rate exact whatever decay it is given, so a decay from a dt 1e-6 off costs nothing.
  if (std::abs(dt_s - servo_dt_s_) > 1e-6 * dt_s) {
    servo_dt_s_ = dt_s;
    servo_decay_ =
        limits_.servo_time_constant_s > 0.0 ? std::exp(-dt_s / limits_.servo_time_constant_s) : 0.0;
  }
  // The true angle is the profile angle through a first-order lag, solved exactly for a
  // profile that moves linearly over the step (first-order hold): with the profile going from
  // p0 to p1 at rate v, y1 = p1 - v tau + (y0 - p0 + v tau) exp(-dt/tau). At a constant profile
  // rate the lag settles at v tau and the axis turns at exactly v whatever the step lengths,
  // which a zero-order hold does not do (its rate then ripples with every change of dt). The
  // axis rate over the step is a weighted mean of the lagged profile rates, so it stays within
  // the rate limit, and its changes within the acceleration limit; the clamps below only catch
  // rounding and the rare dt change right after a profile corner.
  const double tau = limits_.servo_time_constant_s;
  const double v = (profile_angle_deg_ - profile_before_deg) / dt_s;
  const double lag_term = v * tau;
  const double wanted_angle =
      profile_angle_deg_ - lag_term + (angle_deg_ - profile_before_deg + lag_term) * servo_decay_;
  const double wanted_rate = (wanted_angle - angle_deg_) / dt_s;
  const double max_dv = limits_.max_accel_dps2 * dt_s;
  const double rate = std::clamp(std::clamp(wanted_rate, rate_dps_ - max_dv, rate_dps_ + max_dv),
                                 -limits_.max_rate_dps, limits_.max_rate_dps);
  accel_dps2_ = (rate - rate_dps_) / dt_s;
  rate_dps_ = rate;
  angle_deg_ = rate == wanted_rate ? wanted_angle : angle_deg_ + rate * dt_s;
  // In a sine the axis accelerates all the time, and the mean over the step lags the rate at
  // its end by about half the step, which differs between an IMU sample and an encoder reading
  // taken off the sample grid (0.1 ms of false delay in an oscillation test): there the rate
  // reported is the lag's own equation at the step's end, y' = (p - y) / tau. Elsewhere the
  // axis holds a rate or settles, and the mean over the step is kept (a reading at rest then
  // holds still, as the store's interpolation expects); so it is where a limit clamped the
  // step, or without a lag.
  instant_rate_dps_ = mode_ == core::AxisMode::kSine && tau > 0.0 && rate == wanted_rate
                          ? std::clamp((profile_angle_deg_ - angle_deg_) / tau,
                                       -limits_.max_rate_dps, limits_.max_rate_dps)
                          : rate_dps_;
}

void TableAxisSim::step_settling(double dt_s) {
  bool within = false;
  switch (mode_) {
    case core::AxisMode::kPosition:
      within = std::abs(angle_deg_ - target_angle_deg_) < limits_.position_tolerance_deg;
      break;
    case core::AxisMode::kRate:
      within = std::abs(rate_dps_ - target_rate_dps_) < limits_.rate_tolerance_dps;
      break;
    case core::AxisMode::kRest:
      within = std::abs(rate_dps_) < limits_.rate_tolerance_dps;
      break;
    case core::AxisMode::kSine:
      within = true;  // "settled": the start of the sine is settle_time_s behind
      break;
    case core::AxisMode::kFault:
      within = false;  // a faulted axis is never "in position"
      break;
  }
  settled_for_s_ = within ? settled_for_s_ + dt_s : 0.0;
  // Summing a fixed dt drifts by ulps; without the slack a 0.5 s settle at 1 ms would take 501
  // steps on some dt values and 500 on others.
  in_position_ = within && settled_for_s_ >= limits_.settle_time_s * (1.0 - 1e-9);
}

void TableAxisSim::restart_settling() {
  settled_for_s_ = 0.0;
  in_position_ = false;
}

core::AxisState TableAxisSim::state() const {
  core::AxisState s;
  double angle = wrap_180(angle_deg_);
  const double lsb = limits_.encoder_resolution_deg;
  if (lsb > 0.0) {
    angle = std::round(angle / lsb) * lsb;
    // Rounding up near +180 reaches the excluded end of the range.
    if (angle >= 180.0) angle -= 360.0;
    // -180 itself is a code; lsb * round(-180 / lsb) can come back an ulp below it.
    if (angle < -180.0) angle = -180.0;
  }
  s.angle_deg = angle;
  s.rate_dps = instant_rate_dps_;
  s.mode = mode_;
  s.in_position = in_position_;
  s.fault = mode_ == core::AxisMode::kFault;
  s.fault_text = s.fault ? fault_text_ : std::string();
  return s;
}

}  // namespace calstand::sim
