#include "solver/calibration_record.hpp"

#include <gtest/gtest.h>

#include "core/error.hpp"
#include "sim/noise.hpp"
#include "sim_run.hpp"

namespace calstand::solver {
namespace {

using testing::simulate_run;
using testing::six_positions;
using testing::white_noise_truth;

const char* kModel =
    "gyro_bias,gyro_scale,gyro_misalignment,gyro_g_sensitivity,earth_rate,accel_bias,accel_scale,"
    "accel_misalignment";

sim::ImuTruth unit_under_test() {
  sim::ImuTruth t = white_noise_truth();
  t.gyro_bias = {2e-3, -1e-3, 3e-3};
  t.gyro_scale = {300.0, -200.0, 150.0};
  t.gyro_misalignment(0, 1) = 5e-4;
  t.gyro_misalignment(2, 0) = -3e-4;
  t.gyro_g_sensitivity(1, 2) = 2e-3;
  t.accel_bias = {0.01, -0.02, 0.005};
  t.accel_scale = {-400.0, 250.0, 100.0};
  t.accel_misalignment(1, 0) = 4e-4;
  return t;
}

std::vector<testing::SimStep> campaign() {
  auto steps = six_positions();
  for (const auto& r : testing::rate_steps({30.0, 90.0})) steps.push_back(r);
  return steps;
}

struct Fitted {
  RunData data;
  Model model;
  std::vector<StepSummary> steps;
  FitResult fit;
};

Fitted fit_campaign(const sim::ImuTruth& truth, std::uint64_t seed, const std::string& terms) {
  Fitted f{simulate_run(truth, campaign(), seed), Model::parse(terms), {}, {}};
  f.data.setup.run = 1;
  f.data.setup.procedure_name = "test";
  f.data.setup.procedure_sha256 = std::string(64, 'a');
  f.steps = summarize_steps(f.data, f.model);
  f.fit = fit_model(f.steps, f.model, measure_noise_floor(f.steps));
  return f;
}

TEST(CalibrationRecord, IsValidAgainstItsSchemaAndReadsBack) {
  const Fitted f = fit_campaign(unit_under_test(), 1, kModel);
  const nlohmann::json record = make_calibration_record(f.data.setup, f.model, f.fit, f.steps);
  const Calibration c = read_calibration(record, "record.json");
  EXPECT_EQ(c.model.text(), f.model.text());
  for (const auto& p : f.fit.parameters) {
    const auto& list = c.model.parameters();
    const auto i =
        std::find_if(list.begin(), list.end(), [&](const auto& x) { return x.name == p.name; }) -
        list.begin();
    EXPECT_EQ(c.values[i], p.value) << p.name;
  }
  EXPECT_NEAR(c.valid_min_c, 25.0, 1e-9);
  EXPECT_EQ(record["fit"]["dof"], f.fit.dof);
}

TEST(CalibrationRecord, BadRecordsNameTheField) {
  const Fitted f = fit_campaign(unit_under_test(), 2, kModel);
  nlohmann::json record = make_calibration_record(f.data.setup, f.model, f.fit, f.steps);
  nlohmann::json wrong_unit = record;
  wrong_unit["parameters"][0]["unit"] = "deg/h";
  try {
    (void)read_calibration(wrong_unit, "cal.json");
    FAIL();
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cal.json: parameters[0].unit"), std::string::npos)
        << e.what();
  }
  nlohmann::json stranger = record;
  stranger["parameters"][0]["name"] = "accel_quadratic.x";
  EXPECT_THROW((void)read_calibration(stranger, "cal.json"), core::InputError);
  nlohmann::json missing = record;
  missing.erase("fit");
  EXPECT_THROW((void)read_calibration(missing, "cal.json"), core::InputError);
}

// A record from one run, applied to another run of the same unit (another seed), removes the
// errors: the corrected run fits the bare reference (earth_rate only) at the noise floor, while
// the raw run does not.
TEST(Corrector, ValidationRunFallsToTheNoiseFloor) {
  const sim::ImuTruth truth = unit_under_test();
  const Fitted cal = fit_campaign(truth, 3, kModel);
  const Calibration c = read_calibration(
      make_calibration_record(cal.data.setup, cal.model, cal.fit, cal.steps), "cal.json");

  RunData validation = simulate_run(truth, campaign(), 4);
  const Model bare = Model::parse("earth_rate");
  auto raw_steps = summarize_steps(validation, bare);
  const FitResult raw = fit_model(raw_steps, bare, measure_noise_floor(raw_steps));
  EXPECT_GT(raw.chi2_dof, 100.0);

  const Corrector corrector(c, validation.setup);
  const double start = validation.steps.front().samples.front().receive_time_s;
  for (auto& step : validation.steps) corrector.correct(step, start);
  auto steps = summarize_steps(validation, bare);
  const FitResult corrected = fit_model(steps, bare, measure_noise_floor(steps));
  // The record's own uncertainty adds to the validation run's noise: allow a little above 1.
  EXPECT_LT(corrected.chi2_dof, 2.0);
  EXPECT_LT(corrected.residual_rms_gyro_dps, 2.0 * corrected.noise_floor.head<3>().maxCoeff());
  EXPECT_LT(corrected.residual_rms_accel_mps2, 2.0 * corrected.noise_floor.tail<3>().maxCoeff());
}

// Correcting noiseless samples made with exactly the record's parameters gives back the true
// rate and force (the inverse converges), for nonlinear terms too.
TEST(Corrector, InvertsTheModelExactly) {
  sim::ImuTruth truth = unit_under_test();
  truth.gyro_noise = {};
  truth.accel_noise = {};
  truth.gyro_scale_asymmetry = {200.0, -100.0, 50.0};
  truth.gyro_quadratic = {0.3, -0.2, 0.1};
  truth.accel_quadratic = {80.0, -40.0, 20.0};
  const Model model =
      Model::parse(std::string(kModel) + ",gyro_scale_asymmetry,gyro_quadratic,accel_quadratic");
  Calibration c;
  c.model = model;
  c.values.resize(static_cast<Eigen::Index>(model.size()));
  for (std::size_t p = 0; p < model.size(); ++p) {
    c.values[static_cast<Eigen::Index>(p)] = truth.parameter(model.parameters()[p].name);
  }
  RunData run = simulate_run(truth, campaign(), 5);
  const Corrector corrector(c, run.setup);
  const SignalBuilder truth_signals(run.setup, true);
  for (auto& step : run.steps) {
    corrector.correct(step, 0.0);
    for (std::size_t i = 0; i < step.samples.size(); i += 97) {
      const Signals s = truth_signals(step.samples[i], step.table[i], 0.0, 0.0);
      EXPECT_NEAR((step.samples[i].gyro_dps - s.rate_dps).norm(), 0.0, 1e-9);
      EXPECT_NEAR((step.samples[i].accel_mps2 - s.force_mps2).norm(), 0.0, 1e-9);
    }
  }
}

}  // namespace
}  // namespace calstand::solver
