// A record judged against a specification: one check per name a limit matches, guard bands
// from the record's sigmas, and nothing passing by silence (a name the record lacks fails).
#include "factory/acceptance.hpp"

#include <gtest/gtest.h>

#include <map>

namespace calstand::analysis {
namespace {

// A record with numbers chosen for the checks below (not from any fit).
const nlohmann::json kJudgedRecord = nlohmann::json::parse(R"js({
  "device": {"name": "imu0", "model": "ln200", "serial": "SN7"},
  "parameters": [
    {"name": "gyro_bias.x", "value": 0.001, "sigma": 0.0001, "unit": "deg/s"},
    {"name": "gyro_bias.y", "value": -0.0049, "sigma": 0.0001, "unit": "deg/s"},
    {"name": "gyro_bias.z", "value": 0.0062, "sigma": 0.0001, "unit": "deg/s"},
    {"name": "gyro_scale.x", "value": 150, "sigma": 30, "unit": "ppm"}],
  "unidentifiable": [{"name": "gyro_scale.y", "reason": "no rotation about y"}],
  "fit": {"chi2_dof": 1.4, "dof": 60, "residual_rms": {"gyro": 0.0005, "accel": 0.0001},
          "noise_floor": {"gyro": [0, 0, 0], "accel": [0, 0, 0]}},
  "noise": {"step": 3, "duration_s": 600, "channels": {
    "gx": [{"name": "angle_random_walk", "value": 0.1, "sigma": 0.01, "unit": "deg/sqrt(h)", "resolved": true}],
    "gy": [{"name": "angle_random_walk", "value": 0.14, "sigma": 0.01, "unit": "deg/sqrt(h)", "resolved": true}]}},
  "valid_temperature_c": {"min": 20.5, "max": 45.0}
})js");

AcceptanceSpec judged_spec(const std::string& limits, double k = 2.0) {
  return parse_acceptance_spec(R"js({"format": "calstand-acceptance/1", "name": "t", "k": )js" +
                                   std::to_string(k) + R"js(, "limits": [)js" + limits + "]}",
                               "spec.json");
}

std::map<std::string, AcceptanceCheck> checks_by_name(const std::vector<AcceptanceCheck>& checks) {
  std::map<std::string, AcceptanceCheck> out;
  for (const auto& c : checks) out[c.check] = c;
  return out;
}

TEST(Acceptance, EachMatchedParameterIsOneCheckWithItsGuardBand) {
  const auto checks = judge_record(
      kJudgedRecord,
      judged_spec(R"js({"parameter": "gyro_bias.*", "max_abs": 0.005, "unit": "deg/s"})js"));
  ASSERT_EQ(checks.size(), 3u);
  const auto c = checks_by_name(checks);
  EXPECT_EQ(c.at("gyro_bias.x").verdict, Verdict::kPass);           // 0.0012 inside
  EXPECT_EQ(c.at("gyro_bias.y").verdict, Verdict::kIndeterminate);  // 0.0047..0.0051
  EXPECT_EQ(c.at("gyro_bias.z").verdict, Verdict::kFail);           // 0.006 > 0.005
  EXPECT_DOUBLE_EQ(*c.at("gyro_bias.y").sigma, 0.0001);
  EXPECT_EQ(c.at("gyro_bias.z").unit, "deg/s");
  EXPECT_EQ(c.at("gyro_bias.z").spec_limit, "limits[0]");
  EXPECT_EQ(unit_verdict(checks), Verdict::kFail);
  // With k = 0 the same numbers are judged without a band.
  const auto plain = checks_by_name(judge_record(
      kJudgedRecord,
      judged_spec(R"js({"parameter": "gyro_bias.*", "max_abs": 0.005, "unit": "deg/s"})js", 0)));
  EXPECT_EQ(plain.at("gyro_bias.y").verdict, Verdict::kPass);
}

TEST(Acceptance, APatternTheRecordLacksFailsAsNotInTheRecord) {
  const auto checks = judge_record(
      kJudgedRecord,
      judged_spec(R"js({"parameter": "accel_bias.*", "max_abs": 1, "unit": "m/s^2"})js"));
  ASSERT_EQ(checks.size(), 1u);
  EXPECT_EQ(checks[0].check, "accel_bias.*");
  EXPECT_EQ(checks[0].verdict, Verdict::kFail);
  EXPECT_EQ(checks[0].reason, "not in the record");
  EXPECT_FALSE(checks[0].value);
  const nlohmann::json j = to_json(checks[0]);
  EXPECT_TRUE(j.at("value").is_null());
  EXPECT_EQ(j.at("verdict"), "fail");
}

TEST(Acceptance, AParameterTheCalibrationCouldNotDetermineFailsWithWhy) {
  const auto c = checks_by_name(judge_record(
      kJudgedRecord,
      judged_spec(R"js({"parameter": "gyro_scale.*", "max_abs": 2000, "unit": "ppm"})js")));
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c.at("gyro_scale.x").verdict, Verdict::kPass);
  EXPECT_EQ(c.at("gyro_scale.y").verdict, Verdict::kFail);
  EXPECT_NE(c.at("gyro_scale.y").reason.find("no rotation about y"), std::string::npos);
}

TEST(Acceptance, SigmaLimitsAreChecksOfTheirOwn) {
  const auto c = checks_by_name(judge_record(
      kJudgedRecord,
      judged_spec(
          R"js({"parameter": "gyro_scale.x", "max_abs": 2000, "max_sigma": 20, "unit": "ppm"})js")));
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c.at("gyro_scale.x").verdict, Verdict::kPass);
  const AcceptanceCheck& s = c.at("gyro_scale.x sigma");
  EXPECT_EQ(s.kind, "sigma");
  EXPECT_DOUBLE_EQ(*s.value, 30.0);
  EXPECT_EQ(s.verdict, Verdict::kFail);  // 30 ppm > 20 ppm
}

TEST(Acceptance, NoiseFiguresUseTheirSigmaAndFitFiguresNone) {
  const auto c = checks_by_name(judge_record(
      kJudgedRecord, judged_spec(R"js({"noise": "gyro_arw.*", "max": 0.15, "unit": "deg/sqrt(h)"},
                          {"fit": "chi2_dof", "max": 1.5}, {"fit": "rms_gyro", "max": 0.0004},
                          {"fit": "rms_norm", "max": 1})js")));
  EXPECT_EQ(c.at("gyro_arw.x").verdict, Verdict::kPass);           // 0.12 <= 0.15
  EXPECT_EQ(c.at("gyro_arw.y").verdict, Verdict::kIndeterminate);  // 0.12..0.16
  EXPECT_FALSE(c.count("gyro_arw.z"));  // the record has no gz figures: not a check
  EXPECT_EQ(c.at("chi2_dof").verdict, Verdict::kPass);
  EXPECT_DOUBLE_EQ(*c.at("chi2_dof").sigma, 0.0);
  EXPECT_EQ(c.at("rms_gyro").verdict, Verdict::kFail);      // 0.0005 > 0.0004, no band
  EXPECT_EQ(c.at("rms_norm").reason, "not in the record");  // a table fit has no norm residual
}

TEST(Acceptance, TheValidRangeMustCoverTheSpecifiedTemperatures) {
  auto c = checks_by_name(
      judge_record(kJudgedRecord, judged_spec(R"js({"temperature_range_c": [25, 40]})js")));
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c.at("valid_temperature_c.min").verdict, Verdict::kPass);
  EXPECT_EQ(c.at("valid_temperature_c.max").verdict, Verdict::kPass);
  c = checks_by_name(
      judge_record(kJudgedRecord, judged_spec(R"js({"temperature_range_c": [-40, 40]})js")));
  EXPECT_EQ(c.at("valid_temperature_c.min").verdict, Verdict::kFail);  // 20.5 above -40
  EXPECT_EQ(c.at("valid_temperature_c.max").verdict, Verdict::kPass);
  nlohmann::json no_temperature = kJudgedRecord;
  no_temperature["valid_temperature_c"] = {{"min", nullptr}, {"max", nullptr}};
  c = checks_by_name(
      judge_record(no_temperature, judged_spec(R"js({"temperature_range_c": [25, 40]})js")));
  EXPECT_EQ(c.at("valid_temperature_c.min").verdict, Verdict::kFail);
}

TEST(Acceptance, AUnitAsJsonHasTheIssuesShape) {
  UnitAcceptance u;
  u.device = "imu0";
  u.serial = "SN7";
  u.calibration = 4;
  u.run = 2;
  const AcceptanceSpec spec =
      judged_spec(R"js({"parameter": "gyro_bias.*", "max_abs": 0.005, "unit": "deg/s"})js");
  u.checks = judge_record(kJudgedRecord, spec);
  u.verdict = unit_verdict(u.checks);
  const nlohmann::json j = to_json(u, spec);
  for (const char* key : {"device", "serial", "verdict", "checks", "decision_rule", "k", "spec"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  EXPECT_EQ(j.at("verdict"), "fail");
  ASSERT_EQ(j.at("checks").size(), 3u);
  for (const char* key : {"check", "value", "sigma", "limit", "verdict"}) {
    EXPECT_TRUE(j.at("checks")[0].contains(key)) << key;
  }
  EXPECT_EQ(j.at("checks")[0].at("limit"), 0.005);
  EXPECT_EQ(j.at("checks")[0].at("limit_kind"), "max_abs");
  EXPECT_EQ(j.at("checks")[0].at("limit_text"), "|v| <= 0.005 deg/s");
  EXPECT_TRUE(j.at("as_found").is_null());
}

}  // namespace
}  // namespace calstand::analysis
