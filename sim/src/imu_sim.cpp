#include "sim/imu_sim.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/rotation.hpp"

namespace calstand::sim {

ImuInputModel::ImuInputModel(const ImuTruth& truth, const core::TableGeometry& geometry,
                             const core::Site& site, const Eigen::Vector2d& table_tilt_rad)
    : outer_axis_(geometry.outer_axis.normalized()),
      inner_axis_(geometry.inner_axis.normalized()),
      mount_C_PB_(geometry.mount_C_PB),
      lever_arm_m_(truth.accel_lever_arm) {
  // The tilted base: a vector fixed in the base reads v_L = R_tilt v_base, so quantities given
  // in L (gravity, Earth rate) enter the table's frame through R_tilt^T.
  const Eigen::Vector3d tilt_vector(table_tilt_rad.x(), table_tilt_rad.y(), 0.0);
  const double tilt = tilt_vector.norm();
  const Eigen::Matrix3d R_tilt_T =
      tilt > 0.0 ? Eigen::Matrix3d(core::axis_angle(tilt_vector, tilt).transpose())
                 : Eigen::Matrix3d::Identity();
  force_base_mps2_ = R_tilt_T * site.specific_force_level();
  earth_base_dps_ = R_tilt_T * site.earth_rate_level_radps() * core::kRadToDeg;
}

ImuInputs ImuInputModel::operator()(const TableKinematics& k, double temperature_c) const {
  // Same formulas as core::TableGeometry, with each axis rotation computed once (and not at
  // all while the angles stay the same).
  if (k.outer_deg != cache_.outer_deg || k.inner_deg != cache_.inner_deg) {
    const Eigen::Matrix3d R_outer =
        Eigen::AngleAxisd(k.outer_deg * core::kDegToRad, outer_axis_).toRotationMatrix();
    const Eigen::Matrix3d R_inner =
        Eigen::AngleAxisd(k.inner_deg * core::kDegToRad, inner_axis_).toRotationMatrix();
    cache_.C_BL = (R_outer * R_inner * mount_C_PB_).transpose();
    cache_.inner_now = R_outer * inner_axis_;
    cache_.outer_deg = k.outer_deg;
    cache_.inner_deg = k.inner_deg;
  }
  const Eigen::Matrix3d& C_BL = cache_.C_BL;
  const Eigen::Vector3d& inner_now = cache_.inner_now;
  const Eigen::Vector3d table_rate_dps =
      k.outer_rate_dps * outer_axis_ + k.inner_rate_dps * inner_now;

  ImuInputs in;
  in.rate_dps = C_BL * (table_rate_dps + earth_base_dps_);
  in.force_mps2 = C_BL * force_base_mps2_;
  in.temperature_c = temperature_c;
  if (!lever_arm_m_.isZero()) {
    const Eigen::Vector3d table_accel_dps2 =
        k.outer_accel_dps2 * outer_axis_ + k.inner_accel_dps2 * inner_now +
        k.inner_rate_dps * (k.outer_rate_dps * core::kDegToRad * outer_axis_).cross(inner_now);
    const Eigen::Vector3d wt = C_BL * table_rate_dps * core::kDegToRad;
    const Eigen::Vector3d alpha = C_BL * table_accel_dps2 * core::kDegToRad;
    in.force_mps2 += wt.cross(wt.cross(lever_arm_m_)) + alpha.cross(lever_arm_m_);
  }
  return in;
}

ImuInputs imu_inputs(const ImuTruth& truth, const core::TableGeometry& geometry,
                     const core::Site& site, const Eigen::Vector2d& table_tilt_rad,
                     const TableKinematics& k, double temperature_c) {
  return ImuInputModel(truth, geometry, site, table_tilt_rad)(k, temperature_c);
}

double ImuSim::Channel::noise(double& slow) {
  // The total is summed in the same order as before the slow part was reported, so a seed
  // gives the same samples bit for bit.
  double n = 0.0;
  slow = 0.0;
  if (white) n += white->next();
  if (bias_instability) {
    const double x = bias_instability->next();
    n += x;
    slow += x;
  }
  if (random_walk) {
    const double x = random_walk->next();
    n += x;
    slow += x;
  }
  if (gauss_markov) {
    const double x = gauss_markov->next();
    n += x;
    slow += x;
  }
  return n;
}

ImuSim::ImuSim(ImuTruth truth, core::TableGeometry geometry, core::Site site,
               const Eigen::Vector2d& table_tilt_rad, std::uint64_t seed)
    : truth_(std::move(truth)),
      geometry_(std::move(geometry)),
      site_(std::move(site)),
      input_model_(truth_, geometry_, site_, table_tilt_rad),
      seed_(seed),
      turn_on_draw_(derive_seed(seed, "turn-on-bias")),
      turn_on_scale_draw_(derive_seed(seed, "turn-on-scale")) {
  if (!(truth_.sample_rate_hz > 0.0) || !std::isfinite(truth_.sample_rate_hz)) {
    throw std::invalid_argument("IMU " + truth_.name + ": sample_rate_hz must be positive");
  }
  if (truth_.sequence_modulus < 2) {
    throw std::invalid_argument("IMU " + truth_.name + ": sequence_modulus must be >= 2");
  }
  build_channels();
}

void ImuSim::build_channels() {
  const double dt = sample_period_s();
  for (std::size_t c = 0; c < 6; ++c) {
    const TriadNoise& n = c < 3 ? truth_.gyro_noise : truth_.accel_noise;
    const double bandwidth_hz = c < 3 ? truth_.gyro_bandwidth_hz : truth_.accel_bandwidth_hz;
    const int axis = static_cast<int>(c % 3);
    const std::string stream = c < 3 ? "gyro" : "accel";
    Channel& ch = channels_[c];
    if (n.white[axis] > 0.0) {
      ch.white.emplace(n.white[axis], truth_.sample_rate_hz,
                       derive_seed(seed_, stream + "-white", c));
    }
    if (n.bias_instability[axis] > 0.0) {
      ch.bias_instability.emplace(n.bias_instability[axis], dt,
                                  derive_seed(seed_, stream + "-bias-instability", c));
    }
    if (n.random_walk[axis] > 0.0) {
      ch.random_walk.emplace(n.random_walk[axis], dt, derive_seed(seed_, stream + "-walk", c));
    }
    if (n.gauss_markov_sigma[axis] > 0.0) {
      ch.gauss_markov.emplace(n.gauss_markov_sigma[axis], n.gauss_markov_tau_s, dt,
                              derive_seed(seed_, stream + "-gauss-markov", c));
    }
    if (bandwidth_hz > 0.0 && bandwidth_hz < truth_.sample_rate_hz / 2.0) {
      ch.low_pass.emplace(truth_.filter_order, bandwidth_hz, truth_.sample_rate_hz);
    }
    ch.quantizer = Quantizer(n.quantization);
  }
}

void ImuSim::power_on(double time_s, bool warm) {
  transient_running_ = !warm;
  for (int i = 0; i < 3; ++i)
    turn_on_gyro_[i] = turn_on_draw_.next() * truth_.gyro_noise.turn_on_bias[i];
  for (int i = 0; i < 3; ++i) {
    turn_on_accel_[i] = turn_on_draw_.next() * truth_.accel_noise.turn_on_bias[i];
  }
  for (int i = 0; i < 3; ++i) {
    turn_on_gyro_scale_ppm_[i] =
        turn_on_scale_draw_.next() * truth_.gyro_noise.turn_on_scale_ppm[i];
    turn_on_accel_scale_ppm_[i] =
        turn_on_scale_draw_.next() * truth_.accel_noise.turn_on_scale_ppm[i];
  }
  powered_ = true;
  filter_primed_ = false;
  power_on_time_s_ = time_s;
  sequence_ = 0;
  ++power_cycles_;
}

double ImuSim::hysteresis_branch(double temperature_c) {
  const double half = 0.5 * truth_.hysteresis_width_c;
  // The play operator starts where the unit is, in the middle of its band.
  if (!play_started_) {
    play_c_ = temperature_c;
    play_started_ = true;
  }
  play_c_ = std::clamp(play_c_, temperature_c - half, temperature_c + half);
  return (temperature_c - play_c_) / truth_.hysteresis_width_c;  // -1/2 .. +1/2
}

std::pair<Eigen::Vector3d, Eigen::Vector3d> ImuSim::power_on_transient(double time_s) const {
  if (!transient_running_ || time_s < power_on_time_s_) {
    return {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  }
  const double decay = std::exp(-(time_s - power_on_time_s_) / truth_.power_on_time_constant_s);
  return {truth_.gyro_power_on_bias * decay, truth_.accel_power_on_bias * decay};
}

std::pair<Eigen::Vector3d, Eigen::Vector3d> ImuSim::noise_free_reading(const TableKinematics& table,
                                                                       double temperature_c) const {
  const ImuInputs in = input_model_(table, temperature_c);
  const auto [gyro_error, accel_error] = deterministic_errors(truth_, in);
  return {in.rate_dps + gyro_error + turn_on_gyro_ + turn_on_scale_error(in.rate_dps, true),
          in.force_mps2 + accel_error + turn_on_accel_ + turn_on_scale_error(in.force_mps2, false)};
}

core::ImuSample ImuSim::sample(double time_s, const TableKinematics& table, double temperature_c) {
  return sample(time_s, input_model_(table, temperature_c));
}

core::ImuSample ImuSim::sample(double time_s, const ImuInputs& in) {
  const double temperature_c = in.temperature_c;
  const auto [gyro_error, accel_error] = deterministic_errors(truth_, in);
  const auto [gyro_transient, accel_transient] = power_on_transient(time_s);
  const double hysteresis = hysteresis_branch(temperature_c);
  const Eigen::Vector3d gyro_turn_on_scale = turn_on_scale_error(in.rate_dps, true);
  const Eigen::Vector3d accel_turn_on_scale = turn_on_scale_error(in.force_mps2, false);

  std::array<double, 6> value{};
  for (int i = 0; i < 3; ++i) {
    value[static_cast<std::size_t>(i)] = in.rate_dps[i] + gyro_error[i] + turn_on_gyro_[i] +
                                         gyro_turn_on_scale[i] + gyro_transient[i] +
                                         hysteresis * truth_.gyro_hysteresis_bias[i];
    value[static_cast<std::size_t>(i) + 3] = in.force_mps2[i] + accel_error[i] + turn_on_accel_[i] +
                                             accel_turn_on_scale[i] + accel_transient[i] +
                                             hysteresis * truth_.accel_hysteresis_bias[i];
  }
  for (std::size_t c = 0; c < 6; ++c) {
    Channel& ch = channels_[c];
    double v = value[c] + ch.noise(last_slow_noise_[c]);
    if (ch.low_pass) {
      // Start the filter settled on the first sample after power-up, not from zero.
      if (!filter_primed_) ch.low_pass->reset(v);
      v = ch.low_pass->filter(v);
    }
    value[c] = ch.quantizer.apply(v);
  }
  filter_primed_ = true;

  core::ImuSample s;
  s.device_time_s = (time_s - power_on_time_s_) * (1.0 + 1e-6 * truth_.clock_drift_ppm);
  s.receive_time_s = time_s + truth_.latency_s;
  s.sequence = sequence_;
  sequence_ = (sequence_ + 1) % truth_.sequence_modulus;
  s.gyro_dps = Eigen::Vector3d(value[0], value[1], value[2]);
  s.accel_mps2 = Eigen::Vector3d(value[3], value[4], value[5]);
  s.temperature_c = temperature_c;
  return s;
}

}  // namespace calstand::sim
