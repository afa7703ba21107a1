// Temperature calibration from two ramps (library procedure thermal-ramp: the table indexes and
// turns while the chamber heats and cools at 1 degC/min) on an ADIS16488-class unit drawn from
// its sheet (bias, scale and their temperature coefficients, flicker bias instability, random
// walks, g-sensitivity), at one of its decimated output rates. The unit's own temperature lags
// the air by its 600 s thermal time constant, 10 degC at this ramp rate. The fit reads the
// IMU's temperature, so heating and cooling each recover the truth's temperature terms and
// agree with each other; read against the air temperature instead, they disagree by the lag.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include "in_process_run.hpp"
#include "sim/imu_truth.hpp"
#include "sim/sim_world.hpp"
#include "sim/spec_sheet.hpp"
#include "solver/fit.hpp"
#include "solver/model.hpp"
#include "solver/noise_estimate.hpp"
#include "solver/step_summary.hpp"
#include "store/database.hpp"
#include "store/run_store.hpp"

namespace calstand {
namespace {

// The classical model, the sheet's g-sensitivity, and the temperature terms the sheet gives.
constexpr const char* kModel =
    "gyro_bias,gyro_scale,gyro_misalignment,gyro_g_sensitivity,earth_rate,accel_bias,"
    "accel_scale,accel_misalignment,gyro_temp_bias,accel_temp_bias,gyro_temp_scale,"
    "accel_temp_scale";

const std::vector<std::string> kTemperatureTerms = {
    "gyro_temp_bias.x1",  "gyro_temp_bias.y1",  "gyro_temp_bias.z1",  "accel_temp_bias.x1",
    "accel_temp_bias.y1", "accel_temp_bias.z1", "gyro_temp_scale.x",  "gyro_temp_scale.y",
    "gyro_temp_scale.z",  "accel_temp_scale.x", "accel_temp_scale.y", "accel_temp_scale.z"};

/// The ADIS16488-class station: the embedded station with its IMU drawn from the shipped sheet
/// with `seed` (also the seed of its noise), decimated to 246 Hz (2460 SPS / 10, the part's
/// DEC_RATE register) behind a 100 Hz output filter.
core::StationConfig adis_station(std::uint64_t seed, sim::ImuTruth& truth) {
  core::StationConfig station = sim::default_station();
  station.seed = seed;
  truth = sim::truth_from_spec(*sim::builtin_spec("adis16488"), "adis16488", seed);
  truth.sample_rate_hz = 246.0;
  truth.gyro_bandwidth_hz = 100.0;
  truth.accel_bandwidth_hz = 100.0;
  station.imus[0].model.clear();
  station.imus[0].truth = sim::imu_truth_to_json(truth);
  return station;
}

/// The run's steps whose label starts with `prefix` ("heating", "cooling").
solver::RunData steps_labelled(const solver::RunData& data, const std::string& prefix) {
  solver::RunData out{data.setup, {}};
  for (const auto& s : data.steps) {
    if (s.step.label.rfind(prefix, 0) == 0) out.steps.push_back(s);
  }
  return out;
}

/// `data` with every sample's temperature replaced by the chamber air's at its receive time
/// (linear between telemetry rows): what a fit on the air temperature would see.
solver::RunData with_air_temperature(solver::RunData data,
                                     const std::vector<core::ChamberState>& air) {
  for (auto& s : data.steps) {
    for (auto& sample : s.samples) {
      const auto after =
          std::lower_bound(air.begin(), air.end(), sample.receive_time_s,
                           [](const core::ChamberState& c, double t) { return c.time_s < t; });
      if (after == air.begin() || after == air.end()) {
        sample.temperature_c = (after == air.end() ? air.back() : air.front()).air_temperature_c;
        continue;
      }
      const auto before = after - 1;
      const double w = (sample.receive_time_s - before->time_s) / (after->time_s - before->time_s);
      sample.temperature_c =
          before->air_temperature_c + w * (after->air_temperature_c - before->air_temperature_c);
    }
  }
  return data;
}

std::map<std::string, solver::FittedParameter> fitted(const solver::FitResult& fit) {
  std::map<std::string, solver::FittedParameter> out;
  for (const auto& p : fit.parameters) out[p.name] = p;
  return out;
}

double mean_temperature(const solver::RunData& data) {
  double sum = 0.0;
  std::size_t n = 0;
  for (const auto& s : data.steps) {
    for (const auto& sample : s.samples) sum += sample.temperature_c, ++n;
  }
  return sum / static_cast<double>(n);
}

class ThermalRamp : public ::testing::TestWithParam<std::uint64_t> {};

TEST_P(ThermalRamp, HeatingAndCoolingEachRecoverTheTemperatureTermsOnTheImuTemperature) {
  sim::ImuTruth truth;
  const core::StationConfig station = adis_station(GetParam(), truth);
  const std::string db_path = testing::fresh_db("thermal_ramp_" + std::to_string(GetParam()));
  // Two 50 degC ramps of 50 min, each covered by 13 cycles of about 4 min.
  const std::int64_t run_id = testing::run_procedure(
      "thermal-ramp",
      {"low_c=0", "high_c=50", "ramp_c_per_min=1", "cycles=13", "soak_s=600", "final_c=25"},
      db_path, station);
  if (HasFailure()) return;
  store::Database db(db_path);
  const solver::RunData data = solver::load_run_data(db, run_id);
  const solver::Model model = solver::Model::parse(kModel);

  // The whole run: every parameter determined; each temperature term within 4 sigma of the
  // truth, with a sigma small against the sheet's figure, so that the check has power.
  const solver::FitResult both = solver::fit_run(data, model);
  for (const auto& u : both.unidentifiable) ADD_FAILURE() << u.name << ": " << u.reason;
  const auto all = fitted(both);
  for (const std::string& name : kTemperatureTerms) {
    const solver::FittedParameter& p = all.at(name);
    const double want = truth.parameter(name);
    std::cout << name << ": fitted " << p.value << " +- " << p.sigma << ", truth " << want << " ["
              << p.unit << "]\n";
    EXPECT_LT(std::abs(p.value - want), 4.0 * p.sigma) << name;
  }
  // Sheet figures in contract units: 0.0025 deg/s/degC, 0.1 mg/degC, 35 ppm/degC.
  for (const char* a : {"x1", "y1", "z1"}) {
    EXPECT_LT(all.at(std::string("gyro_temp_bias.") + a).sigma, 0.1 * 0.0025) << a;
    EXPECT_LT(all.at(std::string("accel_temp_bias.") + a).sigma, 0.1 * 0.1e-3 * 9.80665) << a;
  }
  for (const char* a : {"x", "y", "z"}) {
    EXPECT_LT(all.at(std::string("gyro_temp_scale.") + a).sigma, 0.2 * 35.0) << a;
    EXPECT_LT(all.at(std::string("accel_temp_scale.") + a).sigma, 0.2 * 35.0) << a;
  }

  // The unit lags the air: hotter air while heating, colder while cooling.
  store::RunStore runs(db);
  const std::vector<core::ChamberState> air = runs.chamber_telemetry(run_id);
  ASSERT_GT(air.size(), 100u);
  const solver::RunData heating = steps_labelled(data, "heating");
  const solver::RunData cooling = steps_labelled(data, "cooling");
  ASSERT_EQ(heating.steps.size(), cooling.steps.size());
  ASSERT_EQ(heating.steps.size(), 13u * 12u);
  const double lag_heating_c =
      mean_temperature(with_air_temperature(heating, air)) - mean_temperature(heating);
  const double lag_cooling_c =
      mean_temperature(with_air_temperature(cooling, air)) - mean_temperature(cooling);
  std::cout << "air minus IMU: heating " << lag_heating_c << " degC, cooling " << lag_cooling_c
            << " degC\n";
  // The lag builds up over the first time constant of each ramp, and the unit's self-heating
  // (3 degC) keeps it above the air: the loop's width is what a fit on the air would miss.
  EXPECT_GT(lag_heating_c, 0.0);
  EXPECT_LT(lag_cooling_c, 0.0);
  const double loop_width_c = lag_heating_c - lag_cooling_c;
  EXPECT_GT(loop_width_c, 10.0);

  // Each ramp alone recovers the temperature terms, and the two agree.
  const auto up = fitted(solver::fit_run(heating, model));
  const auto down = fitted(solver::fit_run(cooling, model));
  for (const std::string& name : kTemperatureTerms) {
    const double want = truth.parameter(name);
    EXPECT_LT(std::abs(up.at(name).value - want), 4.0 * up.at(name).sigma) << "heating " << name;
    EXPECT_LT(std::abs(down.at(name).value - want), 4.0 * down.at(name).sigma)
        << "cooling " << name;
  }
  // On the air temperature the gyro bias at the reference temperature differs between the
  // ramps by about the coefficient times the loop's width; on the unit's own it does not.
  const auto up_air = fitted(solver::fit_run(with_air_temperature(heating, air), model));
  const auto down_air = fitted(solver::fit_run(with_air_temperature(cooling, air), model));
  int shown = 0;
  for (const char* a : {"x", "y", "z"}) {
    const std::string bias = std::string("gyro_bias.") + a;
    const double coefficient = truth.parameter(std::string("gyro_temp_bias.") + a + "1");
    const double on_imu = up.at(bias).value - down.at(bias).value;
    const double on_air = up_air.at(bias).value - down_air.at(bias).value;
    std::cout << bias << ": heating - cooling " << on_imu << " +- "
              << std::hypot(up.at(bias).sigma, down.at(bias).sigma) << " deg/s on the IMU's "
              << "temperature, " << on_air << " on the air's; coefficient x loop width "
              << coefficient * loop_width_c << "\n";
    EXPECT_LT(std::abs(on_imu), 4.0 * std::hypot(up.at(bias).sigma, down.at(bias).sigma))
        << bias << ": heating and cooling on the IMU temperature";
    // Where the coefficient is large enough to show (a quarter of the sheet's 0.0025).
    if (std::abs(coefficient) < 0.25 * 0.0025) continue;
    ++shown;
    EXPECT_GT(std::abs(on_air), 0.5 * std::abs(coefficient) * loop_width_c) << bias;
  }
  EXPECT_GE(shown, 1);
  testing::remove_db(db_path);
}

INSTANTIATE_TEST_SUITE_P(Seeds, ThermalRamp, ::testing::Values(3u, 11u));

}  // namespace
}  // namespace calstand
