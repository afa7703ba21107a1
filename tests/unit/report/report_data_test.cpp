// Gathering `calstand report` as a library call: the fit is recorded, the history labelled,
// the steps grouped, the noise section skipped for a run without a long static record, a long
// static capture read once; and the page itself when gnuplot is installed.
#include "report/report_data.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <cmath>

#include "../analysis/recorded_run.hpp"
#include "analysis/noise_json.hpp"
#include "render/gnuplot_svg.hpp"
#include "report/report_html.hpp"
#include "report/static_report.hpp"
#include "store/fit_history.hpp"
#include "store/sample_reader.hpp"

namespace calstand::analysis {
namespace {

class ReportDataTest : public ::testing::Test {
 protected:
  void SetUp() override {
    run_ = testing::record_run(db_file_.path(), "six-position", {"capture_s=10"}, 9);
    request_.db = "test.db";
    request_.run = run_;
    request_.model = "accel_bias,gyro_bias,earth_rate";
  }
  testing::TempDatabase db_file_{"report"};
  std::int64_t run_ = 0;
  ReportRequest request_;
};

TEST_F(ReportDataTest, GathersTheDiagnosisAndRecordsItAsTheLastFitOfTheHistory) {
  store::Database db(db_file_.path());
  const ReportData first = gather_report(db, request_);
  request_.model = "accel_bias,accel_scale,gyro_bias,earth_rate";
  const ReportData r = gather_report(db, request_);
  EXPECT_EQ(r.procedure, "six-position");
  EXPECT_EQ(r.device, "imu0");
  ASSERT_EQ(r.history.size(), 2u);
  EXPECT_EQ(r.history.back().command, "report");
  EXPECT_EQ(r.history.back().model, r.diagnosis.fit.model);
  ASSERT_EQ(r.history_labels.size(), 2u);
  EXPECT_EQ(r.history_labels[1], "#" + std::to_string(r.history[1].id) + " +accel_scale");
  // Adding the scale factor the known IMU has lowers chi2/dof.
  EXPECT_LT(r.diagnosis.fit.chi2_dof, first.diagnosis.fit.chi2_dof);
  EXPECT_EQ(r.steps.size(), 6u);
  EXPECT_EQ(r.grouping.of_step.size(), r.steps.size());
  EXPECT_GT(r.grouping.values.size(), 1u);
  EXPECT_EQ(store::fit_history(db, run_).size(), 2u);
}

TEST_F(ReportDataTest, ARunWithoutALongStaticRecordSaysWhyThereIsNoAllanSection) {
  store::Database db(db_file_.path());
  const ReportData r = gather_report(db, request_);
  EXPECT_FALSE(r.noise.has_value());
  EXPECT_LT(r.longest_static_s, kMinNoiseRecordS);
  EXPECT_GT(r.longest_static_s, 9.0);
  EXPECT_NE(r.noise_note.find(fmt::format("{:.0f} s or more", kMinNoiseRecordS)), std::string::npos)
      << r.noise_note;
}

TEST_F(ReportDataTest, AStaticRunOfTheUnitWeighsTheDiagnosisWithItsWander) {
  const std::int64_t still = testing::record_run(db_file_.path(), "static-allan",
                                                 {"duration_s=900", "soak_s=1", "warmup_s=1"}, 9);
  store::Database db(db_file_.path());
  request_.noise_run = still;
  const ReportData r = gather_report(db, request_);
  const std::string source = fmt::format("static run {}", still);
  EXPECT_NE(r.diagnosis.fit.noise.method.find(source), std::string::npos)
      << r.diagnosis.fit.noise.method;
  request_.noise_run.reset();
  EXPECT_EQ(gather_report(db, request_).diagnosis.fit.noise.method.find(source), std::string::npos);
}

TEST_F(ReportDataTest, SignalSeriesFollowTheStepMeans) {
  store::Database db(db_file_.path());
  const ReportData r = gather_report(db, request_);
  const auto force_z = signal_series(r.steps, "force_z");
  ASSERT_TRUE(force_z.has_value());
  ASSERT_EQ(force_z->size(), r.steps.size());
  // Step 0 is z up (+g), step 1 z down.
  EXPECT_GT((*force_z)[0], 9.0);
  EXPECT_LT((*force_z)[1], -9.0);
  const auto sq = signal_series(r.steps, "force_z^2");
  ASSERT_TRUE(sq.has_value());
  EXPECT_NEAR((*sq)[0], (*force_z)[0] * (*force_z)[0], 1e-3);
  EXPECT_FALSE(signal_series(r.steps, "force_w").has_value());
}

TEST_F(ReportDataTest, BadRequestsNameTheirPlace) {
  store::Database db(db_file_.path());
  request_.model = "accel_bais";
  EXPECT_THROW(gather_report(db, request_), core::InputError);
  request_.model = "accel_bias";
  request_.run = 77;
  EXPECT_THROW(gather_report(db, request_), RunNotFound);
}

TEST_F(ReportDataTest, ThePageIsOneHtmlDocumentWithInlinePlots) {
  try {
    find_gnuplot();
  } catch (const core::InputError&) {
    GTEST_SKIP() << "gnuplot is not installed";
  }
  store::Database db(db_file_.path());
  const std::string page = run_report_html(db, request_);
  EXPECT_EQ(page.rfind("<!DOCTYPE html>", 0), 0u);
  EXPECT_NE(page.find("<svg"), std::string::npos);
  EXPECT_NE(page.find("Run " + std::to_string(run_)), std::string::npos);
  EXPECT_EQ(page.find("<script"), std::string::npos);
}

// Issue 31's debt: the report analysed a long static capture three times (the fit's read of
// the run, the Allan section, the stability figures). Now the fit's read serves all three: the
// samples decoded while gathering are the run's samples, once each. The stability figures are
// those `calstand analyze stability` reads on its own.
TEST(ReportDataStatic, ALongStaticCaptureIsReadOnceForItsAllanPlotAndItsStability) {
  testing::TempDatabase file("report-static");
  const std::int64_t run = testing::record_run(file.path(), "static-allan",
                                               {"duration_s=600", "soak_s=1", "warmup_s=1"}, 5);
  store::Database db(file.path());
  std::int64_t samples = 0;
  for (const auto& m : store::read_step_means(db, run)) samples += m.count;
  ReportRequest request;
  request.db = "test.db";
  request.run = run;
  request.noise_model = false;  // GMWM costs seconds a channel; static_report_cli_test has it
  const std::uint64_t before = store::samples_decoded();
  const ReportData r = gather_report(db, request);
  const std::uint64_t decoded = store::samples_decoded() - before;
  ASSERT_TRUE(r.noise.has_value()) << r.noise_note;
  ASSERT_TRUE(r.datasheet.stability.has_value())
      << r.datasheet.failure_of(DatasheetKind::kStability);
  EXPECT_GT(r.noise->samples, 100000u) << "a long capture";
  EXPECT_EQ(decoded, static_cast<std::uint64_t>(samples))
      << "the run holds " << samples << " samples; " << r.noise->samples << " in its capture";
  // No error model on a static-allan run: its page has the record-length advice of the page of
  // a record at rest, from the same analysis.
  EXPECT_FALSE(r.fitted());
  ASSERT_NE(r.static_record, nullptr);
  EXPECT_EQ(r.static_record->noise.samples, r.noise->samples);
  EXPECT_EQ(r.static_record->record_needs.size(), 6u);

  const StabilityAnalysis alone = analyse_stability(db, run, "", std::nullopt);
  const StabilityAnalysis& shared = *r.datasheet.stability;
  EXPECT_EQ(shared.step, alone.step);
  for (std::size_t c = 0; c < 6; ++c) {
    // `analyze stability` alone streams the step (solver::DeviationStream), the report reads
    // it whole: the same curve to rounding (the record lies within the stream's exact range).
    EXPECT_NEAR(shared.channels[c].bias_instability, alone.channels[c].bias_instability,
                1e-12 * std::abs(alone.channels[c].bias_instability))
        << c;
    EXPECT_EQ(shared.channels[c].min_tau_s, alone.channels[c].min_tau_s) << c;
    EXPECT_EQ(shared.channels[c].bias_model, alone.channels[c].bias_model) << c;
  }
}

TEST(HistoryLabels, SayWhatEachFitAddedOrRemoved) {
  std::vector<store::FitRecord> fits(3);
  fits[0].id = 1;
  fits[0].model = "gyro_bias";
  fits[1].id = 2;
  fits[1].model = "gyro_bias, gyro_scale";
  fits[2].id = 3;
  fits[2].model = "gyro_scale";
  const auto labels = history_labels(fits);
  ASSERT_EQ(labels.size(), 3u);
  EXPECT_EQ(labels[0], "#1 gyro_bias");
  EXPECT_EQ(labels[1], "#2 +gyro_scale");
  EXPECT_EQ(labels[2], "#3 -gyro_bias");
}

}  // namespace
}  // namespace calstand::analysis
