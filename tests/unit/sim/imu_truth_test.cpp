#include "sim/imu_truth.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>

#include "core/error.hpp"
#include "core/error_terms.hpp"
#include "core/json_schema.hpp"
#include "core/rotation.hpp"
#include "core/site.hpp"
#include "sim/imu_sim.hpp"

namespace calstand::sim {
namespace {

constexpr double g0 = core::kStandardGravity;

// Inputs with every component distinct and signed, so a wrong index or sign shows.
ImuInputs test_inputs() {
  return {Eigen::Vector3d(12.0, -34.0, 56.0), Eigen::Vector3d(1.5, -2.5, 9.1), 40.0};
}

struct TermCase {
  const char* parameter;
  double value;
  // Expected {gyro, accel} error for test_inputs() from the contract formula.
  std::function<std::pair<Eigen::Vector3d, Eigen::Vector3d>(double)> expected;
};

Eigen::Vector3d unit(int i, double v) {
  Eigen::Vector3d e = Eigen::Vector3d::Zero();
  e[i] = v;
  return e;
}

const Eigen::Vector3d kZero = Eigen::Vector3d::Zero();

// One row per kind of term, each written from error-model.md's table by hand.
std::vector<TermCase> cases() {
  const ImuInputs in = test_inputs();
  const Eigen::Vector3d& w = in.rate_dps;
  const Eigen::Vector3d& f = in.force_mps2;
  const double dT = in.temperature_c - 25.0;
  return {
      {"gyro_bias.y", 0.01,
       [](double v) {
         return std::pair{unit(1, v), kZero};
       }},
      {"gyro_scale.z", 300.0,
       [w](double v) {
         return std::pair{unit(2, 1e-6 * v * w.z()), kZero};
       }},
      // M[i][j] couples w_j into axis i: .xz puts w_z into x.
      {"gyro_misalignment.xz", 1e-3,
       [w](double v) {
         return std::pair{unit(0, v * w.z()), kZero};
       }},
      {"gyro_misalignment.zy", -2e-3,
       [w](double v) {
         return std::pair{unit(2, v * w.y()), kZero};
       }},
      {"gyro_scale_asymmetry.y", 500.0,
       [w](double v) {
         return std::pair{unit(1, 1e-6 * v * std::abs(w.y())), kZero};
       }},
      {"gyro_quadratic.x", 2.0,
       [w](double v) {
         return std::pair{unit(0, 1e-6 * v * w.x() * w.x()), kZero};
       }},
      // .xz: gyro x sensing specific force along z.
      {"gyro_g_sensitivity.xz", 0.01,
       [f](double v) {
         return std::pair{unit(0, v * f.z() / g0), kZero};
       }},
      {"gyro_g_sensitivity.yx", -0.02,
       [f](double v) {
         return std::pair{unit(1, v * f.x() / g0), kZero};
       }},
      {"gyro_temp_bias.y1", 1e-4,
       [dT](double v) {
         return std::pair{unit(1, v * dT), kZero};
       }},
      {"gyro_temp_bias.z2", 1e-6,
       [dT](double v) {
         return std::pair{unit(2, v * dT * dT), kZero};
       }},
      {"gyro_temp_bias.x3", 1e-8,
       [dT](double v) {
         return std::pair{unit(0, v * dT * dT * dT), kZero};
       }},
      {"gyro_temp_scale.x", 10.0,
       [w, dT](double v) {
         return std::pair{unit(0, 1e-6 * v * dT * w.x()), kZero};
       }},
      {"accel_bias.z", 0.003,
       [](double v) {
         return std::pair{kZero, unit(2, v)};
       }},
      {"accel_scale.x", 400.0,
       [f](double v) {
         return std::pair{kZero, unit(0, 1e-6 * v * f.x())};
       }},
      {"accel_misalignment.yx", 5e-4,
       [f](double v) {
         return std::pair{kZero, unit(1, v * f.x())};
       }},
      {"accel_scale_asymmetry.y", 200.0,
       [f](double v) {
         return std::pair{kZero, unit(1, 1e-6 * v * std::abs(f.y()))};
       }},
      {"accel_quadratic.z", 50.0,
       [f](double v) {
         return std::pair{kZero, unit(2, 1e-6 * g0 * v * std::pow(f.z() / g0, 2))};
       }},
      {"accel_temp_bias.x1", 2e-4,
       [dT](double v) {
         return std::pair{kZero, unit(0, v * dT)};
       }},
      {"accel_temp_bias.y2", 3e-6,
       [dT](double v) {
         return std::pair{kZero, unit(1, v * dT * dT)};
       }},
      {"accel_temp_scale.z", 20.0,
       [f, dT](double v) {
         return std::pair{kZero, unit(2, 1e-6 * v * dT * f.z())};
       }},
  };
}

TEST(DeterministicErrors, EveryTermMatchesItsContractFormula) {
  for (const TermCase& c : cases()) {
    ImuTruth truth;
    truth.set_parameter(c.parameter, c.value);
    const auto [gyro, accel] = deterministic_errors(truth, test_inputs());
    const auto [want_gyro, want_accel] = c.expected(c.value);
    EXPECT_NEAR((gyro - want_gyro).norm(), 0.0, 1e-15 + 1e-12 * want_gyro.norm()) << c.parameter;
    EXPECT_NEAR((accel - want_accel).norm(), 0.0, 1e-15 + 1e-12 * want_accel.norm()) << c.parameter;
    EXPECT_DOUBLE_EQ(truth.parameter(c.parameter), c.value) << c.parameter;
  }
}

TEST(DeterministicErrors, PerfectSensorHasNoError) {
  const auto [gyro, accel] = deterministic_errors(ImuTruth{}, test_inputs());
  EXPECT_EQ(gyro, kZero);
  EXPECT_EQ(accel, kZero);
}

TEST(DeterministicErrors, TermsAdd) {
  ImuTruth truth;
  truth.set_parameter("gyro_bias.x", 0.5);
  truth.set_parameter("gyro_scale.x", 1000.0);
  const auto [gyro, accel] = deterministic_errors(truth, test_inputs());
  EXPECT_NEAR(gyro.x(), 0.5 + 1e-3 * 12.0, 1e-12);
}

core::TableGeometry default_table() { return {}; }

const Eigen::Vector2d kNoTilt = Eigen::Vector2d::Zero();

core::Site site_at(double lat) {
  core::Site s;
  s.latitude_deg = lat;
  s.gravity_mps2 = 9.8;
  return s;
}

TEST(ImuInputs, StaticLevelSeesGravityUpAndEarthRate) {
  const ImuTruth truth;
  const auto in =
      imu_inputs(truth, default_table(), site_at(30.0), kNoTilt, TableKinematics{}, 25.0);
  EXPECT_NEAR((in.force_mps2 - Eigen::Vector3d(0, 0, 9.8)).norm(), 0.0, 1e-12);
  const double W = core::kEarthRateRadPerS * core::kRadToDeg;
  EXPECT_NEAR((in.rate_dps - Eigen::Vector3d(0, W * std::cos(core::kPi / 6), W * 0.5)).norm(), 0.0,
              1e-15);
}

TEST(ImuInputs, TableRateAddsToEarthRateInBody) {
  const ImuTruth truth;
  TableKinematics k;
  k.inner_rate_dps = -50.0;  // CW about Up, body z up
  const auto in = imu_inputs(truth, default_table(), site_at(0.0), kNoTilt, k, 25.0);
  EXPECT_NEAR(in.rate_dps.z(), -50.0, 1e-12);  // Earth rate has no Up part at the equator
  EXPECT_NEAR(in.rate_dps.y(), core::kEarthRateRadPerS * core::kRadToDeg, 1e-15);
}

// The contract's table_tilt: f = C_BL (I - [t x]) f_L. The simulator rotates exactly; the
// contract's model is first order, so they agree to g t^2 and differ from level by ~g t.
void expect_tilt_matches_contract(const core::TableGeometry& geo, const TableKinematics& k,
                                  const Eigen::Vector2d& tilt) {
  const ImuTruth truth;
  const core::Site site = site_at(45.0);
  const auto in = imu_inputs(truth, geo, site, tilt, k, 25.0);
  const Eigen::Matrix3d C_BL = geo.body_to_level(k.outer_deg, k.inner_deg).transpose();
  const Eigen::Vector3d t(tilt.x(), tilt.y(), 0.0);
  const Eigen::Vector3d f_L(0, 0, 9.8);
  const Eigen::Vector3d linear = C_BL * (Eigen::Matrix3d::Identity() - core::skew(t)) * f_L;
  EXPECT_NEAR((in.force_mps2 - linear).norm(), 0.0, 9.8 * t.squaredNorm());
  EXPECT_GT((in.force_mps2 - C_BL * f_L).norm(), 0.5 * 9.8 * t.norm());
}

TEST(ImuInputs, TableTiltMatchesTheLinearContractModel) {
  TableKinematics k;
  k.outer_deg = 37.0;
  k.inner_deg = -21.0;
  expect_tilt_matches_contract(default_table(), k, {2e-4, -3e-4});  // east, north [rad]
}

TEST(ImuInputs, TableTiltMatchesTheContractOnAnyGeometry) {
  core::TableGeometry geo;
  geo.outer_axis = Eigen::Vector3d(1, 0, 0);                     // East
  geo.inner_axis = Eigen::Vector3d(0, 0.6, 0.8);                 // not vertical at zero
  geo.mount_C_PB = core::from_roll_pitch_yaw_deg({10, -5, 90});  // rotated mount
  TableKinematics k;
  k.outer_deg = -63.0;
  k.inner_deg = 118.0;
  expect_tilt_matches_contract(geo, k, {-4e-4, 1e-4});
  expect_tilt_matches_contract(geo, {}, {0.0, 2e-3});
}

TEST(ImuInputs, TiltedBaseTiltsTheEarthRateWithGravity) {
  // The whole table stands on the tilted base, so the Earth rate reaches the body through the
  // same rotation as gravity: w = C_BL (I - [t x]) w_ie to first order.
  const ImuTruth truth;
  const core::Site site = site_at(30.0);
  const Eigen::Vector2d tilt(1e-2, -2e-2);  // large enough to show in the Earth rate
  TableKinematics k;
  k.outer_deg = 90.0;
  k.inner_deg = 30.0;
  const core::TableGeometry geo = default_table();
  const auto in = imu_inputs(truth, geo, site, tilt, k, 25.0);
  const Eigen::Matrix3d C_BL = geo.body_to_level(k.outer_deg, k.inner_deg).transpose();
  const Eigen::Vector3d t(tilt.x(), tilt.y(), 0.0);
  const Eigen::Vector3d w_ie = site.earth_rate_level_radps() * core::kRadToDeg;
  const Eigen::Vector3d linear = C_BL * (Eigen::Matrix3d::Identity() - core::skew(t)) * w_ie;
  EXPECT_NEAR((in.rate_dps - linear).norm(), 0.0, w_ie.norm() * t.squaredNorm());
  EXPECT_GT((in.rate_dps - C_BL * w_ie).norm(), 0.5 * w_ie.norm() * t.norm());
  // A table rate is about the (tilted) table's own axes: it adds in the body unchanged.
  k.inner_rate_dps = 50.0;
  const auto turning = imu_inputs(truth, geo, site, tilt, k, 25.0);
  EXPECT_NEAR(
      (turning.rate_dps - in.rate_dps - C_BL * geo.table_rate_level_dps(90.0, 0.0, 50.0)).norm(),
      0.0, 1e-12);
}

TEST(ImuInputs, LeverArmAddsCentripetalAndTangentialAcceleration) {
  ImuTruth truth;
  truth.accel_lever_arm = {0.1, 0.0, 0.0};  // 10 cm along body x
  TableKinematics k;
  k.inner_rate_dps = 180.0;  // pi rad/s about Up (body z)
  const auto spin = imu_inputs(truth, default_table(), site_at(0.0), kNoTilt, k, 25.0);
  // wt x (wt x r) = -wt^2 r for r normal to wt: -pi^2 * 0.1 along x.
  EXPECT_NEAR(spin.force_mps2.x(), -core::kPi * core::kPi * 0.1, 1e-12);
  EXPECT_NEAR(spin.force_mps2.z(), 9.8, 1e-12);

  TableKinematics accel;
  accel.inner_accel_dps2 = 90.0;  // pi/2 rad/s^2 about z, at rest
  const auto tangential = imu_inputs(truth, default_table(), site_at(0.0), kNoTilt, accel, 25.0);
  // dwt/dt x r = (0,0,pi/2) x (0.1,0,0) = (0, 0.1 pi/2, 0).
  EXPECT_NEAR(tangential.force_mps2.y(), 0.1 * core::kPi / 2, 1e-12);
}

TEST(ImuTruthJson, RoundTripsEveryParameterAndNoiseFigure) {
  ImuTruth t;
  t.name = "unit-7";
  t.temperature_ref_c = 20.0;
  for (const TermCase& c : cases()) t.set_parameter(c.parameter, c.value);
  t.set_parameter("accel_lever_arm.y", 0.05);
  t.gyro_noise.white = Eigen::Vector3d(1e-3, 2e-3, 3e-3);
  t.gyro_noise.bias_instability.setConstant(1e-4);
  t.gyro_noise.gauss_markov_sigma.setConstant(2e-4);
  t.gyro_noise.gauss_markov_tau_s = 300;
  t.accel_noise.white.setConstant(4e-4);
  t.accel_noise.turn_on_bias.setConstant(5e-3);
  t.accel_noise.quantization = 1e-4;
  t.sample_rate_hz = 200;
  t.gyro_bandwidth_hz = 50;
  t.accel_bandwidth_hz = 30;
  const nlohmann::json doc = imu_truth_to_json(t);
  const ImuTruth back = imu_truth_from_json(doc, "roundtrip.json");
  EXPECT_EQ(back.name, "unit-7");
  EXPECT_EQ(back.nonzero_parameters(), t.nonzero_parameters());
  EXPECT_TRUE(back.gyro_noise.white.isApprox(t.gyro_noise.white, 1e-12));
  EXPECT_TRUE(back.accel_noise.turn_on_bias.isApprox(t.accel_noise.turn_on_bias, 1e-12));
  EXPECT_DOUBLE_EQ(back.gyro_noise.gauss_markov_tau_s, 300);
  EXPECT_DOUBLE_EQ(back.gyro_bandwidth_hz, 50);
  EXPECT_DOUBLE_EQ(back.accel_bandwidth_hz, 30);
  EXPECT_EQ(imu_truth_to_json(back), doc);
}

TEST(ImuTruthJson, ConvertsDatasheetNoiseUnits) {
  const auto doc = nlohmann::json::parse(R"({
    "format": "calstand-truth/1",
    "noise": {"gyro": {"arw_deg_per_sqrt_h": 0.6, "bias_instability_coefficient_deg_per_h": 3.6},
              "accel": {"vrw_mps_per_sqrt_h": 0.06, "bias_instability_coefficient_ug": [10, 20, 30]}}
  })");
  const ImuTruth t = imu_truth_from_json(doc, "units.json");
  // 0.6 deg/sqrt(h) = 0.6/60 deg/sqrt(s); 3.6 deg/h = 1e-3 deg/s.
  EXPECT_NEAR(t.gyro_noise.white.x(), 0.01, 1e-15);
  EXPECT_NEAR(t.gyro_noise.bias_instability.z(), 1e-3, 1e-15);
  EXPECT_NEAR(t.accel_noise.white.y(), 1e-3, 1e-15);
  EXPECT_NEAR(t.accel_noise.bias_instability.z(), 30e-6 * g0, 1e-15);
}

TEST(ImuTruthJson, NamesTheBadParameterAndTheFile) {
  auto doc = nlohmann::json::parse(R"({"format": "calstand-truth/1",
                                       "parameters": {"gyro_misalignment.xx": 0.1}})");
  try {
    imu_truth_from_json(doc, "dut.json");
    FAIL() << "expected an InputError";
  } catch (const core::InputError& e) {
    const std::string text = e.what();
    EXPECT_NE(text.find("dut.json"), std::string::npos) << text;
    EXPECT_NE(text.find("gyro_misalignment.xx"), std::string::npos) << text;
  }
  doc = nlohmann::json::parse(R"({"format": "calstand-truth/1", "noise": {"gyro": {"arw": 1}},
                                  "output": {"sample_rate_hz": -5}})");
  try {
    imu_truth_from_json(doc, "dut.json");
    FAIL() << "expected a SchemaError";
  } catch (const core::SchemaError& e) {
    EXPECT_EQ(e.violations().size(), 2u) << e.what();
  }
}

TEST(ImuTruthJson, TableTiltIsRefusedAsAStationProperty) {
  const auto doc = nlohmann::json::parse(R"({"format": "calstand-truth/1",
                                             "parameters": {"table_tilt.east": 1e-4}})");
  try {
    imu_truth_from_json(doc, "dut.json");
    FAIL() << "expected an InputError";
  } catch (const core::InputError& e) {
    const std::string text = e.what();
    EXPECT_NE(text.find("dut.json"), std::string::npos) << text;
    EXPECT_NE(text.find("table_tilt.east"), std::string::npos) << text;
    EXPECT_NE(text.find("station file (table.tilt_rad)"), std::string::npos) << text;
  }
  ImuTruth t;
  EXPECT_THROW(t.set_parameter("table_tilt.north", 1e-4), core::InputError);
  EXPECT_EQ(t.parameter("table_tilt.north"), 0.0);
}

// The text of the InputError validate() throws, or "" when the truth is valid.
std::string validation_error(const ImuTruth& t) {
  try {
    t.validate("mine.json");
  } catch (const core::InputError& e) {
    return e.what();
  }
  return "";
}

TEST(ImuTruthValidate, NamesTheFieldTheValueInFileUnitsAndTheRule) {
  EXPECT_EQ(validation_error(ImuTruth{}), "");
  ImuTruth t;
  t.gyro_noise.white.setConstant(-0.07 / 60.0);  // -0.07 deg/sqrt(h)
  EXPECT_EQ(validation_error(t),
            "mine.json: noise.gyro.arw_deg_per_sqrt_h: -0.07 must not be negative");
  t = ImuTruth{};
  t.accel_noise.bias_instability = Eigen::Vector3d(0, -10e-6 * g0, 0);  // -10 ug on y alone
  EXPECT_EQ(validation_error(t),
            "mine.json: noise.accel.bias_instability_coefficient_ug[1]: -10 must not be negative");
  t = ImuTruth{};
  t.gyro_noise.gauss_markov_tau_s = 0.0;
  EXPECT_EQ(validation_error(t), "mine.json: noise.gyro.gauss_markov_tau_s: 0 must be positive");
  t = ImuTruth{};
  t.accel_noise.random_walk.setConstant(std::nan(""));
  EXPECT_NE(
      validation_error(t).find("noise.accel.random_walk_ug_per_sqrt_h[0]: nan must be finite"),
      std::string::npos)
      << validation_error(t);
  t = ImuTruth{};
  t.sample_rate_hz = std::numeric_limits<double>::infinity();
  EXPECT_EQ(validation_error(t), "mine.json: output.sample_rate_hz: inf must be finite");
  t = ImuTruth{};
  t.accel_bandwidth_hz = -5.0;
  EXPECT_EQ(validation_error(t), "mine.json: output.accel_bandwidth_hz: -5 must not be negative");
  t = ImuTruth{};
  t.filter_order = 3;
  EXPECT_NE(validation_error(t).find("output.filter_order: 3 must be 2, 4, 6 or 8"),
            std::string::npos);
  t = ImuTruth{};
  t.set_parameter("gyro_bias.z", std::nan(""));
  EXPECT_NE(validation_error(t).find("parameters.gyro_bias.z: nan must be finite"),
            std::string::npos);
}

TEST(ImuTruth, ReadingAParameterLeavesTheTruthAsItIs) {
  const ImuTruth t;
  EXPECT_EQ(t.parameter("gyro_temp_bias.x3"), 0.0);  // beyond the stored orders: zero
  EXPECT_TRUE(t.gyro_temp_bias.empty());
  ImuTruth u;
  u.set_parameter("accel_temp_bias.y2", 3e-6);
  EXPECT_EQ(u.accel_temp_bias.size(), 2u);
  EXPECT_EQ(u.parameter("accel_temp_bias.y2"), 3e-6);
  EXPECT_EQ(u.parameter("accel_temp_bias.y1"), 0.0);
}

}  // namespace
}  // namespace calstand::sim

namespace calstand::sim {
namespace {

// The simulator's per-sample input model re-derives the table kinematics with each rotation
// computed once; it must agree with core::TableGeometry, the reference implementation.
TEST(ImuInputs, FastModelAgreesWithCoreGeometry) {
  core::TableGeometry geo;
  geo.outer_axis = Eigen::Vector3d(0.1, 0.99, 0.05).normalized();
  geo.inner_axis = Eigen::Vector3d(0.02, -0.03, 1.0).normalized();
  geo.mount_C_PB = core::from_roll_pitch_yaw_deg({1.0, -2.0, 90.0});
  ImuTruth truth;
  truth.accel_lever_arm = {0.05, -0.02, 0.1};
  const core::Site site = site_at(52.0);
  NormalSource rnd(99);
  for (int trial = 0; trial < 50; ++trial) {
    TableKinematics k{rnd.next() * 100, rnd.next() * 50, rnd.next() * 20,
                      rnd.next() * 100, rnd.next() * 80, rnd.next() * 30};
    const auto in = imu_inputs(truth, geo, site, kNoTilt, k, 25.0);
    const Eigen::Matrix3d C_BL = geo.body_to_level(k.outer_deg, k.inner_deg).transpose();
    const Eigen::Vector3d w_table =
        geo.table_rate_level_dps(k.outer_deg, k.outer_rate_dps, k.inner_rate_dps);
    const Eigen::Vector3d a_table = geo.table_accel_level_dps2(
        k.outer_deg, k.outer_rate_dps, k.inner_rate_dps, k.outer_accel_dps2, k.inner_accel_dps2);
    const Eigen::Vector3d wt = C_BL * w_table * core::kDegToRad;
    const Eigen::Vector3d alpha = C_BL * a_table * core::kDegToRad;
    const Eigen::Vector3d r = truth.accel_lever_arm;
    const Eigen::Vector3d want_rate =
        C_BL * (w_table + site.earth_rate_level_radps() * core::kRadToDeg);
    const Eigen::Vector3d want_force =
        C_BL * site.specific_force_level() + wt.cross(wt.cross(r)) + alpha.cross(r);
    EXPECT_NEAR((in.rate_dps - want_rate).norm(), 0.0, 1e-10) << trial;
    EXPECT_NEAR((in.force_mps2 - want_force).norm(), 0.0, 1e-10) << trial;
  }
}

}  // namespace
}  // namespace calstand::sim
