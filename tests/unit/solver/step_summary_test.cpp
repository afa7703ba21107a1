#include "solver/step_summary.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "core/rotation.hpp"
#include "sim_run.hpp"
#include "solver/noise_estimate.hpp"
#include "solver/step_regressors.hpp"

namespace calstand::solver {
namespace {

using testing::SimStep;

/// Every catalogue term (temperature polynomials to order 3) and custom terms on both sensors,
/// one of them on some axes only.
Model every_term_model() {
  std::string terms;
  for (const auto& t : core::error_term_catalogue()) {
    terms += (terms.empty() ? "" : ",") + std::string(t.name) + (t.polynomial_order ? ":3" : "");
  }
  return Model::parse(
      terms, {"grad=gyro:temperature_rate*rate_{axis}", "sq=accel.xz:force_{axis}^2 + elapsed/1000",
              "cross=gyro.y:table_rate_x*force_z"});
}

/// Positions, rate steps about each axis, both axes turning at once (the table's angular
/// acceleration), temperature ramps inside steps and a mount that is not the identity.
RunData varied_run() {
  sim::ImuTruth truth = testing::white_noise_truth(2e-3, 5e-4, 50.0);
  std::vector<SimStep> steps;
  for (double temp : {-10.0, 40.0}) {
    for (SimStep s : testing::six_positions(temp, 8.0)) {
      s.temperature_rate_cpm = 1.5;
      steps.push_back(s);
    }
    for (SimStep s : testing::rate_steps({20.0, 200.0}, temp, 4.0)) {
      s.temperature_rate_cpm = -0.5;
      steps.push_back(s);
    }
    SimStep both;
    both.outer_rate_dps = 30.0;
    both.inner_rate_dps = -75.0;
    both.outer_deg = 10.0;
    both.temperature_c = temp;
    both.temperature_rate_cpm = 2.0;
    both.duration_s = 6.0;
    steps.push_back(both);
  }
  core::TableGeometry geometry;
  geometry.mount_C_PB = core::from_roll_pitch_yaw_deg(Eigen::Vector3d(1.0, -2.0, 30.0));
  return testing::simulate_run(truth, steps, 7, Eigen::Vector2d(1e-4, -2e-4), geometry);
}

/// The step means of Model::regressors(), sample by sample, as the summaries were first built.
std::vector<Eigen::MatrixXd> per_sample_means(const RunData& data, const Model& model,
                                              std::vector<Eigen::MatrixXd>* scales) {
  const SignalBuilder build(data.setup, model.earth_rate());
  double run_start_s = data.steps.front().samples.front().receive_time_s;
  for (const auto& step : data.steps) {
    for (const auto& s : step.samples) run_start_s = std::min(run_start_s, s.receive_time_s);
  }
  const auto P = static_cast<Eigen::Index>(model.size());
  std::vector<Eigen::MatrixXd> out;
  Eigen::MatrixXd g(kChannels, P);
  for (const auto& step : data.steps) {
    const std::vector<double> rates = step_temperature_rates(step.samples);
    Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(kChannels, P);
    Eigen::MatrixXd abs_sum = Eigen::MatrixXd::Zero(kChannels, P);
    for (std::size_t i = 0; i < step.samples.size(); ++i) {
      const Signals sig = build(step.samples[i], step.table[i], rates[i],
                                step.samples[i].receive_time_s - run_start_s);
      model.regressors(sig, g);
      sum += g;
      abs_sum += g.cwiseAbs();
    }
    const double n = static_cast<double>(step.samples.size());
    out.push_back(sum / n);
    scales->push_back(abs_sum / n);
  }
  return out;
}

// The summaries sum a few signal products per sample instead of every regressor (issue 28);
// their step means must be the per-sample ones to rounding: within 1e-9 of the mean magnitude
// of each regressor (a mean near zero, a whole revolution's rates, is the difference of large
// sums and has no relative accuracy of its own).
TEST(StepSummary, RegressorMeansAreThoseOfEverySample) {
  const RunData data = varied_run();
  const Model model = every_term_model();
  const std::vector<StepSummary> steps = summarize_steps(data, model);
  std::vector<Eigen::MatrixXd> scales;
  const std::vector<Eigen::MatrixXd> expected = per_sample_means(data, model, &scales);
  ASSERT_EQ(steps.size(), expected.size());
  int nonzero = 0;
  for (std::size_t k = 0; k < steps.size(); ++k) {
    ASSERT_EQ(steps[k].regressors.rows(), kChannels);
    ASSERT_EQ(steps[k].regressors.cols(), static_cast<Eigen::Index>(model.size()));
    for (Eigen::Index r = 0; r < kChannels; ++r) {
      for (Eigen::Index c = 0; c < steps[k].regressors.cols(); ++c) {
        const double want = expected[k](r, c);
        const double scale = scales[k](r, c);
        if (scale == 0.0) {
          EXPECT_EQ(steps[k].regressors(r, c), 0.0) << model.parameters()[c].name;
          continue;
        }
        ++nonzero;
        EXPECT_NEAR(steps[k].regressors(r, c), want, 1e-9 * scale)
            << "step " << k << ", " << channel_name(static_cast<int>(r)) << ", "
            << model.parameters()[static_cast<std::size_t>(c)].name;
      }
    }
  }
  // Every parameter acts somewhere in this run (nothing was compared against zeros only).
  EXPECT_GT(nonzero, static_cast<int>(model.size()));
}

// The same for the superset every fit summarises (the Earth rate in the reference and in the
// tilt's gyro rows).
TEST(StepSummary, NoiseSupersetMeansAreThoseOfEverySample) {
  const RunData data = varied_run();
  const Model superset = noise_superset(Model::parse(testing::kBaseModel, {"t=gyro.x:elapsed"}));
  const std::vector<StepSummary> steps = summarize_steps(data, superset);
  std::vector<Eigen::MatrixXd> scales;
  const std::vector<Eigen::MatrixXd> expected = per_sample_means(data, superset, &scales);
  for (std::size_t k = 0; k < steps.size(); ++k) {
    const Eigen::MatrixXd error = (steps[k].regressors - expected[k]).cwiseAbs();
    EXPECT_TRUE((error.array() <= 1e-9 * scales[k].array()).all()) << "step " << k;
  }
}

// Each product is summed once however many parameters share it.
TEST(StepRegressorSums, SumFarFewerProductsThanRegressors) {
  const Model superset = noise_superset(Model::parse(testing::kBaseModel));
  const StepRegressorSums sums(superset);
  EXPECT_LT(sums.product_count() * 5, kChannels * superset.size());
}

}  // namespace
}  // namespace calstand::solver
