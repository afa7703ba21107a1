// Acceptance of real records: six-position runs of the known IMU (LN200-class white noise,
// errors known) calibrated in process, judged against specifications whose limits come from the
// station's truth: a loose one passes, a tight one fails on the one parameter beyond it; the
// verdicts are stored; a second calibration shows the drift from the first; a validation run
// corrected with a good record passes, with a spoiled record fails.
#include "factory/accept_run.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>

#include "../analysis/recorded_run.hpp"
#include "analysis/calibrate.hpp"
#include "analysis/run_model.hpp"
#include "store/acceptances.hpp"
#include "store/calibrations.hpp"

namespace calstand::analysis {
namespace {

// The known IMU's noise (tests/integration/known_imu_station.hpp): ARW [deg/sqrt(h)] and VRW
// [m/s/sqrt(h)].
constexpr double kTrueArw = 0.1;
constexpr double kTrueVrw = 0.03;
constexpr const char* kModel = "accel_bias,accel_scale,accel_misalignment,gyro_bias,earth_rate";

double true_value(const std::string& name) { return testing::known_imu_truth(name); }

AcceptanceSpec run_spec(const std::string& limits, const std::string& extra = "") {
  return parse_acceptance_spec(
      R"js({"format": "calstand-acceptance/1", "name": "test", "limits": [)js" + limits + "]" +
          extra + "}",
      "spec.json");
}

std::string json_number(double v) { return nlohmann::json(v).dump(); }

// Two runs of one unit recorded once: run 1 with 600 s captures (a noise record), run 2 with
// 20 s captures; each test works on its own copy of the database.
class AcceptRun : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    template_ = new testing::TempDatabase("accept-template");
    run1_ = testing::record_run(template_->path(), "six-position", {"capture_s=600"}, 5);
    run2_ = testing::record_run(template_->path(), "six-position", {"capture_s=20"}, 6);
  }
  static void TearDownTestSuite() {
    delete template_;
    template_ = nullptr;
  }

  AcceptRun()
      : file_("accept-" +
              std::string(::testing::UnitTest::GetInstance()->current_test_info()->name())) {
    std::filesystem::copy_file(template_->path(), file_.path(),
                               std::filesystem::copy_options::overwrite_existing);
    db_ = std::make_unique<store::Database>(file_.path());
  }

  // Calibrates `run` as unit `serial`; `spoil` is added to accel_bias.y's value first.
  std::int64_t calibrate(std::int64_t run, const std::string& serial, double spoil = 0.0) {
    CalibrationOutcome c = calibrate_run(*db_, run, solver::Model::parse(kModel), "");
    c.record["device"]["serial"] = serial;
    for (auto& p : c.record["parameters"]) {
      if (p["name"] == "accel_bias.y") p["value"] = p["value"].get<double>() + spoil;
    }
    return store_calibration(*db_, c);
  }

  static const AcceptanceCheck* find(const UnitAcceptance& u, const std::string& name) {
    for (const auto& c : u.checks) {
      if (c.check == name) return &c;
    }
    return nullptr;
  }

  static inline testing::TempDatabase* template_ = nullptr;
  static inline std::int64_t run1_ = 0, run2_ = 0;
  testing::TempDatabase file_;
  std::unique_ptr<store::Database> db_;
};

TEST_F(AcceptRun, ALooseSpecPassesAndATightOneFailsNamingTheParameter) {
  const std::int64_t id = calibrate(run1_, "SN-A");
  // Loose: every limit twice the largest true value of its term, noise at twice the truth.
  const AcceptanceSpec loose = run_spec(R"js({"parameter": "accel_bias.*", "max_abs": )js" +
                                        json_number(2 * std::abs(true_value("accel_bias.y"))) +
                                        R"js(, "unit": "m/s^2"},
         {"parameter": "accel_scale.*", "max_abs": )js" +
                                        json_number(2 * std::abs(true_value("accel_scale.x"))) +
                                        R"js(, "unit": "ppm"},
         {"parameter": "*_misalignment.*", "max_abs": 0.001, "unit": "rad"},
         {"parameter": "gyro_bias.*", "max_abs": )js" +
                                        json_number(2 * true_value("gyro_bias.z")) +
                                        R"js(, "unit": "deg/s"},
         {"noise": "gyro_arw.*", "max": )js" +
                                        json_number(2 * kTrueArw) + R"js(, "unit": "deg/sqrt(h)"},
         {"noise": "accel_vrw.*", "max": )js" +
                                        json_number(2 * kTrueVrw) + R"js(, "unit": "m/s/sqrt(h)"},
         {"fit": "chi2_dof", "max": 3})js");
  const AcceptanceOutcome pass = accept_run(*db_, loose, {run1_, "", std::nullopt});
  ASSERT_EQ(pass.units.size(), 1u);
  const UnitAcceptance& u = pass.units[0];
  EXPECT_EQ(u.device, "imu0");
  EXPECT_EQ(u.serial, "SN-A");
  EXPECT_EQ(u.calibration, id);
  // 3 + 3 + 6 accelerometer misalignments + 3 gyro biases + 3 + 3 noise + chi2.
  EXPECT_EQ(u.checks.size(), 22u);
  for (const auto& c : u.checks) {
    EXPECT_EQ(c.verdict, Verdict::kPass) << c.check << ": " << c.reason;
  }
  EXPECT_EQ(u.verdict, Verdict::kPass);
  EXPECT_EQ(pass.verdict, Verdict::kPass);
  // The guard band is the record's own sigma: realistic, small against the limits.
  const AcceptanceCheck* bias = find(u, "accel_bias.y");
  ASSERT_NE(bias, nullptr);
  EXPECT_GT(*bias->sigma, 0.0);
  EXPECT_LT(*bias->sigma, 1e-3);

  // Tight: between the largest true accelerometer bias (y) and the next (x).
  const double between =
      0.5 * (std::abs(true_value("accel_bias.y")) + std::abs(true_value("accel_bias.x")));
  const AcceptanceSpec tight = run_spec(R"js({"parameter": "accel_bias.*", "max_abs": )js" +
                                        json_number(between) + R"js(, "unit": "m/s^2"})js");
  const AcceptanceOutcome fail = accept_run(*db_, tight, {run1_, "imu0", std::nullopt});
  ASSERT_EQ(fail.units.size(), 1u);
  EXPECT_EQ(fail.units[0].verdict, Verdict::kFail);
  std::vector<std::string> failed;
  for (const auto& c : fail.units[0].checks) {
    if (c.verdict != Verdict::kPass) failed.push_back(c.check);
  }
  EXPECT_EQ(failed, std::vector<std::string>{"accel_bias.y"});
}

TEST_F(AcceptRun, VerdictsAreStoredWithTheirRecords) {
  const std::int64_t id = calibrate(run1_, "SN-A");
  AcceptanceSpec s =
      run_spec(R"js({"parameter": "accel_bias.x", "max_abs": 0.001, "unit": "m/s^2"})js");
  AcceptanceOutcome o = accept_run(*db_, s, {run1_, "", std::nullopt});
  EXPECT_FALSE(store::latest_acceptance(*db_, id));  // judging alone stores nothing
  store_acceptances(*db_, o);
  const auto stored = store::latest_acceptance(*db_, id);
  ASSERT_TRUE(stored);
  EXPECT_EQ(stored->id, *o.units[0].acceptance_id);
  EXPECT_EQ(stored->verdict, "fail");  // accel_bias.x is 0.01
  EXPECT_EQ(stored->spec_name, "test");
  EXPECT_EQ(stored->spec_sha256, s.sha256);
  EXPECT_EQ(stored->result.at("checks")[0].at("check"), "accel_bias.x");
  EXPECT_EQ(stored->result.at("serial"), "SN-A");
  const nlohmann::json j = to_json(o);
  EXPECT_EQ(j.at("units")[0].at("acceptance_id"), stored->id);
  EXPECT_NE(j.at("decision_rule").get<std::string>().find("guard band"), std::string::npos);
}

TEST_F(AcceptRun, ASecondCalibrationShowsTheDriftFromTheFirst) {
  const std::int64_t first = calibrate(run1_, "SN-A");
  const std::int64_t second = calibrate(run2_, "SN-A");
  const AcceptanceSpec s = run_spec(R"js({"fit": "chi2_dof", "max": 3})js");
  const AcceptanceOutcome o = accept_run(*db_, s, {run2_, "", std::nullopt});
  ASSERT_EQ(o.units.size(), 1u);
  EXPECT_EQ(o.units[0].calibration, second);
  ASSERT_TRUE(o.units[0].as_found);
  const AsFound& d = *o.units[0].as_found;
  EXPECT_EQ(d.calibration, first);
  EXPECT_EQ(d.run, run1_);
  EXPECT_EQ(d.verdict, "");             // never judged, still in force
  EXPECT_EQ(d.parameters.size(), 15u);  // 12 accelerometer parameters and 3 gyro biases
  // The same unit with white noise only: it has not moved beyond both records' uncertainty.
  for (const auto& p : d.parameters) {
    EXPECT_LT(std::abs(p.difference_sigmas), 5.0) << p.parameter;
    EXPECT_NEAR(p.old_value, true_value(p.parameter), 5 * p.combined_sigma) << p.parameter;
  }
  // The first record judged and failed is no longer in force: nothing to compare with.
  store::insert_acceptance(*db_, first, "x", std::string(64, '0'), "fail", {});
  EXPECT_FALSE(accept_run(*db_, s, {run2_, "", std::nullopt}).units[0].as_found);
}

constexpr const char* kValidation =
    R"js(, "validation": {"limits": [
         {"parameter": "accel_bias.*", "max_abs": 0.001, "unit": "m/s^2"},
         {"parameter": "accel_scale.*", "max_abs": 100, "unit": "ppm"},
         {"fit": "chi2_dof", "max": 3}]})js";

TEST_F(AcceptRun, AValidationRunCorrectedWithAGoodRecordPasses) {
  calibrate(run2_, "SN-A");
  const AcceptanceSpec s = run_spec(R"js({"fit": "chi2_dof", "max": 3})js", kValidation);
  const AcceptanceOutcome o = accept_run(*db_, s, {run2_, "", run1_});
  ASSERT_EQ(o.units.size(), 1u);
  const UnitAcceptance& u = o.units[0];
  ASSERT_TRUE(u.validation);
  EXPECT_EQ(u.validation->run, run1_);
  EXPECT_NE(u.validation->corrected_run, run1_);
  std::size_t validation_checks = 0;
  for (const auto& c : u.checks) {
    if (c.source != CheckSource::kValidation) continue;
    ++validation_checks;
    EXPECT_EQ(c.verdict, Verdict::kPass) << c.check << ": " << c.reason;
    EXPECT_EQ(c.check.rfind("validation ", 0), 0u) << c.check;
  }
  EXPECT_EQ(validation_checks, 7u);  // 3 biases, 3 scales, chi2
  EXPECT_EQ(u.verdict, Verdict::kPass);
  // The calibrated run itself is no validation: corrected with its own fit it leaves nothing.
  EXPECT_THROW(accept_run(*db_, s, {run2_, "", run2_}), core::InputError);
}

TEST_F(AcceptRun, AValidationRunCorrectedWithASpoiledRecordFailsOnTheSpoiledParameter) {
  calibrate(run2_, "SN-A", 0.005);  // 5 mm/s^2 added to accel_bias.y
  const AcceptanceOutcome o = accept_run(
      *db_, run_spec(R"js({"fit": "chi2_dof", "max": 3})js", kValidation), {run2_, "", run1_});
  const AcceptanceCheck* y = find(o.units[0], "validation accel_bias.y");
  ASSERT_NE(y, nullptr);
  EXPECT_EQ(y->verdict, Verdict::kFail) << y->reason;
  EXPECT_NEAR(*y->value, -0.005, 10 * *y->sigma);  // the correction left the spoil behind
  EXPECT_EQ(find(o.units[0], "validation accel_bias.x")->verdict, Verdict::kPass);
  EXPECT_EQ(o.units[0].verdict, Verdict::kFail);
}

TEST_F(AcceptRun, WithoutTheValidationRunTheSpecAsksForItsChecksFail) {
  calibrate(run2_, "SN-A");
  const AcceptanceOutcome o =
      accept_run(*db_, run_spec(R"js({"fit": "chi2_dof", "max": 3})js", kValidation),
                 {run2_, "", std::nullopt});
  const AcceptanceCheck* c = find(o.units[0], "validation accel_bias.*");
  ASSERT_NE(c, nullptr);
  EXPECT_EQ(c->verdict, Verdict::kFail);
  EXPECT_NE(c->reason.find("--validation-run"), std::string::npos);
  EXPECT_EQ(o.units[0].verdict, Verdict::kFail);
}

TEST_F(AcceptRun, ARunWithoutRecordsOrAnUnknownRunIsRefused) {
  const AcceptanceSpec s = run_spec(R"js({"fit": "chi2_dof", "max": 3})js");
  try {
    accept_run(*db_, s, {run1_, "", std::nullopt});
    FAIL() << "a run without records was judged";
  } catch (const core::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("calstand calibrate"), std::string::npos) << e.what();
  }
  calibrate(run1_, "SN-A");
  EXPECT_THROW(accept_run(*db_, s, {run1_, "imu9", std::nullopt}), core::InputError);
  EXPECT_THROW(accept_run(*db_, s, {999, "", std::nullopt}), RunNotFound);
}

}  // namespace
}  // namespace calstand::analysis
