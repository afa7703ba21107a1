#include <fmt/format.h>

#include <cmath>
#include <numbers>

#include "drivers/acutrol_server.hpp"
#include "sim/sim_world.hpp"

namespace calstand::drivers {

using acutrol::ErrorCode;
using acutrol::WireMode;

namespace {

acutrol::ErrorReply refuse(ErrorCode code, std::string text) {
  return {static_cast<int>(code), std::move(text)};
}

sim::TableAxisSim& sim_axis(sim::SimWorld& world, int axis) {
  return axis == acutrol::kInnerAxis ? world.table().inner() : world.table().outer();
}

WireMode to_wire_mode(core::AxisMode mode) {
  switch (mode) {
    case core::AxisMode::kRest:
      return WireMode::kRest;
    case core::AxisMode::kPosition:
      return WireMode::kPosition;
    case core::AxisMode::kRate:
      return WireMode::kRate;
    case core::AxisMode::kSine:
      return WireMode::kSine;
    case core::AxisMode::kFault:
      return WireMode::kFault;
  }
  return WireMode::kFault;
}

}  // namespace

SimTableBackend::SimTableBackend(sim::SimWorld& world, std::mutex& world_mutex)
    : world_(world), mutex_(world_mutex) {
  std::lock_guard lock(mutex_);
  for (const int axis : {acutrol::kOuterAxis, acutrol::kInnerAxis}) {
    const auto& limits = sim_axis(world_, axis).limits();
    control(axis).max_rate_dps = limits.max_rate_dps;
    control(axis).max_accel_dps2 = limits.max_accel_dps2;
  }
}

std::string SimTableBackend::identity() { return "CALSTAND,ACUTROL-SIM,0,1.0"; }

void SimTableBackend::catch_up() {
  // The world advances in slices on its runner's thread, and falls behind when that thread
  // waits for a CPU (a busy machine: tens of ms of wall time, a second of world time at 20x).
  // A controller answers from its axes as they are at the moment of the query, and acts on a
  // command then: the world is brought to that moment first. Answered from where the world
  // stood, a turning axis read up to a second behind its time stamp (a rate step's telemetry
  // showed a rate of 45 deg/s for 60), and a command took effect that much earlier in the
  // world than the client sent it.
  if (now_s_) world_.advance_to(now_s_());
}

TableServerBackend::AxisReport SimTableBackend::report(int axis) {
  std::lock_guard lock(mutex_);
  catch_up();
  const core::AxisState s = sim_axis(world_, axis).state();
  const auto& c = control(axis);
  AxisReport r;
  r.angle_deg = s.angle_deg;
  r.rate_dps = s.rate_dps;
  r.status.mode = to_wire_mode(s.mode);
  r.status.settled = s.in_position;
  r.status.interlock_open = c.interlock_open;
  r.status.fault_text = s.fault ? s.fault_text : std::string();
  return r;
}

acutrol::InterlockReply SimTableBackend::interlock(int axis) {
  std::lock_guard lock(mutex_);
  const auto& c = control(axis);
  return {c.interlock_open, c.interlock_why};
}

Refusal SimTableBackend::motion_refusal(int axis) {
  const auto& c = control(axis);
  if (c.interlock_open) {
    return refuse(ErrorCode::kInterlockOpen,
                  fmt::format("axis {} interlock open: {}", axis, c.interlock_why));
  }
  const auto s = sim_axis(world_, axis).state();
  if (s.fault)
    return refuse(ErrorCode::kAxisFault, fmt::format("axis {} fault: {}", axis, s.fault_text));
  return std::nullopt;
}

Refusal SimTableBackend::select_mode(int axis, WireMode mode) {
  std::lock_guard lock(mutex_);
  catch_up();
  if (auto r = motion_refusal(axis)) return r;
  control(axis).selected = mode;
  return std::nullopt;
}

Refusal SimTableBackend::demand_position(int axis, double angle_deg) {
  std::lock_guard lock(mutex_);
  catch_up();
  if (auto r = motion_refusal(axis)) return r;
  if (control(axis).selected != WireMode::kPosition) {
    return refuse(
        ErrorCode::kWrongMode,
        fmt::format("axis {} is not in position mode: send :mode:position {} first", axis, axis));
  }
  const auto st = sim_axis(world_, axis).command_position(angle_deg);
  if (!st) return refuse(ErrorCode::kAxisFault, fmt::format("axis {}: {}", axis, st.message));
  return std::nullopt;
}

Refusal SimTableBackend::demand_rate(int axis, double rate_dps) {
  std::lock_guard lock(mutex_);
  catch_up();
  if (auto r = motion_refusal(axis)) return r;
  auto& c = control(axis);
  if (c.selected != WireMode::kRate) {
    return refuse(ErrorCode::kWrongMode,
                  fmt::format("axis {} is not in rate mode: send :mode:rate {} first", axis, axis));
  }
  if (std::abs(rate_dps) > c.max_rate_dps) {
    return refuse(ErrorCode::kLimitExceeded,
                  fmt::format("axis {} rate {:.6f} deg/s exceeds the limit {:.6f} deg/s", axis,
                              rate_dps, c.max_rate_dps));
  }
  const auto st = sim_axis(world_, axis).command_rate(rate_dps);
  if (!st) return refuse(ErrorCode::kLimitExceeded, fmt::format("axis {}: {}", axis, st.message));
  return std::nullopt;
}

Refusal SimTableBackend::demand_sine(int axis, double amplitude_deg, double frequency_hz) {
  std::lock_guard lock(mutex_);
  catch_up();
  if (auto r = motion_refusal(axis)) return r;
  auto& c = control(axis);
  if (c.selected != WireMode::kSine) {
    return refuse(ErrorCode::kWrongMode,
                  fmt::format("axis {} is not in sine mode: send :mode:sine {} first", axis, axis));
  }
  // The controller's own limits, which may be below the simulated axis's (`:limit`).
  const double w = 2.0 * std::numbers::pi * frequency_hz;
  if (w * amplitude_deg > c.max_rate_dps || w * w * amplitude_deg > c.max_accel_dps2) {
    return refuse(ErrorCode::kLimitExceeded,
                  fmt::format("axis {} sine {:.6f} deg at {:.6f} Hz peaks at {:.6f} deg/s and "
                              "{:.6f} deg/s^2, beyond the limits {:.6f} deg/s, {:.6f} deg/s^2",
                              axis, amplitude_deg, frequency_hz, w * amplitude_deg,
                              w * w * amplitude_deg, c.max_rate_dps, c.max_accel_dps2));
  }
  const auto st = sim_axis(world_, axis).command_sine(amplitude_deg, frequency_hz);
  if (!st) return refuse(ErrorCode::kLimitExceeded, fmt::format("axis {}: {}", axis, st.message));
  return std::nullopt;
}

Refusal SimTableBackend::set_limits(int axis, double max_rate_dps, double max_accel_dps2) {
  std::lock_guard lock(mutex_);
  const auto& own = sim_axis(world_, axis).limits();
  if (max_rate_dps > own.max_rate_dps || max_accel_dps2 > own.max_accel_dps2) {
    return refuse(
        ErrorCode::kLimitExceeded,
        fmt::format("axis {} limits {:.6f} deg/s, {:.6f} deg/s^2 exceed the axis's own "
                    "{:.6f} deg/s, {:.6f} deg/s^2",
                    axis, max_rate_dps, max_accel_dps2, own.max_rate_dps, own.max_accel_dps2));
  }
  control(axis).max_rate_dps = max_rate_dps;
  control(axis).max_accel_dps2 = max_accel_dps2;
  return std::nullopt;
}

void SimTableBackend::stop(int axis) {
  std::lock_guard lock(mutex_);
  catch_up();
  sim_axis(world_, axis).stop();
  control(axis).selected = WireMode::kRest;
}

Refusal SimTableBackend::close_interlock(int axis) {
  std::lock_guard lock(mutex_);
  catch_up();
  auto& c = control(axis);
  if (!c.interlock_open) return std::nullopt;
  if (c.cause_present) {
    return refuse(ErrorCode::kInterlockCause,
                  fmt::format("axis {} interlock cannot close: {}", axis, c.interlock_why));
  }
  c.interlock_open = false;
  c.interlock_why.clear();
  c.selected = WireMode::kRest;
  sim_axis(world_, axis).clear_fault();
  return std::nullopt;
}

void SimTableBackend::open_interlock(int axis, const std::string& why) {
  std::lock_guard lock(mutex_);
  auto& c = control(axis);
  c.interlock_open = true;
  c.cause_present = true;
  c.interlock_why = why.empty() ? std::string("unspecified cause") : why;
  c.selected = WireMode::kRest;
  sim_axis(world_, axis).inject_fault("interlock open: " + c.interlock_why);
}

void SimTableBackend::clear_interlock_cause(int axis) {
  std::lock_guard lock(mutex_);
  control(axis).cause_present = false;
}

std::pair<double, double> SimTableBackend::limits(int axis) {
  std::lock_guard lock(mutex_);
  return {control(axis).max_rate_dps, control(axis).max_accel_dps2};
}

}  // namespace calstand::drivers
