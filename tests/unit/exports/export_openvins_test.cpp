// The OpenVINS export read back by a small parser of the YAML it writes, and OpenVINS' own
// correction (VioManagerOptions: Dw = Tw^-1, Da = Ta^-1, of which the "kalibr" model keeps the
// lower triangles; Propagator: a_hat = R_ACCtoIMU Da (a_m - b_a),
// w_hat = R_GYROtoIMU Dw (w_m - b_g - Tg a_hat)) applied to raw samples: it must give what
// calstand's correction gives, for a hand-made record with every intrinsic and for a record
// fitted on the simulator.
#include <gtest/gtest.h>

#include <Eigen/LU>
#include <algorithm>
#include <map>
#include <sstream>
#include <string>

#include "../analysis/recorded_run.hpp"
#include "analysis/calibrate.hpp"
#include "core/error.hpp"
#include "export_test_support.hpp"
#include "exports/calibration_export.hpp"
#include "solver/model.hpp"

namespace calstand::analysis {
namespace {

using testing::calstand_correct;
using testing::HandRecord;
using testing::kExportRadPerDeg;

struct OpenVinsImu {
  std::map<std::string, std::string> scalars;  // under imu0, comments removed
  std::map<std::string, Eigen::Matrix3d> matrices;
};

std::string yaml_trimmed(const std::string& s) {
  const auto b = s.find_first_not_of(' ');
  const auto e = s.find_last_not_of(' ');
  return b == std::string::npos ? "" : s.substr(b, e - b + 1);
}

// The subset of YAML the file uses: "%YAML:1.0", comments, "imu0:", two-space keys with a
// scalar (a '#' after it starts a comment, a quoted string keeps its quotes) or a 3x3 matrix
// as three "    - [a, b, c]" rows.
OpenVinsImu read_openvins_yaml(const std::string& text) {
  OpenVinsImu imu;
  std::istringstream in(text);
  std::string line;
  std::getline(in, line);
  EXPECT_EQ(line, "%YAML:1.0");
  bool in_imu0 = false;
  std::string matrix_key;
  int row = 0;
  while (std::getline(in, line)) {
    if (line.empty() || yaml_trimmed(line).starts_with("#")) continue;
    if (line == "imu0:") {
      in_imu0 = true;
      continue;
    }
    EXPECT_TRUE(in_imu0 && line.starts_with("  ")) << "outside imu0: " << line;
    if (line.starts_with("    - [")) {
      EXPECT_FALSE(matrix_key.empty()) << line;
      EXPECT_LT(row, 3) << matrix_key;
      const std::string inside = line.substr(7, line.find(']') - 7);
      std::istringstream cells(inside);
      std::string cell;
      for (int c = 0; c < 3 && std::getline(cells, cell, ','); ++c) {
        imu.matrices[matrix_key](row, c) = std::stod(cell);
      }
      ++row;
      continue;
    }
    if (!matrix_key.empty()) {
      EXPECT_EQ(row, 3) << matrix_key;
    }
    const auto colon = line.find(':');
    const std::string key = yaml_trimmed(line.substr(0, colon));
    std::string value = line.substr(colon + 1);
    if (yaml_trimmed(value).empty()) {
      matrix_key = key;
      row = 0;
      imu.matrices[key] = Eigen::Matrix3d::Constant(std::nan(""));
      continue;
    }
    matrix_key.clear();
    if (!yaml_trimmed(value).starts_with("\"")) value = value.substr(0, value.find('#'));
    imu.scalars[key] = yaml_trimmed(value);
  }
  return imu;
}

double yaml_scalar(const OpenVinsImu& imu, const std::string& key) {
  const auto it = imu.scalars.find(key);
  if (it == imu.scalars.end()) {
    ADD_FAILURE() << key << " missing";
    return std::nan("");
  }
  return std::stod(it->second);
}

// OpenVINS' "kalibr" model keeps the lower triangle of D = T^-1 (VioManagerOptions:
// vec_dw << Dw.block<3,1>(0,0), Dw.block<2,1>(1,1), Dw(2,2)).
Eigen::Matrix3d kalibr_model_inverse(const Eigen::Matrix3d& t) {
  return Eigen::Matrix3d(t.inverse().triangularView<Eigen::Lower>());
}

struct OpenVinsCorrected {
  Eigen::Vector3d w_rad_s;
  Eigen::Vector3d a_mps2;
};
OpenVinsCorrected openvins_correct(const OpenVinsImu& imu, const Eigen::Vector3d& w_m,
                                   const Eigen::Vector3d& a_m, const Eigen::Vector3d& b_g,
                                   const Eigen::Vector3d& b_a) {
  const Eigen::Matrix3d da = kalibr_model_inverse(imu.matrices.at("Ta"));
  const Eigen::Matrix3d dw = kalibr_model_inverse(imu.matrices.at("Tw"));
  const Eigen::Vector3d a_hat = imu.matrices.at("R_IMUtoACC").transpose() * da * (a_m - b_a);
  const Eigen::Vector3d w_hat =
      imu.matrices.at("R_IMUtoGYRO").transpose() * dw * (w_m - b_g - imu.matrices.at("Tg") * a_hat);
  return {w_hat, a_hat};
}

void expect_intrinsic_matrices_well_formed(const OpenVinsImu& imu) {
  for (const char* key : {"Tw", "R_IMUtoGYRO", "Ta", "R_IMUtoACC", "Tg"}) {
    ASSERT_EQ(imu.matrices.count(key), 1u) << key;
    EXPECT_TRUE(imu.matrices.at(key).allFinite()) << key;
  }
  for (const char* key : {"Tw", "Ta"}) {
    const Eigen::Matrix3d& t = imu.matrices.at(key);
    EXPECT_EQ(t(0, 1), 0.0) << key;
    EXPECT_EQ(t(0, 2), 0.0) << key;
    EXPECT_EQ(t(1, 2), 0.0) << key;
    for (int i = 0; i < 3; ++i) EXPECT_GT(t(i, i), 0.0) << key;
  }
  for (const char* key : {"R_IMUtoGYRO", "R_IMUtoACC"}) {
    const Eigen::Matrix3d& r = imu.matrices.at(key);
    EXPECT_NEAR((r * r.transpose() - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-12) << key;
    EXPECT_NEAR(r.determinant(), 1.0, 1e-12) << key;
  }
}

// Datasheet figures as a calibration record keeps them (analysis::calibration_noise_figures).
nlohmann::json hand_noise_figures() {
  nlohmann::json channels;
  const auto gyro = [](double arw, double rrw, bool rrw_resolved) {
    return nlohmann::json::array({{{"name", "angle_random_walk"},
                                   {"value", arw},
                                   {"unit", "deg/sqrt(h)"},
                                   {"resolved", true}},
                                  {{"name", "rate_random_walk"},
                                   {"value", rrw},
                                   {"unit", "deg/h/sqrt(h)"},
                                   {"resolved", rrw_resolved}}});
  };
  const auto accel = [](double vrw, double arw) {
    return nlohmann::json::array({{{"name", "velocity_random_walk"},
                                   {"value", vrw},
                                   {"unit", "m/s/sqrt(h)"},
                                   {"resolved", true}},
                                  {{"name", "acceleration_random_walk"},
                                   {"value", arw},
                                   {"unit", "m/s/h/sqrt(h)"},
                                   {"resolved", true}}});
  };
  channels["gx"] = gyro(0.15, 3.0, true);
  channels["gy"] = gyro(0.21, 2.0, true);   // the worst gyro axis for N
  channels["gz"] = gyro(0.12, 4.5, false);  // the worst for K, not resolved
  channels["ax"] = accel(0.03, 0.4);
  channels["ay"] = accel(0.02, 0.9);
  channels["az"] = accel(0.05, 0.3);
  return {{"step", 4}, {"duration_s", 3600.0}, {"sample_rate_hz", 400.0}, {"channels", channels}};
}

TEST(ExportOpenVins, EveryIntrinsicReadsBackThroughOpenVinsCorrection) {
  HandRecord h;
  h.model =
      "gyro_bias,gyro_scale,gyro_misalignment,gyro_g_sensitivity,accel_bias,accel_scale,"
      "accel_misalignment,gyro_temp_bias";
  h.values = {{"gyro_bias.x", 0.05},
              {"gyro_bias.y", -0.02},
              {"gyro_bias.z", 0.01},
              {"gyro_scale.x", 800},
              {"gyro_scale.y", -600},
              {"gyro_scale.z", 300},
              {"gyro_misalignment.xy", 2e-3},
              {"gyro_misalignment.xz", -1e-3},
              {"gyro_misalignment.yx", 5e-4},
              {"gyro_misalignment.yz", 1.5e-3},
              {"gyro_misalignment.zx", -7e-4},
              {"gyro_misalignment.zy", 9e-4},
              {"gyro_g_sensitivity.xx", 0.02},
              {"gyro_g_sensitivity.xz", -0.05},
              {"gyro_g_sensitivity.yy", 0.03},
              {"gyro_g_sensitivity.zx", 0.01},
              {"accel_bias.x", 0.04},
              {"accel_bias.y", -0.03},
              {"accel_bias.z", 0.02},
              {"accel_scale.x", -500},
              {"accel_scale.y", 700},
              {"accel_scale.z", 200},
              {"accel_misalignment.xy", 1e-3},
              {"accel_misalignment.xz", -2e-3},
              {"accel_misalignment.yx", 4e-4},
              {"accel_misalignment.yz", 8e-4},
              {"accel_misalignment.zx", -6e-4},
              {"accel_misalignment.zy", 3e-4},
              {"gyro_temp_bias.x1", 1e-3}};
  h.noise = hand_noise_figures();
  const solver::Calibration c = testing::hand_calibration(h);
  ExportOptions options;
  options.rostopic = "/unit/imu";
  const ExportResult r = export_calibration(c, ExportFormat::kOpenVins, options);
  const OpenVinsImu imu = read_openvins_yaml(r.text);
  expect_intrinsic_matrices_well_formed(imu);
  EXPECT_EQ(imu.scalars.at("model"), "\"kalibr\"");
  EXPECT_EQ(imu.scalars.at("rostopic"), "\"/unit/imu\"");
  EXPECT_DOUBLE_EQ(yaml_scalar(imu, "update_rate"), 400.0);

  // Noise: the worst axis, N from deg/sqrt(h) (1/60) and K from deg/h/sqrt(h) (1/216000), in
  // rad for the gyro; 6 significant digits as imu.yaml has them.
  EXPECT_NEAR(yaml_scalar(imu, "gyroscope_noise_density"), 0.21 / 60.0 * kExportRadPerDeg, 1e-10);
  EXPECT_NEAR(yaml_scalar(imu, "gyroscope_random_walk"), 4.5 / 216000.0 * kExportRadPerDeg, 1e-12);
  EXPECT_NEAR(yaml_scalar(imu, "accelerometer_noise_density"), 0.05 / 60.0, 1e-9);
  EXPECT_NEAR(yaml_scalar(imu, "accelerometer_random_walk"), 0.9 / 216000.0, 1e-11);

  // OpenVINS estimates the biases; given the record's, it corrects as calstand does.
  const Eigen::Vector3d b_g = Eigen::Vector3d(0.05, -0.02, 0.01) * kExportRadPerDeg;
  const Eigen::Vector3d b_a(0.04, -0.03, 0.02);
  for (const auto& raw : testing::export_raw_samples()) {
    const auto expected = calstand_correct(c, raw.gyro_dps, raw.accel_mps2, 25.0);
    const auto got =
        openvins_correct(imu, raw.gyro_dps * kExportRadPerDeg, raw.accel_mps2, b_g, b_a);
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(got.w_rad_s(i), expected.gyro_dps(i) * kExportRadPerDeg, 1e-11) << i;
      EXPECT_NEAR(got.a_mps2(i), expected.accel_mps2(i), 1e-11) << i;
    }
  }

  std::string all;
  for (const auto& w : r.warnings) all += w + "\n";
  for (const char* named : {"gyro_bias.x .y .z, accel_bias.x .y .z", "gyro_temp_bias.x1",
                            "gyroscope_random_walk: not resolved"}) {
    EXPECT_NE(all.find(named), std::string::npos) << named << " not in:\n" << all;
  }
}

// A record's identified-model figures (analysis::calibration_noise_figures' "model_figures"):
// per channel the white density and random walk in the data's unit, from the GMWM or not.
nlohmann::json model_figures(double n, double k, const char* u, const char* n_estimator) {
  return nlohmann::json::array({{{"name", "white_density"},
                                 {"value", n},
                                 {"ci95", {0.9 * n, 1.1 * n}},
                                 {"unit", std::string(u) + "/sqrt(Hz)"},
                                 {"estimator", n_estimator},
                                 {"resolved", true}},
                                {{"name", "random_walk"},
                                 {"value", k},
                                 {"ci95", {0.5 * k, 2.0 * k}},
                                 {"unit", std::string(u) + "/sqrt(s)"},
                                 {"estimator", "gmwm"},
                                 {"resolved", true}}});
}

TEST(ExportOpenVins, TheIdentifiedModelsFiguresAreUsedWhereEveryAxisHasThem) {
  HandRecord h;
  h.model = "gyro_bias,accel_bias";
  h.values = {{"gyro_bias.x", 0.0},  {"gyro_bias.y", 0.0},  {"gyro_bias.z", 0.0},
              {"accel_bias.x", 0.0}, {"accel_bias.y", 0.0}, {"accel_bias.z", 0.0}};
  h.noise = hand_noise_figures();
  nlohmann::json& m = h.noise["model_figures"];
  // Gyro: every axis from its model; the worst white density is gy's, written in rad/s, so that
  // the record's stated unit is converted and not assumed.
  m["gx"] = model_figures(0.0030, 2e-5, "deg/s", "gmwm");
  m["gy"] = model_figures(0.0041 * kExportRadPerDeg, 1e-5 * kExportRadPerDeg, "rad/s", "gmwm");
  m["gz"] = model_figures(0.0020, 4e-5, "deg/s", "gmwm");
  // Accel: az's white density is the Allan line's, so the sensor's density stays the Allan line's
  // (one number per sensor from one estimator); its random walk is every axis's model.
  m["ax"] = model_figures(4e-4, 3e-6, "m/s^2", "gmwm");
  m["ay"] = model_figures(5e-4, 7e-6, "m/s^2", "gmwm");
  m["az"] = model_figures(9e-4, 2e-6, "m/s^2", "allan-line");
  const solver::Calibration c = testing::hand_calibration(h);
  const ExportResult r = export_calibration(c, ExportFormat::kOpenVins, {});
  const OpenVinsImu imu = read_openvins_yaml(r.text);
  EXPECT_NEAR(yaml_scalar(imu, "gyroscope_noise_density"), 0.0041 * kExportRadPerDeg, 1e-9);
  EXPECT_NEAR(yaml_scalar(imu, "gyroscope_random_walk"), 4e-5 * kExportRadPerDeg, 1e-11);
  EXPECT_NEAR(yaml_scalar(imu, "accelerometer_noise_density"), 0.05 / 60.0, 1e-9);  // Allan
  EXPECT_NEAR(yaml_scalar(imu, "accelerometer_random_walk"), 7e-6, 1e-11);
  for (const char* line :
       {"gyroscope_noise_density: 7.15585e-05  # [rad/s/sqrt(Hz)] estimator: gmwm",
        "accelerometer_noise_density: 0.000833333  # [m/s^2/sqrt(Hz)] estimator: allan-line",
        "accelerometer_random_walk: 7e-06  # [m/s^3/sqrt(Hz)] estimator: gmwm"}) {
    EXPECT_NE(r.text.find(line), std::string::npos) << line << " not in:\n" << r.text;
  }

  // A malformed figure is named.
  h.noise["model_figures"]["ay"][1]["unit"] = "m/s";  // not a random walk's dimension
  try {
    export_calibration(testing::hand_calibration(h), ExportFormat::kOpenVins, {});
    ADD_FAILURE() << "accepted";
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("noise.model_figures.ay: random_walk"), std::string::npos)
        << e.what();
  }
}

TEST(ExportOpenVins, ARecordFittedOnTheSimulatorReadsBack) {
  testing::TempDatabase file("export-openvins");
  const std::int64_t run = testing::record_run(file.path(), "six-position", {"capture_s=10"}, 5);
  store::Database db(file.path());
  const CalibrationOutcome fitted = calibrate_run(
      db, run,
      solver::Model::parse("accel_bias,accel_scale,accel_misalignment,gyro_bias,earth_rate"), "");
  const solver::Calibration c = solver::read_calibration(fitted.record, "fitted");
  ExportOptions options;
  options.update_rate_hz = 200.0;  // six 10 s captures are no noise record: no rate in it
  const ExportResult r = export_calibration(c, ExportFormat::kOpenVins, options);
  const OpenVinsImu imu = read_openvins_yaml(r.text);
  expect_intrinsic_matrices_well_formed(imu);
  EXPECT_DOUBLE_EQ(yaml_scalar(imu, "update_rate"), 200.0);
  EXPECT_EQ(yaml_scalar(imu, "gyroscope_noise_density"), 0.0);
  EXPECT_NE(r.warnings.front().find("no noise figures"), std::string::npos) << r.warnings.front();

  Eigen::Vector3d b_g;
  Eigen::Vector3d b_a;
  for (int i = 0; i < 3; ++i) {
    const std::string axis(1, static_cast<char>('x' + i));
    b_g(i) = 0.0;
    b_a(i) = 0.0;
    for (const auto& p : fitted.record.at("parameters")) {
      if (p.at("name") == "gyro_bias." + axis) b_g(i) = p.at("value").get<double>();
      if (p.at("name") == "accel_bias." + axis) b_a(i) = p.at("value").get<double>();
    }
  }
  // The fit found the known IMU's accelerometer: its matrix is not the identity.
  EXPECT_GT((imu.matrices.at("Ta") - Eigen::Matrix3d::Identity()).norm(), 1e-4);
  for (const auto& raw : testing::export_raw_samples()) {
    const auto expected = calstand_correct(c, raw.gyro_dps, raw.accel_mps2, 25.0);
    const auto got = openvins_correct(imu, raw.gyro_dps * kExportRadPerDeg, raw.accel_mps2,
                                      b_g * kExportRadPerDeg, b_a);
    EXPECT_NEAR((got.w_rad_s - expected.gyro_dps * kExportRadPerDeg).norm(), 0.0, 1e-11);
    EXPECT_NEAR((got.a_mps2 - expected.accel_mps2).norm(), 0.0, 1e-11);
  }
}

TEST(ExportOpenVins, WithoutASampleRateItAsksForOne) {
  HandRecord h;
  h.model = "gyro_bias";
  h.values = {{"gyro_bias.x", 0.01}};
  try {
    export_calibration(testing::hand_calibration(h), ExportFormat::kOpenVins);
    ADD_FAILURE() << "accepted";
  } catch (const core::InputError& e) {
    EXPECT_EQ(e.where(), "--update-rate");
  }
}

}  // namespace
}  // namespace calstand::analysis
