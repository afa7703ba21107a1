// The fit-to-history mapping and the history JSON of calstand history --json.
#include "analysis/fit_history.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "analysis/fit_request.hpp"
#include "analysis/run_model.hpp"
#include "recorded_run.hpp"

namespace calstand::analysis {
namespace {

class FitHistoryTest : public ::testing::Test {
 protected:
  void SetUp() override {
    run_ = testing::record_run(db_file_.path(), "six-position", {"capture_s=10"}, 5);
  }
  FitOutcome fit(store::Database& db, const std::string& sensor,
                 const std::vector<std::string>& customs = {}) {
    FitRequest r;
    r.model = model_from_lists({"accel_bias", "gyro_bias"}, customs);
    r.sensor = sensor;
    return fit_request(db, run_, r);
  }
  testing::TempDatabase db_file_{"fit-history"};
  std::int64_t run_ = 0;
};

TEST_F(FitHistoryTest, ARecordHoldsTheFitAndOnlyTheFittedSensorsResiduals) {
  store::Database db(db_file_.path());
  const solver::Model model = model_from_lists({"accel_bias", "gyro_bias"}, {"k=gyro.z:force_z"});
  FitRequest r;
  r.model = model;
  r.sensor = "gyro";
  const FitOutcome gyro = fit_request(db, run_, r);
  const store::FitRecord rec = history_record(run_, "imu0", "fit", model, gyro.fit, "gyro");
  EXPECT_EQ(rec.run, run_);
  EXPECT_EQ(rec.device, "imu0");
  EXPECT_EQ(rec.command, "fit");
  EXPECT_EQ(rec.model, gyro.fit.model);
  EXPECT_EQ(rec.custom_terms, std::vector<std::string>{"k=gyro.z:force_z"});
  EXPECT_EQ(rec.sensors, "gyro");
  EXPECT_EQ(rec.parameters, static_cast<int>(gyro.fit.parameters.size()));
  EXPECT_DOUBLE_EQ(*rec.chi2_dof, gyro.fit.chi2_dof);
  ASSERT_TRUE(rec.rms_gyro_dps.has_value());
  EXPECT_DOUBLE_EQ(*rec.rms_gyro_dps, gyro.fit.residual_rms_gyro_dps);
  EXPECT_FALSE(rec.rms_accel_mps2.has_value());

  const FitOutcome accel = fit(db, "accel");
  const store::FitRecord a = history_record(run_, "imu0", "fit", model, accel.fit, "accel");
  EXPECT_FALSE(a.rms_gyro_dps.has_value());
  EXPECT_TRUE(a.rms_accel_mps2.has_value());
}

TEST_F(FitHistoryTest, RecordedFitsComeBackAsJsonOldestFirstWithNullsForMissingFigures) {
  store::Database db(db_file_.path());
  const solver::Model model = model_from_lists({"accel_bias", "gyro_bias"}, {});
  const FitOutcome both = fit(db, "both");
  const FitOutcome gyro = fit(db, "gyro");
  const std::int64_t first = record_history(db, run_, "imu0", "fit", model, both.fit, "both");
  const std::int64_t second = record_history(db, run_, "imu0", "diagnose", model, gyro.fit, "gyro");
  EXPECT_LT(first, second);
  const nlohmann::json j = history_to_json(store::fit_history(db, run_));
  ASSERT_EQ(j.size(), 2u);
  EXPECT_EQ(j[0].at("id"), first);
  EXPECT_EQ(j[0].at("command"), "fit");
  EXPECT_DOUBLE_EQ(j[0].at("rms_accel_mps2").get<double>(), both.fit.residual_rms_accel_mps2);
  EXPECT_EQ(j[1].at("id"), second);
  EXPECT_EQ(j[1].at("sensors"), "gyro");
  EXPECT_TRUE(j[1].at("rms_accel_mps2").is_null());
  EXPECT_FALSE(j[1].at("time").get<std::string>().empty());
  for (const char* key : {"id", "command", "model", "custom_terms", "sensors", "parameters",
                          "chi2_dof", "rms_gyro_dps", "rms_accel_mps2", "time"}) {
    EXPECT_TRUE(j[0].contains(key)) << key;
  }
}

}  // namespace
}  // namespace calstand::analysis
