// The fit and diagnose requests of calstand fit|diagnose and POST /runs/{id}/fits|diagnose, on a
// run of the simulated IMU with known errors: the recovered parameters against the truth, the
// history row a fit leaves, and errors that name the entry at fault.
#include "analysis/fit_request.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "analysis/run_model.hpp"
#include "recorded_run.hpp"
#include "store/fit_history.hpp"

namespace calstand::analysis {
namespace {

using testing::known_imu_truth;

const solver::FittedParameter* find_parameter(const solver::FitResult& fit,
                                              const std::string& name) {
  for (const auto& p : fit.parameters) {
    if (p.name == name) return &p;
  }
  return nullptr;
}

// Within 5 sigma of `truth`: fails for a wrong sign, unit or axis, seldom by chance.
void expect_recovered(const solver::FitResult& fit, const std::string& name, double truth) {
  const auto* p = find_parameter(fit, name);
  ASSERT_NE(p, nullptr) << name << " not fitted";
  EXPECT_GT(p->sigma, 0.0) << name;
  EXPECT_NEAR(p->value, truth, 5.0 * p->sigma) << name;
}

class FitRequestTest : public ::testing::Test {
 protected:
  void SetUp() override {
    run_ = testing::record_run(db_file_.path(), "six-position", {"capture_s=10"}, 11);
  }

  FitRequest request(const std::vector<std::string>& terms,
                     const std::vector<std::string>& customs = {}) {
    FitRequest r;
    r.model = model_from_lists(terms, customs);
    r.history_command = "fit";
    return r;
  }

  testing::TempDatabase db_file_{"fit-request"};
  std::int64_t run_ = 0;
};

TEST_F(FitRequestTest, RecoversTheKnownAccelerometerErrorsAndRecordsTheFit) {
  store::Database db(db_file_.path());
  const FitOutcome out = fit_request(
      db, run_,
      request({"accel_bias", "accel_scale", "accel_misalignment", "gyro_bias", "earth_rate"}));
  EXPECT_EQ(out.procedure, "six-position");
  EXPECT_EQ(out.device, "imu0");
  EXPECT_EQ(out.steps.size(), 6u);
  for (const char* name :
       {"accel_bias.x", "accel_bias.y", "accel_bias.z", "accel_scale.x", "accel_scale.y",
        "accel_scale.z", "gyro_bias.x", "gyro_bias.y", "gyro_bias.z"}) {
    expect_recovered(out.fit, name, known_imu_truth(name));
  }
  ASSERT_TRUE(out.history_id.has_value());
  const auto history = store::fit_history(db, run_);
  ASSERT_EQ(history.size(), 1u);
  EXPECT_EQ(history[0].id, *out.history_id);
  EXPECT_EQ(history[0].command, "fit");
  EXPECT_EQ(history[0].model, out.fit.model);
  EXPECT_DOUBLE_EQ(*history[0].chi2_dof, out.fit.chi2_dof);

  const nlohmann::json j = to_json(out);
  EXPECT_EQ(j.at("model"), nlohmann::json(out.fit.terms));
  EXPECT_DOUBLE_EQ(j.at("chi2_dof").get<double>(), out.fit.chi2_dof);
  EXPECT_TRUE(j.contains("groups"));
}

TEST_F(FitRequestTest, ACustomTermStandsInForTheScaleFactorItEquals) {
  // c * force_{axis} on each accelerometer axis is the scale factor by another name: it must
  // come out as the true scale factor (ppm in the catalogue, plain ratio here).
  store::Database db(db_file_.path());
  const FitOutcome out =
      fit_request(db, run_,
                  request({"accel_bias", "accel_misalignment", "gyro_bias", "earth_rate"},
                          {"s=accel:force_{axis}"}));
  for (const char* axis : {"x", "y", "z"}) {
    expect_recovered(out.fit, std::string("s.") + axis,
                     known_imu_truth(std::string("accel_scale.") + axis) * 1e-6);
  }
  const auto history = store::fit_history(db, run_);
  ASSERT_EQ(history.size(), 1u);
  EXPECT_EQ(history[0].custom_terms, std::vector<std::string>{"s=accel:force_{axis}"});
}

TEST_F(FitRequestTest, ACustomTermOnOneAxisHasOneParameter) {
  store::Database db(db_file_.path());
  const FitOutcome out =
      fit_request(db, run_, request({"accel_bias", "gyro_bias"}, {"k=accel.z:force_z^2"}));
  EXPECT_NE(find_parameter(out.fit, "k.z"), nullptr);
  EXPECT_EQ(find_parameter(out.fit, "k.x"), nullptr);
  EXPECT_EQ(find_parameter(out.fit, "k.y"), nullptr);
}

TEST_F(FitRequestTest, WithoutAHistoryCommandNothingIsRecorded) {
  store::Database db(db_file_.path());
  FitRequest r = request({"accel_bias"});
  r.history_command.clear();
  EXPECT_FALSE(fit_request(db, run_, r).history_id.has_value());
  EXPECT_TRUE(store::fit_history(db, run_).empty());
}

TEST_F(FitRequestTest, DiagnosisRanksTheMissingScaleFactorFirst) {
  store::Database db(db_file_.path());
  // The known IMU's accelerometer misalignment moves the six positions' means about as much as
  // its scale factors do (within 1% of chi2 on this run): with both missing, which comes first
  // is a coin toss. With the misalignment in the model, the scale factor is what is missing.
  FitRequest r = request({"accel_bias", "accel_misalignment", "gyro_bias", "earth_rate"});
  r.history_command = "diagnose";
  const DiagnoseOutcome out = diagnose_request(db, run_, r);
  ASSERT_FALSE(out.diagnosis.candidates.empty());
  EXPECT_EQ(out.diagnosis.candidates.front().term, "accel_scale");
  EXPECT_GT(out.diagnosis.fit.chi2_dof, out.diagnosis.candidates.front().chi2_dof_after);
  const nlohmann::json j = to_json(out);
  EXPECT_EQ(j.at("candidates").at(0).at("term"), "accel_scale");
  EXPECT_TRUE(j.contains("groups"));
  EXPECT_TRUE(j.contains("suggestions"));
  const auto history = store::fit_history(db, run_);
  ASSERT_EQ(history.size(), 1u);
  EXPECT_EQ(history[0].command, "diagnose");
}

TEST_F(FitRequestTest, AnUnknownRunIsRunNotFoundNamingTheRun) {
  store::Database db(db_file_.path());
  try {
    fit_request(db, 99, request({"accel_bias"}));
    FAIL() << "no error";
  } catch (const RunNotFound& e) {
    EXPECT_EQ(e.where(), "run 99");
  }
}

TEST_F(FitRequestTest, ARunWithoutSamplesIsNothingToFit) {
  const std::int64_t empty =
      testing::record_run(db_file_.path(), "six-position", {"capture_s=10"}, 11, false);
  store::Database db(db_file_.path());
  try {
    fit_request(db, empty, request({"accel_bias"}));
    FAIL() << "no error";
  } catch (const NothingToFit& e) {
    EXPECT_EQ(e.where(), "run " + std::to_string(empty));
  }
}

TEST_F(FitRequestTest, AnUnknownDeviceNamesTheRun) {
  store::Database db(db_file_.path());
  FitRequest r = request({"accel_bias"});
  r.device = "imu7";
  try {
    fit_request(db, run_, r);
    FAIL() << "no error";
  } catch (const core::InputError& e) {
    EXPECT_EQ(e.where(), "run " + std::to_string(run_));
    EXPECT_NE(std::string(e.what()).find("imu7"), std::string::npos);
  }
}

}  // namespace
}  // namespace calstand::analysis
