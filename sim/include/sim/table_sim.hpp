#pragma once

#include <string>

#include "core/station_config.hpp"
#include "core/table_state.hpp"
#include "sim/status.hpp"

namespace calstand::sim {

/// Limits and servo behaviour of one simulated table axis: the station file's axis figures
/// (core::AxisConfig), used as they are.
using AxisLimits = core::AxisConfig;

/// One axis of the simulated table: a rate- and acceleration-limited motion profile (trapezoidal
/// to a position, ramped to a rate) followed by the servo with a first-order lag, so the motion
/// settles as a real axis does and never exceeds the limits. Unbounded (slip-ring) travel: the
/// true angle is continuous, reported angles are wrapped to [-180, 180) and quantized to the
/// encoder resolution. Not thread safe; owned by the simulated world.
///
/// The profile is planned per step: its rate changes by at most max_accel * dt each step and
/// brakes along the discrete braking curve, so a move lands exactly on the target without
/// overshoot; the true angle is the profile through an exactly discretised first-order lag,
/// whose rate and acceleration stay within the limits at every step (re-clamped when dt varies).
/// A new command takes effect from the current motion, so it may overshoot a target it can no
/// longer brake for and come back.
class TableAxisSim {
 public:
  /// `limits` must have positive max_rate_dps and max_accel_dps2 (the station config validates).
  explicit TableAxisSim(AxisLimits limits = {});

  /// Moves to `angle_deg` (any wrap) along the shortest way round and holds it there.
  Status command_position(double angle_deg);
  /// Turns at `rate_dps` (signed, right-handed); refused beyond max_rate_dps.
  Status command_rate(double rate_dps);
  /// Oscillates about the angle the axis is commanded to (its profile's angle, where a settled
  /// axis stands): the profile follows start + amplitude_deg sin(2 pi frequency_hz t), t from
  /// this call, and the axis follows the profile through its servo lag. Refused when the axis
  /// is faulted, for a non-positive or non-finite amplitude or frequency, or when the peak rate
  /// 2 pi f A or the peak acceleration (2 pi f)^2 A exceeds the axis's limits. stop() ends it.
  Status command_sine(double amplitude_deg, double frequency_hz);
  /// Decelerates at the acceleration limit and holds at rest (the safe state).
  void stop();
  /// A fault (e.g. amplifier trip): the axis brakes to rest at the acceleration limit, reports
  /// the fault and refuses commands until clear_fault().
  void inject_fault(std::string why);
  void clear_fault();

  /// Advances the axis by dt_s > 0.
  void step(double dt_s);

  double true_angle_deg() const { return angle_deg_; }  ///< continuous, unquantized [deg]
  /// The rate [deg/s]: in a sine the rate at the end of the last step (IMU samples and encoder
  /// readings end steps of different lengths, and a mean over the step would lag each by half
  /// its own step); elsewhere the mean over the last step.
  double true_rate_dps() const { return instant_rate_dps_; }
  double true_accel_dps2() const { return accel_dps2_; }  ///< over the last step [deg/s^2]
  /// What the controller reports: wrapped, quantized angle, mode, settling and fault.
  core::AxisState state() const;
  const AxisLimits& limits() const { return limits_; }

 private:
  /// Advances the motion profile by one step of dt_s, honouring the limits per step.
  void step_profile(double dt_s);
  /// Advances the servo (true axis) behind the profile by one step of dt_s.
  void step_servo(double dt_s, double profile_before_deg);
  /// Updates the settle timer and in_position_ after a step of dt_s.
  void step_settling(double dt_s);
  /// Forgets settling: a new command (or a fault) starts the settle timer again.
  void restart_settling();

  AxisLimits limits_;
  core::AxisMode mode_ = core::AxisMode::kRest;
  double angle_deg_ = 0.0;          // true axis, continuous (unwrapped) [deg]
  double rate_dps_ = 0.0;           // true axis, mean over the last step [deg/s]
  double instant_rate_dps_ = 0.0;   // true axis, as true_rate_dps() reports it [deg/s]
  double accel_dps2_ = 0.0;         // true axis, over the last step [deg/s^2]
  double profile_angle_deg_ = 0.0;  // where the profile is, unwrapped [deg]
  double profile_rate_dps_ = 0.0;   // profile rate over the last step [deg/s]
  double target_angle_deg_ = 0.0;   // position mode, unwrapped [deg]
  double target_rate_dps_ = 0.0;    // rate mode [deg/s]
  double sine_center_deg_ = 0.0;    // sine mode: the start angle, unwrapped [deg]
  double sine_amplitude_deg_ = 0.0;
  double sine_frequency_hz_ = 0.0;
  double sine_time_s_ = 0.0;    // since the sine was commanded [s]
  double settled_for_s_ = 0.0;  // how long the error has stayed in tolerance [s]
  bool in_position_ = true;
  std::string fault_text_;
  // exp() is the only costly call in step(); the simulator steps at a fixed dt, so it is
  // evaluated once per distinct dt.
  double servo_dt_s_ = -1.0;
  double servo_decay_ = 0.0;  // exp(-dt / servo_time_constant_s) for servo_dt_s_
};

/// The dual-axis table: an outer and an inner axis.
class TableSim {
 public:
  TableSim(AxisLimits outer, AxisLimits inner) : outer_(outer), inner_(inner) {}
  TableAxisSim& outer() { return outer_; }
  TableAxisSim& inner() { return inner_; }
  const TableAxisSim& outer() const { return outer_; }
  const TableAxisSim& inner() const { return inner_; }
  void step(double dt_s) {
    outer_.step(dt_s);
    inner_.step(dt_s);
  }
  core::TableState state(double time_s) const { return {time_s, outer_.state(), inner_.state()}; }

 private:
  TableAxisSim outer_;
  TableAxisSim inner_;
};

}  // namespace calstand::sim
