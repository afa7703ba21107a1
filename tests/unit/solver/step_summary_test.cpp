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

/// What the summaries hold, computed sample by sample as they were first built: every
/// sample's signals from the table state, every regressor of Model::regressors().
struct PerSampleMeans {
  std::vector<Eigen::MatrixXd> regressors;
  std::vector<Eigen::MatrixXd> scales;  ///< mean magnitude of each regressor
  std::vector<Vector6d> reference;
  std::vector<std::array<double, kSignalCount>> signals;
  /// The step mean's variance by batch means: 10 blocks, sample i in block i * 10 / n.
  std::vector<Vector6d> mean_variance;
};

PerSampleMeans per_sample_means(const RunData& data, const Model& model) {
  const SignalBuilder build(data.setup, model.earth_rate());
  double run_start_s = data.steps.front().samples.front().receive_time_s;
  for (const auto& step : data.steps) {
    for (const auto& s : step.samples) run_start_s = std::min(run_start_s, s.receive_time_s);
  }
  const auto P = static_cast<Eigen::Index>(model.size());
  PerSampleMeans out;
  Eigen::MatrixXd g(kChannels, P);
  for (const auto& step : data.steps) {
    const std::vector<double> rates = step_temperature_rates(step.samples);
    Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(kChannels, P);
    Eigen::MatrixXd abs_sum = Eigen::MatrixXd::Zero(kChannels, P);
    Vector6d reference = Vector6d::Zero();
    std::array<double, kSignalCount> signals{};
    constexpr std::size_t kBlocks = 10;
    std::array<Vector6d, kBlocks> block_sum;
    block_sum.fill(Vector6d::Zero());
    std::array<double, kBlocks> block_count{};
    for (std::size_t i = 0; i < step.samples.size(); ++i) {
      const Signals sig = build(step.samples[i], step.table[i], rates[i],
                                step.samples[i].receive_time_s - run_start_s);
      model.regressors(sig, g);
      sum += g;
      abs_sum += g.cwiseAbs();
      reference += model.reference(sig);
      const auto values = signal_values(sig);
      for (std::size_t k = 0; k < kSignalCount; ++k) signals[k] += values[k];
      Vector6d meas;
      meas << step.samples[i].gyro_dps, step.samples[i].accel_mps2;
      const std::size_t b = i * kBlocks / step.samples.size();
      block_sum[b] += meas - model.reference(sig);
      block_count[b] += 1.0;
    }
    Vector6d avar = Vector6d::Zero();
    for (std::size_t b = 0; b + 1 < kBlocks; ++b) {
      const Vector6d d = block_sum[b + 1] / block_count[b + 1] - block_sum[b] / block_count[b];
      avar += 0.5 * d.cwiseProduct(d);
    }
    out.mean_variance.push_back(avar / static_cast<double>(kBlocks - 1) /
                                static_cast<double>(kBlocks));
    const double n = static_cast<double>(step.samples.size());
    out.regressors.push_back(sum / n);
    out.scales.push_back(abs_sum / n);
    out.reference.push_back(reference / n);
    for (double& v : signals) v /= n;
    out.signals.push_back(signals);
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
  const PerSampleMeans means = per_sample_means(data, model);
  const std::vector<Eigen::MatrixXd>& expected = means.regressors;
  const std::vector<Eigen::MatrixXd>& scales = means.scales;
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
  // The signals of a static step's samples come from its first sample's table state: the
  // reference and the signals' means are those of every sample's own; the batch means take
  // the same samples.
  for (std::size_t k = 0; k < steps.size(); ++k) {
    EXPECT_LE((steps[k].mean_variance - means.mean_variance[k]).cwiseAbs().maxCoeff(),
              1e-9 * means.mean_variance[k].cwiseAbs().maxCoeff())
        << "step " << k;
    EXPECT_LE((steps[k].reference - means.reference[k]).cwiseAbs().maxCoeff(),
              1e-12 * std::max(1.0, means.reference[k].cwiseAbs().maxCoeff()))
        << "step " << k;
    for (std::size_t j = 0; j < kSignalCount; ++j) {
      EXPECT_NEAR(steps[k].signals[j], means.signals[k][j],
                  1e-12 * std::max(1.0, std::abs(means.signals[k][j])))
          << "step " << k << ", " << signal_names()[j];
    }
  }
}

// The same for the superset every fit summarises (the Earth rate in the reference and in the
// tilt's gyro rows).
TEST(StepSummary, NoiseSupersetMeansAreThoseOfEverySample) {
  const RunData data = varied_run();
  const Model superset = noise_superset(Model::parse(testing::kBaseModel, {"t=gyro.x:elapsed"}));
  const std::vector<StepSummary> steps = summarize_steps(data, superset);
  const PerSampleMeans means = per_sample_means(data, superset);
  ASSERT_EQ(steps.size(), means.regressors.size());
  for (std::size_t k = 0; k < steps.size(); ++k) {
    const Eigen::MatrixXd error = (steps[k].regressors - means.regressors[k]).cwiseAbs();
    EXPECT_TRUE((error.array() <= 1e-9 * means.scales[k].array()).all()) << "step " << k;
  }
}

// Each product is summed once however many parameters share it.
TEST(StepRegressorSums, SumFarFewerProductsThanRegressors) {
  const Model superset = noise_superset(Model::parse(testing::kBaseModel));
  const StepRegressorSums sums(superset);
  EXPECT_LT(sums.product_count() * 5, kChannels * superset.size());
}

// SignalBuilder computes the outer axis' rotation once for the body attitude, the table rate
// and its acceleration; with axes that are not unit vectors (normalised twice for the
// acceleration) too, it must give TableGeometry's figures.
TEST(SignalBuilder, FollowsTheTableGeometry) {
  RunSetup setup;
  setup.site = testing::wuhan_site();
  setup.geometry.outer_axis = Eigen::Vector3d(0.1, 3.0, -0.2);
  setup.geometry.inner_axis = Eigen::Vector3d(0.0, 0.3, 7.0);
  setup.geometry.mount_C_PB = core::from_roll_pitch_yaw_deg(Eigen::Vector3d(3.0, 1.0, -20.0));
  const core::TableGeometry& geo = setup.geometry;
  const SignalBuilder build(setup, true);
  const store::TableSample table{37.0, -112.5, 45.0, -130.0};
  core::ImuSample sample;
  sample.temperature_c = 31.0;
  const Signals s = build(sample, table, 0.2, 10.0);
  const Eigen::Matrix3d C_BL = geo.body_to_level(table.outer_deg, table.inner_deg).transpose();
  EXPECT_LE((s.C_BL - C_BL).cwiseAbs().maxCoeff(), 1e-15);
  const Eigen::Vector3d rate =
      C_BL * geo.table_rate_level_dps(table.outer_deg, table.outer_rate_dps, table.inner_rate_dps);
  EXPECT_LE((s.table_rate_dps - rate).cwiseAbs().maxCoeff(), 1e-12);
  const Eigen::Vector3d accel =
      C_BL * geo.table_accel_level_dps2(table.outer_deg, table.outer_rate_dps, table.inner_rate_dps,
                                        0.0, 0.0);
  EXPECT_GT(accel.norm(), 1.0);
  EXPECT_LE((s.table_accel_dps2 - accel).cwiseAbs().maxCoeff(), 1e-12);
}

// A sample at the same table state as the one before gets its signals without the rotations:
// exactly those of the full computation.
TEST(SignalBuilder, AtTheSameTableStateAsTheFullComputation) {
  RunSetup setup;
  setup.site = testing::wuhan_site();
  setup.geometry.mount_C_PB = core::from_roll_pitch_yaw_deg(Eigen::Vector3d(3.0, 1.0, -20.0));
  const SignalBuilder build(setup, true);
  const store::TableSample table{135.0, 45.0, 0.0, 0.0};
  core::ImuSample first;
  first.temperature_c = 20.0;
  core::ImuSample second;
  second.temperature_c = 20.5;
  const Signals previous = build(first, table, 0.1, 4.0);
  const Signals full = build(second, table, 0.3, 4.0025);
  Signals same = previous;
  build.advance_at_same_table(same, second, 0.3, 4.0025);
  EXPECT_EQ(same.temperature_c, full.temperature_c);
  EXPECT_EQ(same.dT_c, full.dT_c);
  EXPECT_EQ(same.temperature_rate_cpm, full.temperature_rate_cpm);
  EXPECT_EQ(same.elapsed_s, full.elapsed_s);
  EXPECT_EQ(same.rate_dps, full.rate_dps);
  EXPECT_EQ(same.table_rate_dps, full.table_rate_dps);
  EXPECT_EQ(same.table_accel_dps2, full.table_accel_dps2);
  EXPECT_EQ(same.force_mps2, full.force_mps2);
  EXPECT_EQ(same.earth_rate_dps, full.earth_rate_dps);
  EXPECT_EQ(same.C_BL, full.C_BL);
}

}  // namespace
}  // namespace calstand::solver
