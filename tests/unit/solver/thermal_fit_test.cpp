// Per-plateau thermal calibration: recovery of a simulated unit's temperature terms, exact
// agreement with one fit holding the temperature terms, and the input errors.

#include "solver/thermal_fit.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "sim/noise.hpp"
#include "sim_run.hpp"

namespace calstand::solver {
namespace {

using testing::SimStep;
using testing::simulate_run;
using testing::white_noise_truth;

const char* kThermalBaseModel =
    "gyro_bias,gyro_scale,gyro_misalignment,earth_rate,accel_bias,accel_scale,accel_misalignment";
const std::vector<double> kPlateausC = {-20.0, 5.0, 30.0, 60.0};

/// A unit with bias, scale, misalignment and temperature terms: order-2 temperature bias and a
/// linear temperature scale on both triads (magnitudes of a tactical MEMS unit).
sim::ImuTruth thermal_unit(std::uint64_t seed) {
  sim::NormalSource n(seed * 104729 + 5);
  sim::ImuTruth t = white_noise_truth();
  testing::draw_classical_errors(t, n);
  t.gyro_temp_bias = {Eigen::Vector3d(4e-5, -3e-5, 2e-5),      // deg/s/degC
                      Eigen::Vector3d(8e-7, -5e-7, 6e-7)};     // deg/s/degC^2
  t.gyro_temp_scale = Eigen::Vector3d(3.0, -2.0, 1.5);         // ppm/degC
  t.accel_temp_bias = {Eigen::Vector3d(1e-4, -6e-5, 5e-5),     // m/s^2/degC
                       Eigen::Vector3d(2e-6, -1.5e-6, 1e-6)};  // m/s^2/degC^2
  t.accel_temp_scale = Eigen::Vector3d(2.0, -1.5, 1.0);        // ppm/degC
  return t;
}

/// Six positions and rate steps (whole turns) on each plateau.
std::vector<SimStep> plateau_campaign(const std::vector<double>& plateaus_c) {
  std::vector<SimStep> steps;
  for (double temp : plateaus_c) {
    for (const SimStep& s : testing::six_positions(temp)) steps.push_back(s);
    for (const SimStep& s : testing::rate_steps({20.0, 100.0}, temp)) steps.push_back(s);
  }
  return steps;
}

const ClassicalEstimate* find_estimate(const std::vector<ClassicalEstimate>& list,
                                       const std::string& name) {
  for (const auto& e : list) {
    if (e.name == name) return &e;
  }
  return nullptr;
}

TEST(ThermalFit, RecoversTemperatureTermsWithinThreeSigma) {
  const sim::ImuTruth truth = thermal_unit(1);
  const RunData data = simulate_run(truth, plateau_campaign(kPlateausC), 1);
  const Model model = Model::parse(kThermalBaseModel);
  const std::vector<StepSummary> steps = summarize_steps(data, model);
  ThermalFitOptions options;
  options.temperature_ref_c = data.setup.temperature_ref_c;
  const ThermalFitResult r = fit_per_plateau(steps, model, 2, measure_noise_floor(steps), options);

  ASSERT_EQ(r.plateaus.size(), 4u);
  for (std::size_t p = 0; p < 4; ++p) {
    EXPECT_NEAR(r.plateaus[p].temperature_c, kPlateausC[p], 1e-9);
    EXPECT_EQ(r.plateaus[p].steps, 6u + 12u);
    EXPECT_TRUE(r.plateaus[p].unidentifiable.empty());
    EXPECT_LT(r.plateaus[p].chi2_dof, 2.0);  // the per-plateau model is complete
  }
  EXPECT_TRUE(r.skipped.empty());
  // Per sensor and axis: c_0, two bias orders, scale and its temperature slope.
  ASSERT_EQ(r.coefficients.size(), 2u * 3u * (3u + 2u));
  ASSERT_EQ(r.constants.size(), 12u);  // misalignments
  for (const char* sensor : {"gyro", "accel"}) {
    for (const char* axis : {"x", "y", "z"}) {
      const std::string s(sensor);
      const std::string a(axis);
      for (const std::string& name :
           {s + "_bias." + a, s + "_temp_bias." + a + "1", s + "_temp_bias." + a + "2",
            s + "_scale." + a, s + "_temp_scale." + a}) {
        const ClassicalEstimate* e = find_estimate(r.coefficients, name);
        ASSERT_NE(e, nullptr) << name;
        const double want = truth.parameter(name);
        EXPECT_NEAR(e->value, want, 3.0 * e->sigma) << name;
        // The temperature terms are resolved, not merely "within a huge sigma".
        if (name.find("_temp_") != std::string::npos) {
          EXPECT_LT(3.0 * e->sigma, std::abs(want)) << name;
        }
      }
    }
  }
  for (const ClassicalEstimate& e : r.constants) {
    EXPECT_NEAR(e.value, truth.parameter(e.name), 3.0 * e.sigma) << e.name;
  }
  EXPECT_EQ(find_estimate(r.coefficients, "gyro_temp_bias.x2")->unit, "deg/s/degC^2");
  EXPECT_EQ(find_estimate(r.coefficients, "accel_temp_scale.z")->unit, "ppm/degC");
}

// Six positions per plateau: bias, scale and misalignment columns are orthogonal on each
// plateau, so the two-stage result equals one fit holding the temperature terms exactly.
TEST(ThermalFit, EqualsOneFitWithTemperatureTermsOnAnOrthogonalDesign) {
  const sim::ImuTruth truth = thermal_unit(2);
  std::vector<SimStep> sim_steps;
  for (double temp : kPlateausC) {
    for (const SimStep& s : testing::six_positions(temp)) sim_steps.push_back(s);
  }
  const RunData data = simulate_run(truth, sim_steps, 2);
  const Model single_model =
      Model::parse("accel_bias,accel_scale,accel_misalignment,accel_temp_bias:2,accel_temp_scale");
  const std::vector<StepSummary> all = summarize_steps(data, single_model);
  const NoiseFloor floor = measure_noise_floor(all);
  FitOptions fit_options;
  fit_options.rows = SensorRows::kAccel;
  fit_options.inflate_sigma_by_chi2 = false;
  const FitResult single = fit_model(all, single_model, floor, fit_options);

  const Model model = Model::parse("accel_bias,accel_scale,accel_misalignment");
  ThermalFitOptions options;
  options.fit = fit_options;
  options.temperature_ref_c = data.setup.temperature_ref_c;
  const ThermalFitResult r =
      fit_per_plateau(summarize_steps(data, model), model, 2, floor, options);
  ASSERT_EQ(r.coefficients.size(), 15u);
  for (const ClassicalEstimate& e : r.coefficients) {
    const auto it = std::find_if(single.parameters.begin(), single.parameters.end(),
                                 [&](const FittedParameter& p) { return p.name == e.name; });
    ASSERT_NE(it, single.parameters.end()) << e.name;
    EXPECT_NEAR(e.value, it->value, 1e-9 * std::max(std::abs(it->value), it->sigma)) << e.name;
    EXPECT_NEAR(e.sigma, it->sigma, 1e-7 * it->sigma) << e.name;
  }
}

TEST(ThermalFit, TooFewPlateausIsAnInputErrorNamingOrderAndCount) {
  const RunData data = simulate_run(thermal_unit(3), plateau_campaign({10.0, 40.0}), 3);
  const Model model = Model::parse(kThermalBaseModel);
  const std::vector<StepSummary> steps = summarize_steps(data, model);
  try {
    (void)fit_per_plateau(steps, model, 2, measure_noise_floor(steps));
    FAIL() << "expected core::InputError";
  } catch (const core::InputError& e) {
    EXPECT_EQ(e.where(), "fit_per_plateau");
    const std::string what = e.what();
    EXPECT_NE(what.find("order 2 needs at least 3 temperature plateaus"), std::string::npos)
        << what;
    EXPECT_NE(what.find("the run has 2"), std::string::npos) << what;
  }
  // Order 1 on the same two plateaus is fine.
  EXPECT_EQ(fit_per_plateau(steps, model, 1, measure_noise_floor(steps)).plateaus.size(), 2u);
}

TEST(ThermalFit, PlateauWithTooFewStepsIsAnInputErrorNamingIt) {
  std::vector<SimStep> sim_steps;
  for (double temp : {0.0, 30.0}) {
    for (const SimStep& s : testing::six_positions(temp)) sim_steps.push_back(s);
  }
  sim_steps.push_back(testing::six_positions(60.0).front());  // one step at 60 degC
  const RunData data = simulate_run(thermal_unit(4), sim_steps, 4);
  const Model model = Model::parse("accel_bias,accel_scale,accel_misalignment");
  const std::vector<StepSummary> steps = summarize_steps(data, model);
  ThermalFitOptions options;
  options.fit.rows = SensorRows::kAccel;
  try {
    (void)fit_per_plateau(steps, model, 1, measure_noise_floor(steps), options);
    FAIL() << "expected core::InputError";
  } catch (const core::InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("plateau at 60.0 degC has too few steps (1)"), std::string::npos) << what;
  }
}

TEST(ThermalFit, RejectsTemperatureTermsAndOrderBelowOne) {
  const RunData data = simulate_run(thermal_unit(5), plateau_campaign({10.0, 40.0}), 5);
  const Model with_temp = Model::parse(std::string(kThermalBaseModel) + ",gyro_temp_scale");
  const std::vector<StepSummary> steps = summarize_steps(data, with_temp);
  const NoiseFloor floor = measure_noise_floor(steps);
  try {
    (void)fit_per_plateau(steps, with_temp, 1, floor);
    FAIL() << "expected core::InputError";
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("gyro_temp_scale"), std::string::npos) << e.what();
  }
  const Model model = Model::parse(kThermalBaseModel);
  EXPECT_THROW((void)fit_per_plateau(summarize_steps(data, model), model, 0, floor),
               core::InputError);
}

TEST(ThermalFit, JsonHasTheDocumentedFields) {
  const RunData data = simulate_run(thermal_unit(6), plateau_campaign({0.0, 25.0, 50.0}), 6);
  const Model model = Model::parse(kThermalBaseModel);
  const std::vector<StepSummary> steps = summarize_steps(data, model);
  const nlohmann::json j =
      thermal_fit_to_json(fit_per_plateau(steps, model, 2, measure_noise_floor(steps)));
  for (const char* key : {"model", "order", "temperature_ref_c", "plateaus", "coefficients",
                          "constants", "polynomials", "skipped"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  EXPECT_EQ(j["order"], 2);
  ASSERT_EQ(j["plateaus"].size(), 3u);
  EXPECT_TRUE(j["plateaus"][0]["parameters"][0].contains("sigma"));
  EXPECT_TRUE(j["plateaus"][0].contains("chi2_dof"));
  EXPECT_EQ(j["coefficients"][1]["name"], "gyro_temp_bias.x1");
  EXPECT_EQ(j["polynomials"][0]["residuals"].size(), 3u);
}

}  // namespace
}  // namespace calstand::solver
