// Thermal calibration: polynomial recovery of known coefficients, the contract's names and
// units, and an end-to-end chain from simulated per-plateau six-position fits.

#include "solver/thermal.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/error.hpp"
#include "core/site.hpp"
#include "core/table_geometry.hpp"
#include "sim/imu_sim.hpp"
#include "sim/imu_truth.hpp"
#include "sim/noise.hpp"
#include "solver/classical.hpp"

namespace calstand::solver {
namespace {

double cubic(double dT) { return 0.0123 + 2.1e-4 * dT - 3.3e-6 * dT * dT + 4.7e-8 * dT * dT * dT; }

std::vector<ThermalPoint> cubic_points(double sigma) {
  std::vector<ThermalPoint> points;
  for (double t = -40.0; t <= 85.0; t += 12.5) points.push_back({t, cubic(t - 25.0), sigma});
  return points;
}

TEST(ThermalPolynomial, RecoversKnownCoefficientsNoiseless) {
  const ThermalPolynomial fit = thermal_polynomial(cubic_points(1e-4), 3);
  ASSERT_EQ(fit.coefficients.size(), 4);
  EXPECT_NEAR(fit.coefficients(0), 0.0123, 1e-9 * 0.0123);
  EXPECT_NEAR(fit.coefficients(1), 2.1e-4, 1e-9 * 2.1e-4);
  EXPECT_NEAR(fit.coefficients(2), -3.3e-6, 1e-9 * 3.3e-6);
  EXPECT_NEAR(fit.coefficients(3), 4.7e-8, 1e-9 * 4.7e-8);
  EXPECT_EQ(fit.dof, 11 - 4);
  EXPECT_LT(fit.chi2_dof, 1e-12);
  EXPECT_NEAR(fit.evaluate(60.0), cubic(35.0), 1e-15);
}

TEST(ThermalPolynomial, ReferenceTemperatureShiftsTheExpansion) {
  // The same cubic about T_ref = 0: c_0 becomes the value at 0 degC, c_1 its slope there.
  ThermalOptions options;
  options.temperature_ref_c = 0.0;
  const ThermalPolynomial fit = thermal_polynomial(cubic_points(1e-4), 3, options);
  const double h = 1e-3;
  EXPECT_NEAR(fit.coefficients(0), cubic(-25.0), 1e-13);
  EXPECT_NEAR(fit.coefficients(1), (cubic(-25.0 + h) - cubic(-25.0 - h)) / (2.0 * h), 1e-10);
}

TEST(ThermalPolynomial, NoisyWithinThreeSigmaAndHonest) {
  double sum_sq = 0.0;
  int count = 0;
  double chi2_sum = 0.0;
  const int trials = 400;
  for (std::uint64_t seed = 1; seed <= trials; ++seed) {
    sim::NormalSource normal(seed);
    std::vector<ThermalPoint> points = cubic_points(2e-4);
    for (ThermalPoint& p : points) p.value += 2e-4 * normal.next();
    const ThermalPolynomial fit = thermal_polynomial(points, 3);
    const double truth[] = {0.0123, 2.1e-4, -3.3e-6, 4.7e-8};
    for (int k = 0; k < 4; ++k) {
      const double z = (fit.coefficients(k) - truth[k]) / fit.sigmas(k);
      if (seed == 1) {
        EXPECT_LT(std::abs(z), 3.0) << "c" << k;
      }
      sum_sq += z * z;
      ++count;
    }
    chi2_sum += fit.chi2_dof;
  }
  EXPECT_NEAR(std::sqrt(sum_sq / count), 1.0, 0.06);
  EXPECT_NEAR(chi2_sum / trials, 1.0, 0.06);
}

TEST(ThermalPolynomial, ScaleByChi2InflatesOptimisticSigmas) {
  sim::NormalSource normal(3);
  std::vector<ThermalPoint> points = cubic_points(1e-4);
  for (ThermalPoint& p : points) p.value += 1e-3 * normal.next();  // ten times the claimed sigma
  const ThermalPolynomial plain = thermal_polynomial(points, 1);
  ThermalOptions options;
  options.scale_by_chi2 = true;
  const ThermalPolynomial scaled = thermal_polynomial(points, 1, options);
  EXPECT_GT(plain.chi2_dof, 10.0);
  EXPECT_TRUE(scaled.scaled_by_chi2);
  EXPECT_NEAR(scaled.sigmas(1), plain.sigmas(1) * std::sqrt(plain.chi2_dof), 1e-15);
  EXPECT_EQ(scaled.coefficients, plain.coefficients);
}

TEST(ThermalPolynomial, RefusesOrderAtOrAbovePlateauCount) {
  const std::vector<ThermalPoint> three{{-20.0, 0.1, 1e-3}, {25.0, 0.2, 1e-3}, {70.0, 0.4, 1e-3}};
  EXPECT_NO_THROW(thermal_polynomial(three, 2));  // exact interpolation, dof 0
  try {
    thermal_polynomial(three, 3);
    FAIL() << "order 3 on three plateaus accepted";
  } catch (const core::InputError& e) {
    EXPECT_EQ(e.where(), "thermal_polynomial");
    EXPECT_NE(std::string(e.what()).find("order 3 needs at least 4 temperature plateaus, 3 given"),
              std::string::npos)
        << e.what();
  }
}

TEST(ThermalPolynomial, RefusesDegenerateOrBadPoints) {
  // Four plateaus but only two temperatures: a quadratic is not determined.
  const std::vector<ThermalPoint> repeated{
      {10.0, 0.1, 1e-3}, {10.0, 0.11, 1e-3}, {40.0, 0.2, 1e-3}, {40.0, 0.21, 1e-3}};
  try {
    thermal_polynomial(repeated, 2);
    FAIL() << "two distinct temperatures accepted for order 2";
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("2 given"), std::string::npos) << e.what();
  }
  EXPECT_NO_THROW(thermal_polynomial(repeated, 1));
  EXPECT_THROW(thermal_polynomial({{10.0, 0.1, 0.0}, {20.0, 0.2, 1e-3}}, 1), core::InputError);
  EXPECT_THROW(thermal_polynomial({{10.0, NAN, 1e-3}, {20.0, 0.2, 1e-3}}, 1), core::InputError);
  EXPECT_THROW(thermal_polynomial({{10.0, 0.1, 1e-3}, {20.0, 0.2, 1e-3}}, -1), core::InputError);
}

TEST(ThermalCalibration, NamesAndUnitsFollowTheContract) {
  std::vector<ThermalPlateau> plateaus;
  for (double t : {-10.0, 10.0, 25.0, 45.0, 70.0}) {
    const double dT = t - 25.0;
    plateaus.push_back({t,
                        {{"gyro_bias.y", 0.002 + 1e-5 * dT + 2e-7 * dT * dT, 1e-5, "deg/s"},
                         {"accel_bias.z", -0.01 + 3e-4 * dT - 1e-6 * dT * dT, 1e-4, "m/s^2"}}});
  }
  const std::vector<ClassicalEstimate> out = thermal_calibration(plateaus, 2);
  ASSERT_EQ(out.size(), 6u);
  EXPECT_EQ(out[0].name, "gyro_bias.y");
  EXPECT_EQ(out[0].unit, "deg/s");
  EXPECT_NEAR(out[0].value, 0.002, 1e-12);
  EXPECT_EQ(out[1].name, "gyro_temp_bias.y1");
  EXPECT_EQ(out[1].unit, "deg/s/degC");
  EXPECT_NEAR(out[1].value, 1e-5, 1e-13);
  EXPECT_EQ(out[2].name, "gyro_temp_bias.y2");
  EXPECT_EQ(out[2].unit, "deg/s/degC^2");
  EXPECT_NEAR(out[2].value, 2e-7, 1e-15);
  EXPECT_GT(out[2].sigma, 0.0);
  EXPECT_EQ(out[5].name, "accel_temp_bias.z2");
  EXPECT_EQ(out[5].unit, "m/s^2/degC^2");
  EXPECT_NEAR(out[5].value, -1e-6, 1e-14);
}

TEST(ThermalCalibration, RefusesWhatTheContractLacks) {
  const std::vector<ThermalPlateau> misalignment{
      {0.0, {{"gyro_misalignment.xy", 1e-3, 1e-5, "rad"}}},
      {50.0, {{"gyro_misalignment.xy", 1e-3, 1e-5, "rad"}}}};
  EXPECT_THROW(thermal_calibration(misalignment, 1), core::InputError);
  const std::vector<ThermalPlateau> scale{{0.0, {{"gyro_scale.x", 100.0, 1.0, "ppm"}}},
                                          {30.0, {{"gyro_scale.x", 103.0, 1.0, "ppm"}}},
                                          {60.0, {{"gyro_scale.x", 107.0, 1.0, "ppm"}}}};
  try {
    thermal_calibration(scale, 2);
    FAIL() << "quadratic temperature scale accepted";
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("gyro_temp_scale is linear"), std::string::npos)
        << e.what();
  }
  std::vector<ThermalPlateau> missing = scale;
  missing[1].parameters[0].name = "gyro_scale.y";
  EXPECT_THROW(thermal_calibration(missing, 1), core::InputError);
  try {
    thermal_calibration(scale, 3);
    FAIL();
  } catch (const core::InputError& e) {
    // The parameter is named along with the order and the plateau count.
    const std::string what = e.what();
    EXPECT_NE(what.find("gyro_scale.x"), std::string::npos) << what;
  }
}

// End to end: six-position fits of the simulated IMU on each plateau (noiseless means plus
// seeded noise), then the thermal fit of the plateau biases and scales.
TEST(ThermalCalibration, RecoversSimulatedTemperatureTermsFromPlateauFits) {
  sim::ImuTruth truth;
  truth.accel_bias = {0.02, -0.01, 0.03};
  truth.accel_scale = {200.0, -100.0, 50.0};
  truth.accel_temp_bias = {Eigen::Vector3d(1e-4, -2e-4, 3e-4), Eigen::Vector3d(-2e-6, 1e-6, 4e-6)};
  truth.accel_temp_scale = {1.5, -2.0, 0.8};
  core::Site site;
  site.latitude_deg = 45.0;
  site.gravity_mps2 = 9.806;
  const std::vector<std::pair<double, double>> angles{{-90.0, 0.0},  {90.0, 0.0}, {-90.0, -90.0},
                                                      {90.0, -90.0}, {0.0, 0.0},  {180.0, 0.0}};
  const double sigma = 5e-5;
  MatrixFitOptions fit_options;
  fit_options.measurement_sigma = Eigen::Vector3d::Constant(sigma);
  sim::NormalSource normal(17);

  std::vector<ThermalPlateau> plateaus;
  for (double t : {-20.0, 0.0, 25.0, 50.0, 75.0}) {
    Eigen::Matrix<double, 3, 6> U;
    Eigen::Matrix<double, 4, 6> A;
    for (int k = 0; k < 6; ++k) {
      sim::TableKinematics table;
      table.outer_deg = angles[static_cast<std::size_t>(k)].first;
      table.inner_deg = angles[static_cast<std::size_t>(k)].second;
      const sim::ImuInputs in =
          sim::imu_inputs(truth, core::TableGeometry{}, site, Eigen::Vector2d::Zero(), table, t);
      const Eigen::Vector3d accel_err = sim::deterministic_errors(truth, in).second;
      for (int i = 0; i < 3; ++i) U(i, k) = in.force_mps2(i) + accel_err(i) + sigma * normal.next();
      A.col(k) << in.force_mps2, 1.0;
    }
    const MatrixCalibration fit = six_position(U, A, fit_options);
    ThermalPlateau plateau{t, {}};
    for (const ClassicalEstimate& e : named_parameters(fit, ClassicalSensor::kAccel)) {
      if (e.name.find("misalignment") == std::string::npos) plateau.parameters.push_back(e);
    }
    plateaus.push_back(plateau);
  }

  const auto find = [](const std::vector<ClassicalEstimate>& v, const std::string& name) {
    for (const ClassicalEstimate& e : v) {
      if (e.name == name) return e;
    }
    ADD_FAILURE() << name << " missing";
    return ClassicalEstimate{};
  };
  const auto within = [](const ClassicalEstimate& e, double truth_value) {
    EXPECT_LT(std::abs(e.value - truth_value), 3.0 * e.sigma)
        << e.name << " " << e.value << " vs " << truth_value << " sigma " << e.sigma;
    EXPECT_GT(e.sigma, 0.0) << e.name;
  };

  // Biases: quadratic in dT.
  std::vector<ThermalPlateau> bias_plateaus = plateaus;
  for (ThermalPlateau& p : bias_plateaus)
    std::erase_if(p.parameters, [](const ClassicalEstimate& e) {
      return e.name.find("scale") != std::string::npos;
    });
  const std::vector<ClassicalEstimate> bias = thermal_calibration(bias_plateaus, 2);
  const char axes[] = {'x', 'y', 'z'};
  for (int i = 0; i < 3; ++i) {
    const std::string a(1, axes[i]);
    within(find(bias, "accel_bias." + a), truth.accel_bias(i));
    within(find(bias, "accel_temp_bias." + a + "1"), truth.accel_temp_bias[0](i));
    within(find(bias, "accel_temp_bias." + a + "2"), truth.accel_temp_bias[1](i));
  }
  // Scales: linear in dT (ppm and ppm/degC).
  std::vector<ThermalPlateau> scale_plateaus = plateaus;
  for (ThermalPlateau& p : scale_plateaus)
    std::erase_if(p.parameters, [](const ClassicalEstimate& e) {
      return e.name.find("bias") != std::string::npos;
    });
  const std::vector<ClassicalEstimate> scale = thermal_calibration(scale_plateaus, 1);
  for (int i = 0; i < 3; ++i) {
    const std::string a(1, axes[i]);
    within(find(scale, "accel_scale." + a), truth.accel_scale(i));
    const ClassicalEstimate d = find(scale, "accel_temp_scale." + a);
    EXPECT_EQ(d.unit, "ppm/degC");
    within(d, truth.accel_temp_scale(i));
  }
}

}  // namespace
}  // namespace calstand::solver
