#pragma once
// Builds a solver::RunData in memory from the IMU simulator: each step is a table state held
// for a while (a position, or constant rates with the angles advancing) at a temperature, so the
// fit can be checked against the simulator's truth without a database.

#include <fmt/format.h>

#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

#include "sim/imu_sim.hpp"
#include "sim/noise.hpp"
#include "sim/spec_sheet.hpp"
#include "solver/step_summary.hpp"

namespace calstand::solver::testing {

struct SimStep {
  double outer_deg = 0.0;
  double inner_deg = 0.0;
  double outer_rate_dps = 0.0;
  double inner_rate_dps = 0.0;
  double temperature_c = 25.0;
  double temperature_rate_cpm = 0.0;  ///< the IMU temperature ramps at this rate in the step
  double duration_s = 20.0;
  /// Time before the step that is not recorded (a move, a settle, a soak) [s]: the IMU's noise
  /// processes run on through it, as they do on a station.
  double gap_before_s = 0.0;
};

/// The classical model of both triads (bias, scale factor, misalignment) with the Earth rate.
inline constexpr const char* kBaseModel =
    "gyro_bias,gyro_scale,gyro_misalignment,earth_rate,accel_bias,accel_scale,accel_misalignment";

inline core::Site wuhan_site() {
  core::Site site;
  site.latitude_deg = 30.5288;
  site.height_m = 25.0;
  return site;
}

/// A truth with white noise only (ARW/VRW densities in contract units per sqrt(Hz)).
inline sim::ImuTruth white_noise_truth(double gyro_dps_rthz = 2e-3, double accel_rthz = 5e-4,
                                       double rate_hz = 100.0) {
  sim::ImuTruth t;
  t.sample_rate_hz = rate_hz;
  t.gyro_noise.white = Eigen::Vector3d::Constant(gyro_dps_rthz);
  t.accel_noise.white = Eigen::Vector3d::Constant(accel_rthz);
  t.latency_s = 0.0;
  return t;
}

/// Draws bias, scale factor and misalignment of both triads from `normal` (LN200-class sizes:
/// 3e-3 deg/s, 5e-3 m/s^2, 300 ppm, 1 mrad) into `t`.
inline void draw_classical_errors(sim::ImuTruth& t, sim::NormalSource& normal) {
  for (int i = 0; i < 3; ++i) {
    t.gyro_bias[i] = 3e-3 * normal.next();
    t.gyro_scale[i] = 300.0 * normal.next();
    t.accel_bias[i] = 5e-3 * normal.next();
    t.accel_scale[i] = 300.0 * normal.next();
    for (int j = 0; j < 3; ++j) {
      if (i == j) continue;
      t.gyro_misalignment(i, j) = 1e-3 * normal.next();
      t.accel_misalignment(i, j) = 1e-3 * normal.next();
    }
  }
}

/// A unit drawn from a built-in spec sheet ("ln200", "adis16488": every error term and wander
/// the sheet has) at `rate_hz` to keep a test quick (noise densities are per sqrt(Hz), the
/// wander does not depend on the rate), with the turn-on bias folded out so that the fitted bias
/// is the truth's (it is a constant within a run).
inline sim::ImuTruth datasheet_unit(const char* sheet, std::uint64_t seed, double rate_hz = 100.0) {
  sim::ImuTruth t = sim::truth_from_spec(*sim::builtin_spec(sheet), sheet, seed);
  t.gyro_noise.turn_on_bias.setZero();
  t.accel_noise.turn_on_bias.setZero();
  t.sample_rate_hz = rate_hz;
  if (t.gyro_bandwidth_hz >= rate_hz / 2.0) t.gyro_bandwidth_hz = 0.0;
  if (t.accel_bandwidth_hz >= rate_hz / 2.0) t.accel_bandwidth_hz = 0.0;
  return t;
}

/// A MEMS part whose Gauss-Markov bias moves a 30 s step mean more than its white noise does
/// (gyro 3x, accelerometer 4x), with LN200-class calibratable errors.
inline sim::ImuTruth mems_gauss_markov_unit(std::uint64_t seed) {
  sim::ImuTruth t = white_noise_truth(5e-3, 1e-3, 100.0);      // 0.3 deg/sqrt(h), 100 ug/sqrt(Hz)
  t.gyro_noise.gauss_markov_sigma.setConstant(10.0 / 3600.0);  // 10 deg/h
  t.accel_noise.gauss_markov_sigma.setConstant(700e-6 * 9.80665);  // 700 ug
  t.gyro_noise.gauss_markov_tau_s = 300.0;
  t.accel_noise.gauss_markov_tau_s = 300.0;
  sim::NormalSource n(seed);
  draw_classical_errors(t, n);
  return t;
}

/// The catalogue terms (and temperature orders) the truth has, with the Earth rate and both
/// biases: the model that should fit it to the noise.
inline std::string true_terms(const sim::ImuTruth& truth) {
  std::set<std::string> terms{"gyro_bias", "accel_bias", "earth_rate"};
  std::map<std::string, int> orders;
  for (const auto& [name, value] : truth.nonzero_parameters()) {
    const std::string term = name.substr(0, name.find('.'));
    if (term.find("temp_bias") != std::string::npos) {
      orders[term] = std::max(orders[term], name.back() - '0');
    } else {
      terms.insert(term);
    }
  }
  std::string out;
  for (const auto& t : terms) out += (out.empty() ? "" : ",") + t;
  for (const auto& [t, k] : orders) out += fmt::format(",{}:{}", t, k);
  return out;
}

inline RunData simulate_run(const sim::ImuTruth& truth, const std::vector<SimStep>& steps,
                            std::uint64_t seed,
                            const Eigen::Vector2d& tilt_rad = Eigen::Vector2d::Zero(),
                            const core::TableGeometry& geometry = {}) {
  RunData data;
  data.setup.site = wuhan_site();
  data.setup.geometry = geometry;
  data.setup.temperature_ref_c = truth.temperature_ref_c;
  data.setup.device = "imu0";
  sim::ImuSim imu(truth, geometry, data.setup.site, tilt_rad, seed);
  imu.power_on(0.0);
  const double dt = 1.0 / truth.sample_rate_hz;
  double t = 0.0;
  for (std::size_t k = 0; k < steps.size(); ++k) {
    const SimStep& st = steps[k];
    // Unrecorded time: the samples are drawn (so the bias wanders on) and dropped.
    const auto gap = static_cast<std::size_t>(st.gap_before_s * truth.sample_rate_hz);
    sim::TableKinematics rest;
    rest.outer_deg = st.outer_deg;
    rest.inner_deg = st.inner_deg;
    for (std::size_t i = 0; i < gap; ++i, t += dt) imu.sample(t, rest, st.temperature_c);
    store::StepData step;
    step.step.index = k;
    step.step.label = "step " + std::to_string(k);
    step.step.status = store::StepStatus::kCompleted;
    const auto n = static_cast<std::size_t>(st.duration_s * truth.sample_rate_hz);
    for (std::size_t i = 0; i < n; ++i, t += dt) {
      const double ts = static_cast<double>(i) * dt;
      sim::TableKinematics kin;
      kin.outer_deg = st.outer_deg + st.outer_rate_dps * ts;
      kin.inner_deg = st.inner_deg + st.inner_rate_dps * ts;
      kin.outer_rate_dps = st.outer_rate_dps;
      kin.inner_rate_dps = st.inner_rate_dps;
      const double temp =
          st.temperature_c + st.temperature_rate_cpm * (ts - 0.5 * st.duration_s) / 60.0;
      core::ImuSample s = imu.sample(t, kin, temp);
      s.receive_time_s = t;
      step.samples.push_back(s);
      step.table.push_back({kin.outer_deg, kin.inner_deg, kin.outer_rate_dps, kin.inner_rate_dps});
    }
    data.steps.push_back(std::move(step));
  }
  return data;
}

/// Six static positions (each body axis up and down) on the default table (outer axis North,
/// inner axis Up at zero) at `temperature_c`.
inline std::vector<SimStep> six_positions(double temperature_c = 25.0, double duration_s = 20.0) {
  // outer 0: z up; outer 180: z down; outer +-90 turns z to -E/+E ... the inner angle then
  // selects which of x and y points up.
  const double positions[6][2] = {{0, 0}, {180, 0}, {90, 0}, {-90, 0}, {90, 90}, {-90, 90}};
  std::vector<SimStep> out;
  for (const auto& p : positions) {
    SimStep s;
    s.outer_deg = p[0];
    s.inner_deg = p[1];
    s.temperature_c = temperature_c;
    s.duration_s = duration_s;
    out.push_back(s);
  }
  return out;
}

/// Rate steps about the inner axis at each rate (both signs) with the inner axis vertical,
/// horizontal (outer 90) and along the other horizontal (outer 90, inner turned) so that each
/// body axis sees rate.
inline std::vector<SimStep> rate_steps(const std::vector<double>& rates_dps,
                                       double temperature_c = 25.0, double duration_s = 36.0) {
  std::vector<SimStep> out;
  for (double r : rates_dps) {
    for (double sign : {1.0, -1.0}) {
      SimStep z;  // inner axis Up: body z
      z.inner_rate_dps = sign * r;
      z.temperature_c = temperature_c;
      z.duration_s = duration_s;
      out.push_back(z);
      SimStep x = z;  // outer axis (North) with inner 90: rate about body -x / ...
      x.inner_rate_dps = 0.0;
      x.outer_rate_dps = sign * r;
      x.inner_deg = 0.0;
      out.push_back(x);
      SimStep y = x;
      y.inner_deg = 90.0;
      out.push_back(y);
    }
  }
  return out;
}

}  // namespace calstand::solver::testing
