#pragma once
// What the export tests share: calibration records made by hand with known numbers (checked by
// the record's own schema through solver::read_calibration), and calstand's own correction of
// a raw sample (solver::Corrector, as `calstand apply` does), against which each target's
// correction formula, applied to the numbers read back from its file, is compared.

#include <Eigen/Core>
#include <cmath>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "solver/calibration_record.hpp"
#include "solver/model.hpp"
#include "store/step_data.hpp"

namespace calstand::testing {

inline constexpr double kExportRadPerDeg = 3.14159265358979323846 / 180.0;

/// A number as PX4 and ArduPilot hold it: their parameters are float32.
inline double as_float32(double v) { return static_cast<double>(static_cast<float>(v)); }

/// How far a target's correction may differ from calstand's because its parameters are float32
/// (2 ulp of the raw reading, whose scale factor is stored in 24 bits) [same unit as `raw`].
inline double float32_tolerance(double raw_magnitude) { return 2.5e-7 * raw_magnitude + 1e-10; }

/// What a hand-made record holds besides its parameters.
struct HandRecord {
  std::string model;  ///< --model text, e.g. "gyro_bias,gyro_temp_bias:3"
  std::vector<std::string> customs;
  std::map<std::string, double> values;             ///< parameter name -> value (contract units)
  std::map<std::string, std::string> undetermined;  ///< name -> reason
  nlohmann::json temperature_ref_c = 25.0;
  nlohmann::json valid_min_c = -10.0;
  nlohmann::json valid_max_c = 60.0;
  nlohmann::json noise;  ///< null: none
  std::string serial = "SN-0042";
  std::vector<int> runs = {7};
};

/// The record JSON of `h`: every value with a sigma of 1 % of it and the model's unit.
inline nlohmann::json hand_record_json(const HandRecord& h) {
  const solver::Model model = solver::Model::parse(h.model, h.customs);
  nlohmann::json r;
  r["format"] = "calstand-calibration/1";
  r["device"] = {{"name", "imu0"}, {"model", "test-imu"}, {"serial", h.serial}};
  r["station"] = "export-test-station";
  r["runs"] = h.runs;
  r["procedure"] = {{"name", "thermal-calibration"}, {"sha256", std::string(64, 'a')}};
  r["model"] = nlohmann::json::array();
  for (const auto& t : model.terms()) r["model"].push_back(t.name);
  r["custom_terms"] = h.customs;
  r["parameters"] = nlohmann::json::array();
  for (const auto& p : model.parameters()) {
    const auto v = h.values.find(p.name);
    if (v == h.values.end()) continue;
    r["parameters"].push_back({{"name", p.name},
                               {"value", v->second},
                               {"sigma", 0.01 * std::abs(v->second)},
                               {"unit", p.unit}});
  }
  r["unidentifiable"] = nlohmann::json::array();
  for (const auto& [name, reason] : h.undetermined) {
    r["unidentifiable"].push_back({{"name", name}, {"reason", reason}});
  }
  r["fit"] = {{"chi2_dof", 1.05},
              {"dof", 40},
              {"residual_rms", {{"gyro", 0.001}, {"accel", 0.0005}}},
              {"noise_floor", {{"gyro", {0.001, 0.001, 0.001}}, {"accel", {1e-4, 1e-4, 1e-4}}}}};
  if (!h.noise.is_null()) r["noise"] = h.noise;
  r["temperature_ref_c"] = h.temperature_ref_c;
  r["valid_temperature_c"] = {{"min", h.valid_min_c}, {"max", h.valid_max_c}};
  r["created_utc"] = "2024-05-06T07:08:09Z";
  r["software"] = "calstand test";
  return r;
}

/// `h` read as `calstand apply` reads a record (schema and catalogue checked).
inline solver::Calibration hand_calibration(const HandRecord& h) {
  return solver::read_calibration(hand_record_json(h), "hand-record.json");
}

/// calstand's correction of one raw sample at `temperature_c`: gyro [deg/s], accel [m/s^2].
struct CalstandCorrected {
  Eigen::Vector3d gyro_dps;
  Eigen::Vector3d accel_mps2;
};
inline CalstandCorrected calstand_correct(const solver::Calibration& calibration,
                                          const Eigen::Vector3d& raw_gyro_dps,
                                          const Eigen::Vector3d& raw_accel_mps2,
                                          double temperature_c) {
  // A default setup: the sensor terms need no table, and the Corrector uses the record's T_ref.
  const solver::Corrector corrector(calibration, solver::RunSetup{});
  store::StepData step;
  core::ImuSample s;
  s.gyro_dps = raw_gyro_dps;
  s.accel_mps2 = raw_accel_mps2;
  s.temperature_c = temperature_c;
  step.samples = {s};
  step.table = {store::TableSample{}};
  corrector.correct(step, 0.0);
  return {step.samples[0].gyro_dps, step.samples[0].accel_mps2};
}

/// Raw samples spread over directions and magnitudes a unit sees: rates up to 200 deg/s,
/// specific forces around 1 g in every direction.
struct RawSample {
  Eigen::Vector3d gyro_dps;
  Eigen::Vector3d accel_mps2;
};
inline std::vector<RawSample> export_raw_samples() {
  return {{{0.0, 0.0, 0.0}, {0.0, 0.0, 9.81}},
          {{100.0, -20.0, 5.0}, {9.81, 0.1, -0.2}},
          {{-3.0, 200.0, -50.0}, {0.3, -9.79, 0.5}},
          {{45.0, 45.0, -180.0}, {-5.6, 5.6, -5.7}},
          {{-0.5, 0.25, 0.1}, {1.0, 2.0, -9.5}}};
}

}  // namespace calstand::testing
