#include "sim/chamber_sim.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <utility>

namespace calstand::sim {
namespace {

/// exp(-dt / tau), the fraction of a first-order lag's error left after dt; a non-positive
/// time constant means no lag at all.
double lag_keep(double dt_s, double tau_s) { return tau_s > 0.0 ? std::exp(-dt_s / tau_s) : 0.0; }

}  // namespace

ChamberSim::ChamberSim(ChamberParams params, std::uint64_t seed)
    : params_(params),
      target_c_(params.ambient_c),
      ramp_c_per_min_(params.max_ramp_c_per_min),
      working_setpoint_c_(params.ambient_c),
      air_c_(params.ambient_c),
      imu_c_(params.ambient_c),
      normal_(seed) {
  // Start from the stationary distribution: the controller has been running before the
  // simulation started, so there is no start-up transient in the noise.
  noise_c_ = params_.control_noise_c * normal_.next();
}

Status ChamberSim::set_setpoint(double target_c, std::optional<double> ramp_c_per_min) {
  if (mode_ == core::ChamberMode::kFault) {
    return Status::refused(
        fmt::format("chamber in fault ({}): clear the fault first", fault_text_));
  }
  if (!std::isfinite(target_c)) {
    return Status::refused(fmt::format("setpoint {} degC is not finite", target_c));
  }
  if (target_c < params_.min_c || target_c > params_.max_c) {
    return Status::refused(
        fmt::format("setpoint {} degC is outside the chamber range [{}, {}] degC", target_c,
                    params_.min_c, params_.max_c));
  }
  const double ramp = ramp_c_per_min.value_or(params_.max_ramp_c_per_min);
  if (!std::isfinite(ramp) || ramp <= 0.0) {
    return Status::refused(fmt::format("ramp {} degC/min must be positive and finite", ramp));
  }
  if (mode_ != core::ChamberMode::kActive) working_setpoint_c_ = air_c_;
  target_c_ = target_c;
  ramp_c_per_min_ = std::min(ramp, params_.max_ramp_c_per_min);
  mode_ = core::ChamberMode::kActive;
  return Status::success();
}

void ChamberSim::standby() {
  // Standby must not hide a fault: only clear_fault() leaves kFault.
  if (mode_ == core::ChamberMode::kActive) mode_ = core::ChamberMode::kStandby;
}

void ChamberSim::inject_fault(std::string why) {
  mode_ = core::ChamberMode::kFault;
  fault_text_ = why.empty() ? std::string("unspecified fault") : std::move(why);
}

void ChamberSim::clear_fault() {
  if (mode_ != core::ChamberMode::kFault) return;
  mode_ = core::ChamberMode::kStandby;
  fault_text_.clear();
}

void ChamberSim::update_step_factors(double dt_s) {
  factors_dt_s_ = dt_s;
  air_keep_ = lag_keep(dt_s, params_.air_time_constant_s);
  imu_keep_ = lag_keep(dt_s, params_.imu_time_constant_s);
  noise_keep_ = lag_keep(dt_s, params_.control_noise_tau_s);
  // Drive variance sigma^2 (1 - keep^2) keeps the stationary sigma whatever dt is.
  noise_drive_c_ = params_.control_noise_c * std::sqrt(1.0 - noise_keep_ * noise_keep_);
}

void ChamberSim::step(double dt_s) {
  if (!(dt_s > 0.0) || !std::isfinite(dt_s)) return;
  if (dt_s != factors_dt_s_) update_step_factors(dt_s);

  const bool controlling = mode_ == core::ChamberMode::kActive;
  if (controlling) {
    const double ramp_step = ramp_c_per_min_ / 60.0 * dt_s;
    working_setpoint_c_ += std::clamp(target_c_ - working_setpoint_c_, -ramp_step, ramp_step);
  }
  const double goal_c = controlling ? working_setpoint_c_ : params_.ambient_c;
  // Exact lag with the goal held over the step, then the chamber's own rate limit (heater and
  // compressor power), which binds on big steps such as a drift back from an extreme.
  const double max_change = params_.max_ramp_c_per_min / 60.0 * dt_s;
  const double lagged = goal_c + (air_c_ - goal_c) * air_keep_;
  air_c_ += std::clamp(lagged - air_c_, -max_change, max_change);
  if (!controlling) working_setpoint_c_ = air_c_;

  noise_c_ = noise_keep_ * noise_c_ + noise_drive_c_ * normal_.next();

  const double imu_goal_c = air_temperature_c() + params_.imu_self_heating_c;
  imu_c_ = imu_goal_c + (imu_c_ - imu_goal_c) * imu_keep_;
  imu_rate_c_per_min_ = params_.imu_time_constant_s > 0.0
                            ? (imu_goal_c - imu_c_) / params_.imu_time_constant_s * 60.0
                            : 0.0;
}

double ChamberSim::air_temperature_c() const { return air_c_ + noise_c_; }

core::ChamberState ChamberSim::state(double time_s) const {
  core::ChamberState s;
  s.time_s = time_s;
  s.air_temperature_c = air_temperature_c();
  s.setpoint_c = target_c_;
  s.mode = mode_;
  s.fault = mode_ == core::ChamberMode::kFault;
  s.fault_text = s.fault ? fault_text_ : std::string();
  return s;
}

}  // namespace calstand::sim
