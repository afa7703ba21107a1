// As found: the record in force before a new calibration (newest earlier record of the same
// serial from another run, not failed or indeterminate; never judged counts) and the drift of
// each parameter in units of the combined sigma.
#include "factory/as_found.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "../analysis/recorded_run.hpp"
#include "store/acceptances.hpp"

namespace calstand::analysis {
namespace {

nlohmann::json unit_record(const std::string& serial, double bias, double bias_sigma,
                           double scale) {
  return {{"device", {{"name", "imu0"}, {"model", "m"}, {"serial", serial}}},
          {"parameters",
           {{{"name", "gyro_bias.x"}, {"value", bias}, {"sigma", bias_sigma}, {"unit", "deg/s"}},
            {{"name", "gyro_scale.x"}, {"value", scale}, {"sigma", 40.0}, {"unit", "ppm"}}}}};
}

class AsFoundTest : public ::testing::Test {
 protected:
  AsFoundTest()
      : file_("as-found-" +
              std::string(::testing::UnitTest::GetInstance()->current_test_info()->name())) {
    // Runs recorded without samples: a calibration row needs only its run to exist.
    for (int i = 0; i < 4; ++i) {
      runs_.push_back(
          testing::record_run(file_.path(), "six-position", {"capture_s=10"}, 3, false));
    }
  }
  std::int64_t calibrate(std::size_t run, const nlohmann::json& rec) {
    store::Database db(file_.path());
    return store::insert_calibration(db, runs_.at(run), "imu0", "gyro_bias,gyro_scale", rec);
  }
  void judge(std::int64_t calibration, const std::string& verdict) {
    store::Database db(file_.path());
    store::insert_acceptance(db, calibration, "spec", std::string(64, 'a'), verdict,
                             nlohmann::json::object());
  }
  store::CalibrationRow row(std::int64_t id) {
    store::Database db(file_.path());
    return store::load_calibration(db, id);
  }
  std::optional<std::int64_t> in_force_before(std::int64_t id) {
    store::Database db(file_.path());
    const auto found = record_in_force_before(db, row(id));
    return found ? std::optional<std::int64_t>(found->id) : std::nullopt;
  }

  testing::TempDatabase file_;
  std::vector<std::int64_t> runs_;
};

TEST_F(AsFoundTest, TheNewestEarlierRecordNeverJudgedIsInForce) {
  const auto a = calibrate(0, unit_record("SN1", 0.001, 0.0001, 100));
  const auto b = calibrate(1, unit_record("SN1", 0.002, 0.0001, 110));
  const auto other = calibrate(1, unit_record("SN2", 0.0, 0.0001, 0));
  const auto c = calibrate(2, unit_record("SN1", 0.004, 0.0002, 130));
  EXPECT_EQ(in_force_before(c), b);
  EXPECT_EQ(in_force_before(b), a);
  EXPECT_EQ(in_force_before(a), std::nullopt);  // the unit's first record
  EXPECT_EQ(in_force_before(other), std::nullopt);
}

TEST_F(AsFoundTest, FailedAndIndeterminateRecordsAreNotInForce) {
  const auto a = calibrate(0, unit_record("SN1", 0.001, 0.0001, 100));
  const auto b = calibrate(1, unit_record("SN1", 0.002, 0.0001, 110));
  const auto c = calibrate(2, unit_record("SN1", 0.003, 0.0001, 120));
  const auto d = calibrate(3, unit_record("SN1", 0.004, 0.0001, 130));
  judge(a, "pass");
  judge(b, "fail");
  judge(c, "pass");
  judge(c, "indeterminate");  // the latest judgement counts
  EXPECT_EQ(in_force_before(d), a);
  judge(b, "pass");  // judged again against another specification, and passed
  EXPECT_EQ(in_force_before(d), b);
}

TEST_F(AsFoundTest, ASecondRecordOfTheSameRunIsNotAnEarlierState) {
  const auto a = calibrate(0, unit_record("SN1", 0.001, 0.0001, 100));
  calibrate(1, unit_record("SN1", 0.002, 0.0001, 110));
  const auto again = calibrate(1, unit_record("SN1", 0.0021, 0.0001, 111));
  const auto found = in_force_before(again);
  EXPECT_EQ(found, a);
}

TEST_F(AsFoundTest, AUnitWithoutSerialHasNoHistory) {
  calibrate(0, unit_record("", 0.001, 0.0001, 100));
  const auto b = calibrate(1, unit_record("", 0.002, 0.0001, 110));
  EXPECT_EQ(in_force_before(b), std::nullopt);
}

TEST_F(AsFoundTest, TheDriftIsInUnitsOfTheCombinedSigma) {
  const auto a = calibrate(0, unit_record("SN1", 0.001, 0.0003, 100));
  judge(a, "pass");
  nlohmann::json newer = unit_record("SN1", 0.003, 0.0004, 100);
  newer["parameters"].push_back(
      {{"name", "accel_bias.x"}, {"value", 0.01}, {"sigma", 0.001}, {"unit", "m/s^2"}});
  const auto b = calibrate(1, newer);
  store::Database db(file_.path());
  const auto drift = as_found(db, row(b));
  ASSERT_TRUE(drift);
  EXPECT_EQ(drift->calibration, a);
  EXPECT_EQ(drift->run, runs_[0]);
  EXPECT_EQ(drift->verdict, "pass");
  ASSERT_EQ(drift->parameters.size(), 2u);
  const ParameterDrift& bias = drift->parameters[0];
  EXPECT_EQ(bias.parameter, "gyro_bias.x");
  EXPECT_DOUBLE_EQ(bias.old_value, 0.001);
  EXPECT_DOUBLE_EQ(bias.new_value, 0.003);
  EXPECT_NEAR(bias.difference, 0.002, 1e-15);
  EXPECT_NEAR(bias.combined_sigma, 0.0005, 1e-15);  // 3-4-5
  EXPECT_NEAR(bias.difference_sigmas, 4.0, 1e-9);
  EXPECT_NEAR(drift->parameters[1].difference_sigmas, 0.0, 1e-12);
  EXPECT_EQ(drift->only_new, std::vector<std::string>{"accel_bias.x"});
  EXPECT_TRUE(drift->only_old.empty());
  const nlohmann::json j = to_json(*drift);
  EXPECT_EQ(j.at("parameters")[0].at("old_value"), 0.001);
  EXPECT_EQ(j.at("verdict"), "pass");
}

}  // namespace
}  // namespace calstand::analysis
