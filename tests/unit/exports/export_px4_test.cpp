// The PX4 export read back by a small parser of QGroundControl's .params format, and PX4's own
// correction (TemperatureCompensation::calc_thermal_offsets_3D, then
// calibration::Accelerometer/Gyroscope::Correct, or the TC_*_SCL_* generation's
// apply_corrections_*) applied to raw samples with the numbers read back: it must give what
// calstand's correction of the record gives.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
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

struct Px4Param {
  int sysid = 0;
  int component = 0;
  std::string value;
  int type = 0;
};

// QGroundControl's reader: '#' lines are comments, every other line is five tab-separated
// fields (vehicle id, component id, name, value, MAV_PARAM_TYPE).
std::map<std::string, Px4Param> read_px4_params(const std::string& text) {
  std::map<std::string, Px4Param> params;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::vector<std::string> f;
    std::istringstream fields(line);
    for (std::string x; std::getline(fields, x, '\t');) f.push_back(x);
    EXPECT_EQ(f.size(), 5u) << line;
    if (f.size() != 5) continue;
    EXPECT_EQ(params.count(f[2]), 0u) << "twice: " << f[2];
    params[f[2]] = {std::stoi(f[0]), std::stoi(f[1]), f[3], std::stoi(f[4])};
  }
  return params;
}

double px4_number(const std::map<std::string, Px4Param>& p, const std::string& name) {
  const auto it = p.find(name);
  if (it == p.end()) {
    ADD_FAILURE() << name << " missing";
    return std::nan("");
  }
  return testing::as_float32(std::stod(it->second.value));
}

Eigen::Vector3d px4_vector(const std::map<std::string, Px4Param>& p, const std::string& prefix,
                           const std::string& suffix, bool xyz_letters) {
  Eigen::Vector3d v;
  for (int i = 0; i < 3; ++i) {
    v(i) = xyz_letters ? px4_number(p, prefix + static_cast<char>('X' + i) + suffix)
                       : px4_number(p, prefix + std::to_string(i) + suffix);
  }
  return v;
}

// TemperatureCompensation::calc_thermal_offsets_3D: T clipped to [TMIN, TMAX], polynomial of
// order 3 in T - TREF.
Eigen::Vector3d px4_thermal_offset(const std::map<std::string, Px4Param>& p, const std::string& tc,
                                   double temperature_c) {
  const double t =
      std::clamp(temperature_c, px4_number(p, tc + "TMIN"), px4_number(p, tc + "TMAX"));
  const double d = t - px4_number(p, tc + "TREF");
  Eigen::Vector3d offset;
  for (int axis = 0; axis < 3; ++axis) {
    const auto x = [&](int k) {
      return px4_number(p, tc + "X" + std::to_string(k) + "_" + std::to_string(axis));
    };
    offset(axis) = x(0) + x(1) * d + x(2) * d * d + x(3) * d * d * d;
  }
  return offset;
}

// A record of what PX4 represents: biases, the accelerometer's scale, thermal polynomials of
// order 3 (gyro) and 2 (accel) about T_ref = 30 degC.
HandRecord px4_record() {
  HandRecord h;
  h.model = "gyro_bias,gyro_temp_bias:3,accel_bias,accel_scale,accel_temp_bias:2";
  h.values = {
      {"gyro_bias.x", 0.02},         {"gyro_bias.y", -0.015},       {"gyro_bias.z", 0.008},
      {"gyro_temp_bias.x1", 0.0012}, {"gyro_temp_bias.y1", -8e-4},  {"gyro_temp_bias.z1", 5e-4},
      {"gyro_temp_bias.x2", -2e-5},  {"gyro_temp_bias.y2", 1e-5},   {"gyro_temp_bias.z2", 3e-6},
      {"gyro_temp_bias.x3", 4e-7},   {"gyro_temp_bias.y3", -1e-7},  {"gyro_temp_bias.z3", 2e-8},
      {"accel_bias.x", 0.03},        {"accel_bias.y", -0.025},      {"accel_bias.z", 0.04},
      {"accel_scale.x", 4000},       {"accel_scale.y", -250},       {"accel_scale.z", 150},
      {"accel_temp_bias.x1", 1e-4},  {"accel_temp_bias.y1", -2e-4}, {"accel_temp_bias.z1", 5e-5},
      {"accel_temp_bias.x2", 2e-6},  {"accel_temp_bias.y2", -1e-6}, {"accel_temp_bias.z2", 3e-7}};
  h.temperature_ref_c = 30.0;
  h.valid_min_c = -20.0;
  h.valid_max_c = 70.0;
  return h;
}

constexpr std::int64_t kGyroId = 2490378;
constexpr std::int64_t kAccelId = 3000000000;  // above 2^31: PX4 keeps it in an INT32

TEST(ExportPx4, ReadBackThroughPx4sCorrectionItEqualsCalstands) {
  const solver::Calibration c = testing::hand_calibration(px4_record());
  ExportOptions options;
  options.px4_gyro_id = kGyroId;
  options.px4_accel_id = kAccelId;
  const ExportResult r = export_calibration(c, ExportFormat::kPx4, options);
  EXPECT_TRUE(r.warnings.empty()) << r.warnings.front();
  const auto p = read_px4_params(r.text);

  for (const auto& [name, param] : p) {
    EXPECT_EQ(param.sysid, 1) << name;
    EXPECT_EQ(param.component, 1) << name;
    const bool integer = name.ends_with("_ID") || name.ends_with("_ENABLE");
    EXPECT_EQ(param.type, integer ? 6 : 9) << name;  // MAV_PARAM_TYPE INT32, REAL32
  }
  EXPECT_EQ(p.at("TC_G_ENABLE").value, "1");
  EXPECT_EQ(p.at("TC_A_ENABLE").value, "1");
  EXPECT_EQ(std::stoll(p.at("TC_G0_ID").value), kGyroId);
  EXPECT_EQ(std::stoll(p.at("CAL_GYRO0_ID").value), kGyroId);
  EXPECT_EQ(static_cast<std::uint32_t>(std::stoi(p.at("TC_A0_ID").value)), kAccelId);
  EXPECT_EQ(static_cast<std::uint32_t>(std::stoi(p.at("CAL_ACC0_ID").value)), kAccelId);
  EXPECT_DOUBLE_EQ(px4_number(p, "TC_G0_TREF"), 30.0);
  EXPECT_DOUBLE_EQ(px4_number(p, "TC_A0_TMIN"), -20.0);
  EXPECT_DOUBLE_EQ(px4_number(p, "TC_A0_TMAX"), 70.0);
  // The accelerometer polynomial is of order 2: its cubic coefficients are zero.
  EXPECT_EQ(px4_vector(p, "TC_A0_X3_", "", false), Eigen::Vector3d::Zero());
  EXPECT_EQ(p.count("TC_G0_SCL_0"), 0u);  // not in this generation of PX4

  // PX4: corrected = (raw - TC(T) - CAL_OFF) .* CAL_SCALE, rad/s and m/s^2.
  for (const double t : {-20.0, 0.0, 30.0, 45.5, 70.0}) {
    for (const auto& raw : testing::export_raw_samples()) {
      const auto expected = calstand_correct(c, raw.gyro_dps, raw.accel_mps2, t);
      const Eigen::Vector3d gyro = raw.gyro_dps * kExportRadPerDeg -
                                   px4_thermal_offset(p, "TC_G0_", t) -
                                   px4_vector(p, "CAL_GYRO0_", "OFF", true);
      const Eigen::Vector3d accel = (raw.accel_mps2 - px4_thermal_offset(p, "TC_A0_", t) -
                                     px4_vector(p, "CAL_ACC0_", "OFF", true))
                                        .cwiseProduct(px4_vector(p, "CAL_ACC0_", "SCALE", true));
      for (int i = 0; i < 3; ++i) {
        EXPECT_NEAR(gyro(i), expected.gyro_dps(i) * kExportRadPerDeg, 1e-10) << t << " gyro " << i;
        EXPECT_NEAR(accel(i), expected.accel_mps2(i),
                    testing::float32_tolerance(raw.accel_mps2.norm()))
            << t << " accel " << i;
      }
    }
  }
  // Beyond TMAX PX4 holds the offsets of TMAX.
  const auto at_max = calstand_correct(c, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 70.0);
  EXPECT_NEAR(-px4_thermal_offset(p, "TC_G0_", 95.0)(0), at_max.gyro_dps(0) * kExportRadPerDeg,
              1e-10);
}

TEST(ExportPx4, LegacyPutsBothScalesInTcSclAndWritesNoCalParameters) {
  HandRecord h = px4_record();
  h.model += ",gyro_scale";
  h.values.insert({{"gyro_scale.x", 3000}, {"gyro_scale.y", -120}, {"gyro_scale.z", 80}});
  const solver::Calibration c = testing::hand_calibration(h);
  ExportOptions options;
  options.px4_gyro_id = kGyroId;
  options.px4_accel_id = kAccelId;
  const ExportResult r = export_calibration(c, ExportFormat::kPx4Legacy, options);
  EXPECT_TRUE(r.warnings.empty()) << r.warnings.front();
  const auto p = read_px4_params(r.text);
  for (const auto& [name, param] : p) EXPECT_FALSE(name.starts_with("CAL_")) << name;

  // The TC_*_SCL_* generation: corrected = (raw - TC(T)) .* TC_SCL.
  for (const double t : {-5.0, 30.0, 61.0}) {
    for (const auto& raw : testing::export_raw_samples()) {
      const auto expected = calstand_correct(c, raw.gyro_dps, raw.accel_mps2, t);
      const Eigen::Vector3d gyro =
          (raw.gyro_dps * kExportRadPerDeg - px4_thermal_offset(p, "TC_G0_", t))
              .cwiseProduct(px4_vector(p, "TC_G0_SCL_", "", false));
      const Eigen::Vector3d accel = (raw.accel_mps2 - px4_thermal_offset(p, "TC_A0_", t))
                                        .cwiseProduct(px4_vector(p, "TC_A0_SCL_", "", false));
      for (int i = 0; i < 3; ++i) {
        EXPECT_NEAR(gyro(i), expected.gyro_dps(i) * kExportRadPerDeg,
                    testing::float32_tolerance(raw.gyro_dps.norm() * kExportRadPerDeg))
            << t << " gyro " << i;
        EXPECT_NEAR(accel(i), expected.accel_mps2(i),
                    testing::float32_tolerance(raw.accel_mps2.norm()))
            << t << " accel " << i;
      }
    }
  }
}

TEST(ExportPx4, NamesEveryParameterItLeavesOutAndTheMissingDeviceIds) {
  HandRecord h;
  h.model =
      "gyro_bias,gyro_scale,gyro_misalignment,gyro_g_sensitivity,accel_bias,accel_quadratic,"
      "table_tilt,grad";
  h.customs = {"grad=gyro:temperature_rate"};
  h.values = {{"gyro_bias.x", 0.01},          {"gyro_scale.y", 100},
              {"gyro_misalignment.zx", 1e-4}, {"gyro_g_sensitivity.xz", 0.05},
              {"accel_quadratic.z", 20},      {"grad.x", 0.001},
              {"table_tilt.east", 1e-5}};
  h.undetermined = {{"gyro_misalignment.yz", "no rotation about y"}};
  const ExportResult r = export_calibration(testing::hand_calibration(h), ExportFormat::kPx4);
  std::string all;
  for (const auto& w : r.warnings) all += w + "\n";
  for (const char* named :
       {"gyro_scale.x .y .z", "gyro_misalignment.xy .xz .yx .yz .zx .zy", "gyro_g_sensitivity.xx",
        "accel_quadratic.x", "grad.x", "table_tilt.east .north", "px4-legacy",
        "TC_G0_ID and CAL_GYRO0_ID", "TC_A0_ID and CAL_ACC0_ID", "gyro_misalignment.yz: written",
        "no gyro_temp_bias", "no accel_temp_bias"}) {
    EXPECT_NE(all.find(named), std::string::npos) << named << " not in:\n" << all;
  }
  EXPECT_EQ(all.find("gyro_bias"), std::string::npos) << all;  // PX4 holds it
}

TEST(ExportPx4, WithoutTemperatureTheConstantOffsetsHoldAtEveryTemperature) {
  HandRecord h;
  h.model = "gyro_bias,accel_bias,accel_scale";
  h.values = {{"gyro_bias.z", -0.05}, {"accel_bias.y", 0.02}, {"accel_scale.x", -300}};
  h.temperature_ref_c = nullptr;  // a recording without temperature
  h.valid_min_c = nullptr;
  h.valid_max_c = nullptr;
  const solver::Calibration c = testing::hand_calibration(h);
  const ExportResult r = export_calibration(c, ExportFormat::kPx4);
  const auto p = read_px4_params(r.text);
  EXPECT_NEAR(px4_number(p, "TC_G0_X0_2"), -0.05 * kExportRadPerDeg, 1e-10);
  EXPECT_NEAR(px4_number(p, "TC_A0_X0_1"), 0.02, 1e-9);
  for (const char* tc : {"TC_G0_", "TC_A0_"}) {
    for (int k = 1; k <= 3; ++k) {
      EXPECT_EQ(px4_vector(p, std::string(tc) + "X" + std::to_string(k) + "_", "", false),
                Eigen::Vector3d::Zero());
    }
    EXPECT_EQ(px4_number(p, std::string(tc) + "TMIN"), px4_number(p, std::string(tc) + "TREF"));
    EXPECT_EQ(px4_number(p, std::string(tc) + "TMAX"), px4_number(p, std::string(tc) + "TREF"));
  }
  for (const double t : {-40.0, 25.0, 85.0}) {
    const auto raw = testing::export_raw_samples()[1];
    const auto expected = calstand_correct(c, raw.gyro_dps, raw.accel_mps2, t);
    const Eigen::Vector3d accel = (raw.accel_mps2 - px4_thermal_offset(p, "TC_A0_", t))
                                      .cwiseProduct(px4_vector(p, "CAL_ACC0_", "SCALE", true));
    EXPECT_NEAR((accel - expected.accel_mps2).norm(), 0.0,
                testing::float32_tolerance(raw.accel_mps2.norm()))
        << t;
  }
  int said = 0;
  for (const auto& w : r.warnings) {
    said += w.find("no gyro_temp_bias") != std::string::npos ||
            w.find("no accel_temp_bias") != std::string::npos;
  }
  EXPECT_EQ(said, 2);
}

TEST(ExportPx4, RefusesAPolynomialOfOrderFourByName) {
  HandRecord h;
  h.model = "gyro_bias,gyro_temp_bias:4";
  h.values = {{"gyro_temp_bias.x4", 1e-9}};
  const solver::Calibration c = testing::hand_calibration(h);
  for (const auto format : {ExportFormat::kPx4, ExportFormat::kPx4Legacy}) {
    try {
      export_calibration(c, format);
      ADD_FAILURE() << "accepted";
    } catch (const core::InputError& e) {
      EXPECT_NE(std::string(e.what()).find("gyro_temp_bias:4"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("order 3"), std::string::npos) << e.what();
    }
  }
}

TEST(ExportPx4, InstanceAndSystemIdNameTheSlotAndTheVehicle) {
  ExportOptions options;
  options.instance = 2;
  options.mav_sysid = 7;
  const ExportResult r =
      export_calibration(testing::hand_calibration(px4_record()), ExportFormat::kPx4, options);
  const auto p = read_px4_params(r.text);
  for (const char* name : {"TC_G2_X0_0", "TC_A2_TREF", "CAL_GYRO2_XOFF", "CAL_ACC2_ZSCALE"}) {
    ASSERT_EQ(p.count(name), 1u) << name;
    EXPECT_EQ(p.at(name).sysid, 7) << name;
  }
  EXPECT_EQ(p.count("TC_G0_X0_0"), 0u);
}

}  // namespace
}  // namespace calstand::analysis
