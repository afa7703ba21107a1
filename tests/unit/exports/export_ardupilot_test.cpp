// The ArduPilot export read back by a small parser of the .param format (NAME,VALUE), and
// ArduPilot's own correction (AP_InertialSensor::TCal::correct_sensor with its fixed 35 degC
// reference and 1e-6 parameter scale, then the offsets and accel scales of
// AP_InertialSensor_Backend::_rotate_and_correct_*) applied to raw samples with the numbers
// read back: it must give what calstand's correction of the record gives.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <sstream>
#include <string>

#include "core/error.hpp"
#include "export_test_support.hpp"
#include "exports/calibration_export.hpp"

namespace calstand::analysis {
namespace {

using testing::calstand_correct;
using testing::HandRecord;
using testing::kExportRadPerDeg;

// Mission Planner's and MAVProxy's reader: '#' lines are comments, others NAME,VALUE.
std::map<std::string, double> read_ardupilot_params(const std::string& text) {
  std::map<std::string, double> params;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    const auto comma = line.find(',');
    EXPECT_NE(comma, std::string::npos) << line;
    EXPECT_EQ(line.find(' '), std::string::npos) << line;
    if (comma == std::string::npos) continue;
    const std::string name = line.substr(0, comma);
    EXPECT_LE(name.size(), 16u) << name;  // MAVLink parameter ids are 16 characters at most
    EXPECT_EQ(params.count(name), 0u) << "twice: " << name;
    params[name] = testing::as_float32(std::stod(line.substr(comma + 1)));
  }
  return params;
}

double ap_number(const std::map<std::string, double>& p, const std::string& name) {
  const auto it = p.find(name);
  if (it == p.end()) {
    ADD_FAILURE() << name << " missing";
    return std::nan("");
  }
  return it->second;
}

Eigen::Vector3d ap_vector(const std::map<std::string, double>& p, const std::string& prefix) {
  return {ap_number(p, prefix + "X"), ap_number(p, prefix + "Y"), ap_number(p, prefix + "Z")};
}

// TCal::polynomial_eval: (c1 + (c2 + c3 x) x) x * 1e-6, coefficients INS_TCALn_<S>k_{X,Y,Z}.
Eigen::Vector3d ap_polynomial(const std::map<std::string, double>& p, const std::string& tcal,
                              double x) {
  const Eigen::Vector3d c1 = ap_vector(p, tcal + "1_");
  const Eigen::Vector3d c2 = ap_vector(p, tcal + "2_");
  const Eigen::Vector3d c3 = ap_vector(p, tcal + "3_");
  return (c1 + (c2 + c3 * x) * x) * x * 1e-6;
}

// TCal::correct_sensor, then the offsets (and the accel scales).
Eigen::Vector3d ap_correct(const std::map<std::string, double>& p, int n, bool accel,
                           const Eigen::Vector3d& raw, double temperature_c) {
  const std::string ins = "INS_TCAL" + std::to_string(n) + "_";
  const std::string sensor = accel ? "ACC" : "GYR";
  const std::string sfx = n == 1 ? "" : std::to_string(n);
  const double tmin = ap_number(p, ins + "TMIN");
  const double tmax = ap_number(p, ins + "TMAX");
  const double t = std::clamp(temperature_c, tmin, tmax);
  const double tcal =
      std::clamp(ap_number(p, "INS_" + sensor + std::to_string(n) + "_CALTEMP"), tmin, tmax);
  Eigen::Vector3d v = raw;
  if (ap_number(p, ins + "ENABLE") == 1.0) {
    v -= ap_polynomial(p, ins + sensor, t - 35.0);
    v += ap_polynomial(p, ins + sensor, tcal - 35.0);
  }
  v -= ap_vector(p, "INS_" + sensor + sfx + "OFFS_");
  if (accel) v = v.cwiseProduct(ap_vector(p, "INS_ACC" + sfx + "SCAL_"));
  return v;
}

// What ArduPilot represents: offsets, accel scales, polynomials of order 3 (gyro) and 2 (accel)
// about a T_ref of 28 degC, away from ArduPilot's 35 so that the polynomial is re-expanded.
HandRecord ardupilot_record() {
  HandRecord h;
  h.model = "gyro_bias,gyro_temp_bias:3,accel_bias,accel_scale,accel_temp_bias:2";
  h.values = {{"gyro_bias.x", -0.03},         {"gyro_bias.y", 0.011},
              {"gyro_bias.z", 0.006},         {"gyro_temp_bias.x1", -0.0015},
              {"gyro_temp_bias.y1", 7e-4},    {"gyro_temp_bias.z1", 2e-4},
              {"gyro_temp_bias.x2", 3e-5},    {"gyro_temp_bias.y2", -1.5e-5},
              {"gyro_temp_bias.z2", 4e-6},    {"gyro_temp_bias.x3", -5e-7},
              {"gyro_temp_bias.y3", 2e-7},    {"gyro_temp_bias.z3", 6e-8},
              {"accel_bias.x", -0.045},       {"accel_bias.y", 0.02},
              {"accel_bias.z", 0.06},         {"accel_scale.x", -3500},
              {"accel_scale.y", 220},         {"accel_scale.z", 90},
              {"accel_temp_bias.x1", -3e-4},  {"accel_temp_bias.y1", 1e-4},
              {"accel_temp_bias.z1", 2.5e-4}, {"accel_temp_bias.x2", 1e-6},
              {"accel_temp_bias.y2", 4e-6},   {"accel_temp_bias.z2", -2e-6}};
  h.temperature_ref_c = 28.0;
  h.valid_min_c = -15.0;
  h.valid_max_c = 65.0;
  return h;
}

void expect_ardupilot_matches_calstand(const solver::Calibration& c,
                                       const std::map<std::string, double>& p, int n,
                                       std::initializer_list<double> temperatures) {
  for (const double t : temperatures) {
    for (const auto& raw : testing::export_raw_samples()) {
      const auto expected = calstand_correct(c, raw.gyro_dps, raw.accel_mps2, t);
      const Eigen::Vector3d gyro = ap_correct(p, n, false, raw.gyro_dps * kExportRadPerDeg, t);
      const Eigen::Vector3d accel = ap_correct(p, n, true, raw.accel_mps2, t);
      for (int i = 0; i < 3; ++i) {
        EXPECT_NEAR(gyro(i), expected.gyro_dps(i) * kExportRadPerDeg, 1e-10) << t << " gyro " << i;
        EXPECT_NEAR(accel(i), expected.accel_mps2(i),
                    testing::float32_tolerance(raw.accel_mps2.norm()))
            << t << " accel " << i;
      }
    }
  }
}

TEST(ExportArduPilot, ReadBackThroughArduPilotsCorrectionItEqualsCalstands) {
  const solver::Calibration c = testing::hand_calibration(ardupilot_record());
  const ExportResult r = export_calibration(c, ExportFormat::kArduPilot);
  EXPECT_TRUE(r.warnings.empty()) << r.warnings.front();
  const auto p = read_ardupilot_params(r.text);
  EXPECT_EQ(ap_number(p, "INS_TCAL1_ENABLE"), 1.0);
  EXPECT_EQ(ap_number(p, "INS_TCAL1_TMIN"), -15.0);
  EXPECT_EQ(ap_number(p, "INS_TCAL1_TMAX"), 65.0);
  // The offsets are stated at T_ref: the record's biases themselves.
  EXPECT_EQ(ap_number(p, "INS_ACC1_CALTEMP"), 28.0);
  EXPECT_EQ(ap_number(p, "INS_GYR1_CALTEMP"), 28.0);
  EXPECT_NEAR(ap_number(p, "INS_ACCOFFS_Y"), 0.02, 1e-9);
  EXPECT_NEAR(ap_number(p, "INS_GYROFFS_X"), -0.03 * kExportRadPerDeg, 1e-10);
  // A cubic re-expanded about 35 degC keeps its leading coefficient (times 1e6, in rad/s).
  EXPECT_NEAR(ap_number(p, "INS_TCAL1_GYR3_Z"), 6e-8 * kExportRadPerDeg * 1e6, 1e-9);
  expect_ardupilot_matches_calstand(c, p, 1, {-15.0, 0.0, 28.0, 35.0, 50.5, 65.0});
}

TEST(ExportArduPilot, AReferenceOutsideTheRangeMovesTheCalibrationTemperatureIntoIt) {
  HandRecord h = ardupilot_record();
  h.valid_min_c = 40.0;  // ArduPilot clips the calibration temperature as it clips T
  h.valid_max_c = 75.0;
  const solver::Calibration c = testing::hand_calibration(h);
  const auto p = read_ardupilot_params(export_calibration(c, ExportFormat::kArduPilot).text);
  EXPECT_EQ(ap_number(p, "INS_ACC1_CALTEMP"), 40.0);
  EXPECT_EQ(ap_number(p, "INS_GYR1_CALTEMP"), 40.0);
  expect_ardupilot_matches_calstand(c, p, 1, {40.0, 52.0, 75.0});
}

TEST(ExportArduPilot, TheThirdImuHasItsOwnNames) {
  ExportOptions options;
  options.instance = 2;
  const solver::Calibration c = testing::hand_calibration(ardupilot_record());
  const auto p =
      read_ardupilot_params(export_calibration(c, ExportFormat::kArduPilot, options).text);
  for (const char* name : {"INS_TCAL3_ENABLE", "INS_TCAL3_GYR2_Y", "INS_ACC3OFFS_Z",
                           "INS_ACC3SCAL_X", "INS_GYR3OFFS_Y", "INS_ACC3_CALTEMP"}) {
    EXPECT_EQ(p.count(name), 1u) << name;
  }
  EXPECT_EQ(p.count("INS_ACCOFFS_X"), 0u);
  expect_ardupilot_matches_calstand(c, p, 3, {10.0, 60.0});
}

TEST(ExportArduPilot, NamesWhatItLeavesOutAndDisablesAnEmptyTemperatureCalibration) {
  HandRecord h;
  h.model = "gyro_bias,gyro_scale,accel_bias,accel_misalignment,accel_scale_asymmetry";
  h.values = {{"gyro_bias.y", 0.02},
              {"gyro_scale.z", -150},
              {"accel_bias.x", 0.01},
              {"accel_misalignment.yx", 2e-4},
              {"accel_scale_asymmetry.z", 30}};
  const solver::Calibration c = testing::hand_calibration(h);
  const ExportResult r = export_calibration(c, ExportFormat::kArduPilot);
  std::string all;
  for (const auto& w : r.warnings) all += w + "\n";
  for (const char* named : {"gyro_scale.x .y .z", "accel_misalignment.xy .xz .yx .yz .zx .zy",
                            "accel_scale_asymmetry.x .y .z", "no gyro_temp_bias",
                            "no accel_temp_bias", "INS_TCAL1_ENABLE = 0"}) {
    EXPECT_NE(all.find(named), std::string::npos) << named << " not in:\n" << all;
  }
  const auto p = read_ardupilot_params(r.text);
  EXPECT_EQ(ap_number(p, "INS_TCAL1_ENABLE"), 0.0);
  EXPECT_NEAR(ap_number(p, "INS_GYROFFS_Y"), 0.02 * kExportRadPerDeg, 1e-10);
}

TEST(ExportArduPilot, RefusesAPolynomialOfOrderFourByName) {
  HandRecord h;
  h.model = "accel_bias,accel_temp_bias:4";
  h.values = {{"accel_temp_bias.z4", 1e-9}};
  try {
    export_calibration(testing::hand_calibration(h), ExportFormat::kArduPilot);
    ADD_FAILURE() << "accepted";
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("accel_temp_bias:4"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace calstand::analysis
