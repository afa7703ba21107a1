#include "sim/spec_sheet.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.hpp"
#include "core/json_schema.hpp"
#include "core/rotation.hpp"
#include "core/site.hpp"

namespace calstand::sim {
namespace {

TEST(SpecSheet, ShipsLn200AndAdis16488) {
  const auto names = builtin_spec_names();
  EXPECT_NE(std::find(names.begin(), names.end(), "ln200"), names.end());
  EXPECT_NE(std::find(names.begin(), names.end(), "adis16488"), names.end());
  EXPECT_FALSE(builtin_spec("ln100").has_value());
}

TEST(SpecSheet, Ln200NoiseFiguresConvertToSimulatorUnits) {
  const ImuTruth t = truth_from_spec(*builtin_spec("ln200"), "ln200", 1);
  // Gyro: ARW 0.07 deg/sqrt(h) = 0.07/60 deg/s/sqrt(Hz); bias variation 0.35 deg/h, 100 s.
  EXPECT_NEAR(t.gyro_noise.white.x(), 0.07 / 60.0, 1e-15);
  EXPECT_NEAR(t.gyro_noise.gauss_markov_sigma.y(), 0.35 / 3600.0, 1e-15);
  EXPECT_DOUBLE_EQ(t.gyro_noise.gauss_markov_tau_s, 100.0);
  EXPECT_NEAR(t.gyro_noise.turn_on_bias.z(), 3.0 / 3600.0, 1e-15);
  // Accel: 50 ug/sqrt(Hz) white; 50 ug bias variation with 60 s.
  EXPECT_NEAR(t.accel_noise.white.x(), 50e-6 * core::kStandardGravity, 1e-15);
  EXPECT_NEAR(t.accel_noise.gauss_markov_sigma.x(), 50e-6 * core::kStandardGravity, 1e-15);
  EXPECT_DOUBLE_EQ(t.accel_noise.gauss_markov_tau_s, 60.0);
  // Output: 400 Hz; each sensor has its own filter: accel 100 Hz, while the gyro's 500 Hz is
  // above Nyquist (200 Hz) and filters nothing.
  EXPECT_DOUBLE_EQ(t.sample_rate_hz, 400.0);
  EXPECT_DOUBLE_EQ(t.accel_bandwidth_hz, 100.0);
  EXPECT_DOUBLE_EQ(t.gyro_bandwidth_hz, 0.0);
}

TEST(SpecSheet, Adis16488InRunStabilityBecomesTheFlickerCoefficient) {
  const ImuTruth t = truth_from_spec(*builtin_spec("adis16488"), "adis16488", 1);
  // The sheet's 5.1 deg/h is the Allan deviation floor, which IEEE Std 952 puts at
  // sqrt(2 ln2 / pi) B for flicker of coefficient B; computed here independently.
  const double floor_per_coefficient = std::sqrt(2.0 * std::log(2.0) / std::acos(-1.0));
  EXPECT_NEAR(floor_per_coefficient, 0.6643, 1e-4);
  EXPECT_NEAR(t.gyro_noise.bias_instability.x() * 3600.0, 5.1 / floor_per_coefficient, 1e-12);
  EXPECT_NEAR(t.accel_noise.bias_instability.y() / (1e-3 * core::kStandardGravity),
              0.1 / floor_per_coefficient, 1e-12);  // 0.1 mg floor
  // Both sensors at 330 Hz, below Nyquist of 2460 Hz.
  EXPECT_DOUBLE_EQ(t.gyro_bandwidth_hz, 330.0);
  EXPECT_DOUBLE_EQ(t.accel_bandwidth_hz, 330.0);
  EXPECT_NEAR(t.gyro_noise.white.x() * 60.0, 0.26, 1e-12);
  EXPECT_EQ(t.gyro_temp_bias.size(), 1u);
  EXPECT_GT(t.gyro_g_sensitivity.cwiseAbs().maxCoeff(), 0.0);
}

// The repeatability and warm-up figures: a turn-on scale change per power-up, and a power-on
// bias transient drawn per axis with the sheet's time constant. They are drawn after every
// other figure, so the same sheet without them draws the same unit as before.
TEST(SpecSheet, ScaleRepeatabilityAndWarmUpBecomeTheTurnOnScaleAndThePowerOnTransient) {
  nlohmann::json spec = *builtin_spec("ln200");
  const ImuTruth plain = truth_from_spec(spec, "ln200", 4);
  spec["gyro"]["scale_factor_repeatability"] = "100 ppm";
  spec["accel"]["scale_factor_repeatability"] = "0.02 %";
  spec["gyro"]["warm_up_bias"] = "20 deg/h";
  spec["accel"]["warm_up_bias"] = "0.2 mg";
  spec["output"]["warm_up_time_constant"] = "2 min";
  const ImuTruth t = truth_from_spec(spec, "mine.json", 4);
  EXPECT_DOUBLE_EQ(t.gyro_noise.turn_on_scale_ppm.x(), 100.0);
  EXPECT_DOUBLE_EQ(t.accel_noise.turn_on_scale_ppm.z(), 200.0);
  EXPECT_DOUBLE_EQ(t.power_on_time_constant_s, 120.0);
  EXPECT_TRUE(t.gyro_bias.isApprox(plain.gyro_bias));
  EXPECT_TRUE(t.accel_scale.isApprox(plain.accel_scale));
  // Drawn from N(0, figure): nonzero, and within 5 sigma.
  for (int i = 0; i < 3; ++i) {
    EXPECT_NE(t.gyro_power_on_bias[i], 0.0);
    EXPECT_LT(std::abs(t.gyro_power_on_bias[i]) * 3600.0, 5.0 * 20.0);
    EXPECT_LT(std::abs(t.accel_power_on_bias[i]), 5.0 * 0.2e-3 * core::kStandardGravity);
  }
  EXPECT_TRUE(plain.gyro_power_on_bias.isZero());
  // A warm-up without its time constant is refused, naming what is missing.
  spec["output"].erase("warm_up_time_constant");
  try {
    (void)truth_from_spec(spec, "mine.json", 4);
    ADD_FAILURE() << "accepted a warm-up bias without a time constant";
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("output.warm_up_time_constant"), std::string::npos)
        << e.what();
  }
}

TEST(SpecSheet, DrawnErrorsScatterAsTheFiguresSay) {
  // Over many drawn units, the misalignment spread equals the nonorthogonality figure.
  const auto spec = *builtin_spec("ln200");
  const double sigma_rad = 20.0 * core::kPi / (180.0 * 3600.0);
  double sum_sq = 0.0;
  int n = 0;
  for (std::uint64_t seed = 1; seed <= 400; ++seed) {
    const ImuTruth t = truth_from_spec(spec, "ln200", seed);
    EXPECT_EQ(t.gyro_misalignment.diagonal(), Eigen::Vector3d::Zero());
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) {
        if (i == j) continue;
        sum_sq += t.gyro_misalignment(i, j) * t.gyro_misalignment(i, j);
        ++n;
      }
    }
  }
  // 2400 draws: relative standard error of the RMS 1/sqrt(4800) = 1.4 %.
  EXPECT_NEAR(std::sqrt(sum_sq / n), sigma_rad, sigma_rad * 0.06);
}

TEST(SpecSheet, SameSeedSameUnit) {
  const auto spec = *builtin_spec("adis16488");
  const ImuTruth a = truth_from_spec(spec, "a", 5);
  const ImuTruth b = truth_from_spec(spec, "a", 5);
  const ImuTruth c = truth_from_spec(spec, "a", 6);
  EXPECT_EQ(a.nonzero_parameters(), b.nonzero_parameters());
  EXPECT_NE(a.nonzero_parameters(), c.nonzero_parameters());
}

TEST(SpecSheet, WrongUnitNamesTheField) {
  auto spec = *builtin_spec("ln200");
  spec["gyro"]["random_walk"] = "0.07 m/sqrt(h)";
  try {
    truth_from_spec(spec, "mine.json", 1);
    FAIL() << "expected an InputError";
  } catch (const core::InputError& e) {
    const std::string text = e.what();
    EXPECT_NE(text.find("mine.json"), std::string::npos) << text;
    EXPECT_NE(text.find("gyro.random_walk"), std::string::npos) << text;
    EXPECT_NE(text.find("dimensions differ"), std::string::npos) << text;
  }
  spec = *builtin_spec("ln200");
  spec["gyro"]["bias_repeatabilty"] = "1 deg/h";  // typo: unknown field
  EXPECT_THROW(truth_from_spec(spec, "mine.json", 1), core::SchemaError);
}

// The text of the error truth_from_spec throws for `spec`, or "" when it draws a unit.
std::string spec_error(const nlohmann::json& spec) {
  try {
    truth_from_spec(spec, "mine.json", 1);
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(SpecSheet, NegativeOrZeroFiguresNameTheSheetField) {
  auto spec = *builtin_spec("ln200");
  spec["gyro"]["random_walk"] = "-0.07 deg/sqrt(h)";
  EXPECT_EQ(spec_error(spec),
            "mine.json: gyro.random_walk: -0.07 deg/sqrt(h) must not be negative");
  spec = *builtin_spec("ln200");
  spec["accel"]["bias_variation"]["sigma"] = "-50 ug";
  EXPECT_EQ(spec_error(spec), "mine.json: accel.bias_variation.sigma: -50 ug must not be negative");
  spec = *builtin_spec("ln200");
  spec["accel"]["bias_variation"]["correlation_time"] = "0 s";
  EXPECT_EQ(spec_error(spec),
            "mine.json: accel.bias_variation.correlation_time: 0 s must be positive");
  spec = *builtin_spec("ln200");
  spec["output"]["sample_rate"] = "0 Hz";
  EXPECT_EQ(spec_error(spec), "mine.json: output.sample_rate: 0 Hz must be positive");
  spec = *builtin_spec("ln200");
  spec["gyro"]["bias_repeatability"] = "1e400 deg/h";  // overflows to infinity
  EXPECT_NE(spec_error(spec).find("gyro.bias_repeatability"), std::string::npos)
      << spec_error(spec);
  // Rates and times cannot carry a sign at all: the schema already refuses it.
  spec = *builtin_spec("ln200");
  spec["output"]["sample_rate"] = "-400 Hz";
  EXPECT_THROW(truth_from_spec(spec, "mine.json", 1), core::SchemaError);
}

}  // namespace
}  // namespace calstand::sim
