#include <fmt/format.h>

#include <cmath>

#include "drivers/modbus_chamber_server.hpp"

namespace calstand::drivers {
namespace {

Result from_sim(const sim::Status& s) {
  return s.ok ? Result::success() : Result::failure(s.message);
}

}  // namespace

SimChamberBackend::SimChamberBackend(sim::SimWorld& world, std::mutex& world_mutex)
    : world_(world), mutex_(world_mutex) {
  std::lock_guard lock(mutex_);
  setpoint_c_ = world_.chamber_state().setpoint_c;
}

core::ChamberState SimChamberBackend::state() {
  std::lock_guard lock(mutex_);
  auto s = world_.chamber_state();
  // The simulated chamber forgets nothing, but a setpoint written in standby lives only here
  // until control starts.
  if (s.mode != core::ChamberMode::kActive) s.setpoint_c = setpoint_c_;
  return s;
}

Result SimChamberBackend::set_setpoint(double setpoint_c) {
  std::lock_guard lock(mutex_);
  auto& chamber = world_.chamber();
  if (world_.chamber_state().mode == core::ChamberMode::kActive) {
    if (auto r = from_sim(chamber.set_setpoint(setpoint_c, ramp_c_per_min_)); !r) return r;
  } else {
    const auto& p = chamber.params();
    if (!std::isfinite(setpoint_c) || setpoint_c < p.min_c || setpoint_c > p.max_c) {
      return Result::failure(
          fmt::format("setpoint {} degC is outside the chamber range [{}, {}] degC", setpoint_c,
                      p.min_c, p.max_c));
    }
  }
  setpoint_c_ = setpoint_c;
  return Result::success();
}

Result SimChamberBackend::set_mode(Mode mode) {
  std::lock_guard lock(mutex_);
  if (mode == Mode::kStandby) {
    world_.chamber().standby();
    return Result::success();
  }
  return from_sim(world_.chamber().set_setpoint(setpoint_c_, ramp_c_per_min_));
}

Result SimChamberBackend::set_ramp(double ramp_c_per_min) {
  if (!std::isfinite(ramp_c_per_min) || ramp_c_per_min <= 0.0) {
    return Result::failure(fmt::format("ramp {} degC/min must be positive", ramp_c_per_min));
  }
  std::lock_guard lock(mutex_);
  ramp_c_per_min_ = ramp_c_per_min;
  if (world_.chamber_state().mode == core::ChamberMode::kActive) {
    return from_sim(world_.chamber().set_setpoint(setpoint_c_, ramp_c_per_min_));
  }
  return Result::success();
}

}  // namespace calstand::drivers
