#include "solver/fit.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "core/error.hpp"
#include "sim/noise.hpp"
#include "sim_run.hpp"
#include "solver/noise_estimate.hpp"

namespace calstand::solver {
namespace {

using testing::kBaseModel;
using testing::simulate_run;
using testing::six_positions;
using testing::white_noise_truth;

/// A unit with bias, scale and misalignment drawn per seed (LN200-class magnitudes).
sim::ImuTruth random_unit(std::uint64_t seed) {
  sim::NormalSource n(seed * 7919 + 1);
  sim::ImuTruth t = white_noise_truth();
  testing::draw_classical_errors(t, n);
  return t;
}

std::vector<testing::SimStep> base_campaign() {
  std::vector<testing::SimStep> steps = six_positions();
  for (const auto& r : testing::rate_steps({20.0, 100.0})) steps.push_back(r);
  return steps;
}

FitResult fit_at_noise_floor(const RunData& data, const Model& model,
                             const FitOptions& options = {}) {
  const auto summaries = summarize_steps(data, model);
  return fit_model(summaries, model, measure_noise_floor(summaries), options);
}

double value_of(const FitResult& fit, const std::string& name) {
  for (const auto& p : fit.parameters) {
    if (p.name == name) return p.value;
  }
  ADD_FAILURE() << name << " not fitted";
  return 0.0;
}

TEST(Fit, RecoversTheTruthWithinThreeSigma) {
  const sim::ImuTruth truth = random_unit(1);
  const Model model = Model::parse(kBaseModel);
  const FitResult fit = fit_at_noise_floor(simulate_run(truth, base_campaign(), 1), model);
  EXPECT_TRUE(fit.unidentifiable.empty()) << fit.unidentifiable.front().name;
  ASSERT_EQ(fit.parameters.size(), model.size());
  for (const auto& p : fit.parameters) {
    EXPECT_NEAR(p.value, truth.parameter(p.name), 3.0 * p.sigma) << p.name;
    EXPECT_GT(p.sigma, 0.0) << p.name;
  }
  EXPECT_GT(fit.chi2_dof, 0.5);
  EXPECT_LT(fit.chi2_dof, 1.6);
  // With the right model the step residuals are at the noise floor.
  EXPECT_LT(fit.residual_rms_gyro_dps, 1.5 * fit.noise_floor.head<3>().maxCoeff());
  EXPECT_LT(fit.residual_rms_accel_mps2, 1.5 * fit.noise_floor.tail<3>().maxCoeff());
}

// Sigmas are honest: over seeds, (estimate - truth) / sigma has mean near 0 and spread near 1.
TEST(Fit, SigmasAreHonestOverSeeds) {
  const Model model = Model::parse(kBaseModel);
  std::vector<double> pulls;
  for (std::uint64_t seed = 1; seed <= 12; ++seed) {
    const sim::ImuTruth truth = random_unit(seed);
    const FitResult fit = fit_at_noise_floor(simulate_run(truth, base_campaign(), 100 + seed),
                                             model, {.inflate_sigma_by_chi2 = false});
    for (const auto& p : fit.parameters)
      pulls.push_back((p.value - truth.parameter(p.name)) / p.sigma);
  }
  double mean = 0.0, sq = 0.0;
  for (double z : pulls) {
    mean += z;
    sq += z * z;
  }
  mean /= static_cast<double>(pulls.size());
  const double rms = std::sqrt(sq / static_cast<double>(pulls.size()));
  // 12 seeds x 30 parameters: the spread of an honest rms is about 1/sqrt(2 * 360) = 0.04.
  EXPECT_NEAR(mean, 0.0, 0.15);
  EXPECT_GT(rms, 0.8);
  EXPECT_LT(rms, 1.25);
}

TEST(Fit, AMissingTermShowsInChiSquare) {
  sim::ImuTruth truth = random_unit(3);
  truth.gyro_g_sensitivity(0, 2) = 5e-3;  // (deg/s)/g: far above the step-mean noise
  const FitResult without =
      fit_at_noise_floor(simulate_run(truth, base_campaign(), 3), Model::parse(kBaseModel));
  EXPECT_GT(without.chi2_dof, 5.0);
  const FitResult with =
      fit_at_noise_floor(simulate_run(truth, base_campaign(), 3),
                         Model::parse(std::string(kBaseModel) + ",gyro_g_sensitivity"));
  EXPECT_LT(with.chi2_dof, 1.6);
  EXPECT_NEAR(value_of(with, "gyro_g_sensitivity.xz"), 5e-3, 5e-4);
}

// The classical six-position test of a gyro's g-sensitivity, with the classical model in the
// fit as users write it. At rest a gyro's scale and misalignment act only through the Earth
// rate, whose up component follows gravity: judged first in model order they took the span of
// three g-sensitivity columns, were then dropped as barely excited, and left those three
// held at zero (the fit missing by 40 deg/h on an ADIS16488-class unit).
TEST(Fit, ASixPositionRunDeterminesEveryGSensitivityTheScaleCannotTake) {
  const double g_sensitivity[3][3] = {// (deg/s)/g, ADIS16488-class sizes
                                      {-5.7e-3, 2.1e-3, 12.9e-3},
                                      {-6.4e-3, -24.1e-3, -12.4e-3},
                                      {6.3e-3, 8.3e-3, 5.0e-3}};
  // A unit with the default test noise (2e-3 deg/s/sqrt(Hz)), and a quiet one (1e-4), whose
  // misalignments at rest come out just under the bound of any real sensor's and so are not
  // dropped as barely excited: in model order they took the span of gyro_g_sensitivity.yy and
  // .zy.
  for (const double gyro_white : {2e-3, 1e-4}) {
    SCOPED_TRACE(fmt::format("gyro white noise {} deg/s/sqrt(Hz)", gyro_white));
    sim::ImuTruth truth = random_unit(5);
    truth.gyro_noise.white.setConstant(gyro_white);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) truth.gyro_g_sensitivity(i, j) = g_sensitivity[i][j];
    const FitResult fit =
        fit_at_noise_floor(simulate_run(truth, six_positions(25.0, 60.0), 5),
                           Model::parse(std::string(kBaseModel) + ",gyro_g_sensitivity"));
    const char axes[] = "xyz";
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) {
        const std::string name = fmt::format("gyro_g_sensitivity.{}{}", axes[i], axes[j]);
        const auto it = std::find_if(fit.parameters.begin(), fit.parameters.end(),
                                     [&](const FittedParameter& p) { return p.name == name; });
        ASSERT_NE(it, fit.parameters.end()) << name << " not fitted";
        EXPECT_NEAR(it->value, g_sensitivity[i][j], 4.0 * it->sigma) << name;
      }
    }
    // What the run cannot tell is said, and it is the scale and misalignment (barely excited,
    // or in a g-sensitivity's span), not the g-sensitivity.
    std::size_t scale_or_misalignment = 0;
    for (const auto& u : fit.unidentifiable) {
      EXPECT_EQ(u.name.rfind("gyro_g_sensitivity", 0), std::string::npos)
          << u.name << ": " << u.reason;
      if (u.name.rfind("gyro_scale", 0) == 0 || u.name.rfind("gyro_misalignment", 0) == 0)
        ++scale_or_misalignment;
    }
    EXPECT_GE(scale_or_misalignment, 6u);
    // The residual is the noise (the fit's own test at 1e-3).
    EXPECT_FALSE(above_noise(fit.chi2_dof_gyro, fit.dof_gyro))
        << fit.chi2_dof_gyro << " over " << fit.dof_gyro;
  }
}

TEST(Fit, AsymmetryWithoutBothDirectionsIsReportedNotFitted) {
  std::vector<testing::SimStep> steps = six_positions();
  for (const auto& r : testing::rate_steps({20.0, 100.0})) {
    if (r.inner_rate_dps >= 0.0 && r.outer_rate_dps >= 0.0) steps.push_back(r);  // CW only
  }
  const FitResult fit =
      fit_at_noise_floor(simulate_run(random_unit(4), steps, 4),
                         Model::parse("gyro_bias,gyro_scale,gyro_scale_asymmetry,earth_rate"),
                         {.rows = SensorRows::kGyro});
  std::map<std::string, Unidentifiable> flagged;
  for (const auto& u : fit.unidentifiable) flagged[u.name] = u;
  for (const char* axis : {"x", "y", "z"}) {
    const std::string name = std::string("gyro_scale_asymmetry.") + axis;
    ASSERT_TRUE(flagged.count(name)) << name;
    EXPECT_NE(std::find(flagged[name].related.begin(), flagged[name].related.end(),
                        std::string("gyro_scale.") + axis),
              flagged[name].related.end())
        << flagged[name].reason;
  }
  for (const auto& p : fit.parameters) EXPECT_EQ(p.name.find("asymmetry"), std::string::npos);
}

TEST(Fit, QuadraticWithOnlyPlusAndMinusOneGIsReported) {
  // Two positions: z up and z down. f_z^2 is g^2 in both, the same as a bias.
  std::vector<testing::SimStep> steps = six_positions();
  steps.resize(2);
  const FitResult fit = fit_at_noise_floor(simulate_run(random_unit(5), steps, 5),
                                           Model::parse("accel_bias,accel_scale,accel_quadratic"),
                                           {.rows = SensorRows::kAccel});
  bool flagged = false;
  for (const auto& u : fit.unidentifiable) {
    if (u.name == "accel_quadratic.z") {
      flagged = true;
      EXPECT_NE(std::find(u.related.begin(), u.related.end(), "accel_bias.z"), u.related.end());
    }
  }
  EXPECT_TRUE(flagged);
}

TEST(Fit, TemperatureOrderAtOrAbovePlateausIsReported) {
  std::vector<testing::SimStep> steps;
  for (double temp : {-10.0, 25.0}) {
    for (auto s : six_positions(temp)) steps.push_back(s);
  }
  const FitResult fit = fit_at_noise_floor(simulate_run(random_unit(6), steps, 6),
                                           Model::parse("accel_bias,accel_temp_bias:2"),
                                           {.rows = SensorRows::kAccel});
  std::vector<std::string> names;
  for (const auto& u : fit.unidentifiable) names.push_back(u.name);
  EXPECT_EQ(names, (std::vector<std::string>{"accel_temp_bias.x2", "accel_temp_bias.y2",
                                             "accel_temp_bias.z2"}));
  EXPECT_NE(fit.unidentifiable.front().reason.find("the run has 2"), std::string::npos);
}

TEST(Fit, CustomTermFollowingTemperatureRate) {
  // A bias proportional to dT/dt: not a catalogue term.
  sim::ImuTruth truth = random_unit(8);
  std::vector<testing::SimStep> steps;
  for (double ramp : {-2.0, 0.0, 1.0, 3.0}) {
    for (auto s : six_positions(25.0, 30.0)) {
      s.temperature_rate_cpm = ramp;
      steps.push_back(s);
    }
  }
  RunData data = simulate_run(truth, steps, 8);
  // Add 1e-3 deg/s per degC/min to gyro x, the effect the simulator lacks.
  for (auto& step : data.steps) {
    const std::vector<double> rates = step_temperature_rates(step.samples);
    for (std::size_t i = 0; i < step.samples.size(); ++i)
      step.samples[i].gyro_dps.x() += 1e-3 * rates[i];
  }
  const FitResult base =
      fit_at_noise_floor(data, Model::parse("gyro_bias,earth_rate"), {.rows = SensorRows::kGyro});
  EXPECT_GT(base.chi2_dof, 5.0);
  const FitResult custom =
      fit_at_noise_floor(data, Model::parse("gyro_bias,earth_rate", {"grad=gyro:temperature_rate"}),
                         {.rows = SensorRows::kGyro});
  EXPECT_LT(custom.chi2_dof, 1.6);
  EXPECT_NEAR(value_of(custom, "grad.x"), 1e-3, 2e-4);
}

TEST(Fit, TooFewRowsIsAnInputError) {
  std::vector<testing::SimStep> steps = six_positions();
  steps.resize(1);
  EXPECT_THROW((void)fit_at_noise_floor(simulate_run(random_unit(9), steps, 9),
                                        Model::parse("accel_bias,accel_scale"),
                                        {.rows = SensorRows::kAccel}),
               core::InputError);
}

TEST(Fit, JsonHasTheDocumentedFields) {
  const FitResult fit = fit_at_noise_floor(simulate_run(random_unit(10), base_campaign(), 10),
                                           Model::parse(kBaseModel));
  const nlohmann::json j = fit_to_json(fit);
  for (const char* key :
       {"model", "chi2_dof", "residual_rms", "noise_floor", "parameters", "unidentifiable"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  EXPECT_EQ(j["model"].size(), 7u);
  EXPECT_EQ(j["noise_floor"]["gyro"].size(), 3u);
  EXPECT_TRUE(j["parameters"][0].contains("sigma"));
  EXPECT_EQ(j["parameters"][0]["unit"], "deg/s");
}

// Each step of the JSON carries its time span and the mean of every signal, so that the
// residual can be drawn against what it follows (the console does) without the samples.
TEST(Fit, JsonStepsCarryTheirSignals) {
  const Model model = Model::parse(kBaseModel);
  const auto summaries = summarize_steps(simulate_run(random_unit(11), base_campaign(), 11), model);
  const FitResult fit = fit_model(summaries, model, measure_noise_floor(summaries), {});
  const nlohmann::json j = fit_to_json(fit);
  ASSERT_EQ(j["steps"].size(), summaries.size());
  bool saw_a_rate_step = false;
  for (std::size_t i = 0; i < summaries.size(); ++i) {
    const auto& js = j["steps"][i];
    EXPECT_EQ(js["step"], summaries[i].index);
    EXPECT_DOUBLE_EQ(js["start_s"].get<double>(), summaries[i].start_s);
    EXPECT_DOUBLE_EQ(js["end_s"].get<double>(), summaries[i].end_s);
    EXPECT_EQ(js["static"].get<bool>(), summaries[i].is_static);
    ASSERT_EQ(js["signals"].size(), kSignalCount);
    for (std::size_t k = 0; k < kSignalCount; ++k) {
      const std::string name(signal_names()[k]);
      if (std::isfinite(summaries[i].signals[k])) {
        EXPECT_DOUBLE_EQ(js["signals"][name].get<double>(), summaries[i].signals[k]) << name;
      } else {
        EXPECT_TRUE(js["signals"][name].is_null()) << name;
      }
    }
    // A rate step about a table axis shows its rate in the body-frame signals.
    const double rate = std::abs(js["signals"]["table_rate_x"].get<double>()) +
                        std::abs(js["signals"]["table_rate_y"].get<double>()) +
                        std::abs(js["signals"]["table_rate_z"].get<double>());
    if (!summaries[i].is_static && rate > 10.0) saw_a_rate_step = true;
  }
  EXPECT_TRUE(saw_a_rate_step);
}

}  // namespace
}  // namespace calstand::solver

namespace calstand::solver {
namespace {

// A unit that does not measure one channel (a 5-DoF automotive sensor without pitch rate, read
// through a DBC file, delivers it as NaN): the fit uses the channels it has, and the terms of
// the missing one are not determined, said so; nothing becomes NaN.
TEST(Fit, AChannelTheUnitDoesNotMeasureIsLeftOutNotNaN) {
  const sim::ImuTruth truth = random_unit(1);
  const Model model = Model::parse(kBaseModel);
  RunData data = simulate_run(truth, base_campaign(), 1);
  for (auto& step : data.steps) {
    for (auto& s : step.samples) s.gyro_dps[1] = std::numeric_limits<double>::quiet_NaN();
  }
  for (const FitResult& fit : {fit_at_noise_floor(data, model), fit_run(data, model)}) {
    EXPECT_TRUE(std::isfinite(fit.chi2_dof));
    bool gyro_y_undetermined = false;
    for (const auto& u : fit.unidentifiable) {
      if (u.name == "gyro_bias.y") gyro_y_undetermined = true;
    }
    EXPECT_TRUE(gyro_y_undetermined);
    for (const auto& p : fit.parameters) {
      EXPECT_TRUE(std::isfinite(p.value)) << p.name;
      EXPECT_TRUE(std::isfinite(p.sigma)) << p.name;
      if (p.name.rfind("accel", 0) == 0 || p.name == "gyro_bias.x") {
        EXPECT_NEAR(p.value, truth.parameter(p.name), 4.0 * p.sigma) << p.name;
      }
    }
  }
}

}  // namespace
}  // namespace calstand::solver
