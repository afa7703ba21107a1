// calstand accept as a user runs it, on the built-in LN200-class station (its sigmas are what a
// six-position run of such a unit gives, bias wander included): a specification written from
// the unit's truth (calstand station --json) passes, the same with one limit at half the largest
// accelerometer scale factor fails naming that parameter; JSON, JUnit XML, exit codes, and a
// bad specification refused by file and field with nothing stored.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "cli_runner.hpp"

namespace {

using calstand::testing::read_text;
using calstand::testing::Result;
using calstand::testing::run;
using calstand::testing::write_text;

constexpr const char* kModel = "accel_bias,accel_scale,accel_misalignment,gyro_bias,earth_rate";

// Limits an LN200-class datasheet allows (gyro bias 0.005 deg/s = 18 deg/h, accelerometer bias
// 5 mg, scale factor 2000 ppm, axes within 1 mrad): a healthy unit is well inside them.
constexpr const char* kDatasheetLimits =
    R"js({"parameter": "gyro_bias.*", "max_abs": 0.005, "unit": "deg/s"},
         {"parameter": "accel_bias.*", "max_abs": 0.049, "unit": "m/s^2"},
         {"parameter": "accel_scale.*", "max_abs": 2000, "unit": "ppm"},
         {"parameter": "*_misalignment.*", "max_abs": 0.001, "unit": "rad"})js";

class AcceptCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = ::testing::TempDir() + "calstand-accept-cli-" + std::to_string(::getpid()) + "/";
    std::filesystem::create_directories(dir_);
    const Result station = run("station --json");
    ASSERT_EQ(station.exit_code, 0) << station.out;
    truth_ = nlohmann::json::parse(station.out)["derived"]["imus"][0]["truth"]["parameters"];
  }
  static void TearDownTestSuite() { std::filesystem::remove_all(dir_); }

  // A database of its own with one six-position run on the built-in station, calibrated.
  static std::string calibrated_db(const std::string& name) {
    const std::string db = dir_ + name + ".db";
    Result r = run("run six-position --quiet --db " + db);
    EXPECT_EQ(r.exit_code, 0) << r.out;
    r = run("calibrate --db " + db + " --run 1 --model " + kModel + " --out " + dir_ + name +
            ".json");
    EXPECT_EQ(r.exit_code, 0) << r.out;
    return db;
  }

  static std::string spec_file(const std::string& name, const std::string& limits) {
    const std::string path = dir_ + name + ".spec.json";
    write_text(path, R"js({"format": "calstand-acceptance/1", "name": ")js" + name +
                         R"js(", "k": 2, "limits": [)js" + limits + "]}");
    return path;
  }

  // The accelerometer scale factor the unit has most of, by its truth.
  static std::string largest_accel_scale() {
    std::string best;
    for (const char* axis : {"x", "y", "z"}) {
      const std::string name = std::string("accel_scale.") + axis;
      if (best.empty() || std::abs(truth_.value(name, 0.0)) > std::abs(truth_.value(best, 0.0)))
        best = name;
    }
    return best;
  }

  static inline std::string dir_;
  static inline nlohmann::json truth_;
};

TEST_F(AcceptCli, ADatasheetSpecPassesAndOneTighterLimitFailsNamingTheParameter) {
  const std::string db = calibrated_db("pass-fail");
  const std::string loose = spec_file("datasheet", kDatasheetLimits);
  Result r = run("accept --db " + db + " --run 1 --spec " + loose + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  nlohmann::json j = nlohmann::json::parse(r.out);
  ASSERT_EQ(j.at("units").size(), 1u);
  const nlohmann::json& unit = j.at("units")[0];
  EXPECT_EQ(unit.at("device"), "imu0");
  EXPECT_TRUE(unit.at("serial").is_string());
  EXPECT_EQ(unit.at("verdict"), "pass");
  // 3 gyro biases, 3 + 3 accelerometer biases and scales, 6 misalignments (the gyro's are not
  // in a six-position record, the accelerometer's are).
  EXPECT_EQ(unit.at("checks").size(), 15u) << unit.dump(2);
  for (const auto& c : unit.at("checks")) {
    for (const char* key : {"check", "value", "sigma", "limit", "verdict"}) {
      EXPECT_TRUE(c.contains(key)) << key << " missing in " << c.dump();
    }
    EXPECT_EQ(c.at("verdict"), "pass") << c.dump();
    EXPECT_GT(c.at("sigma").get<double>(), 0.0) << c.dump();
  }
  EXPECT_EQ(j.at("k"), 2.0);
  EXPECT_NE(j.at("decision_rule").get<std::string>().find("ISO 14253-1"), std::string::npos);

  // The same with the largest accelerometer scale factor limited to half its true value.
  const std::string name = largest_accel_scale();
  const double half = 0.5 * std::abs(truth_.at(name).get<double>());
  const std::string tight =
      spec_file("tight", std::string(kDatasheetLimits) + R"js(, {"parameter": ")js" + name +
                             R"js(", "max_abs": )js" + nlohmann::json(half).dump() +
                             R"js(, "unit": "ppm"})js");
  const std::string xml = dir_ + "tight.xml";
  r = run("accept --db " + db + " --run 1 --spec " + tight + " --json --junit " + xml);
  ASSERT_EQ(r.exit_code, 1) << r.out;
  j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j.at("units")[0].at("verdict"), "fail");
  std::vector<std::string> failed;
  for (const auto& c : j.at("units")[0].at("checks")) {
    if (c.at("verdict") != "pass") failed.push_back(c.at("check").get<std::string>());
  }
  EXPECT_EQ(failed, std::vector<std::string>{name}) << r.out;

  // The JUnit file: one test case per check, the one failure naming the parameter.
  const std::string junit = read_text(xml);
  EXPECT_NE(junit.find("<testsuite name=\"imu0"), std::string::npos) << junit;
  EXPECT_NE(junit.find("tests=\"16\" failures=\"1\""), std::string::npos) << junit;
  const auto failure = junit.find("<failure type=\"fail\"");
  ASSERT_NE(failure, std::string::npos) << junit;
  const auto testcase = junit.rfind("<testcase name=\"", failure);
  EXPECT_EQ(junit.substr(testcase, 16 + name.size() + 1), "<testcase name=\"" + name + "\"");

  // Text: the verdict and the failing check with its reason.
  r = run("accept --db " + db + " --run 1 --spec " + tight);
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_NE(r.out.find("imu0"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("decision rule:"), std::string::npos) << r.out;
  // The parameter is judged twice (by its pattern and by its own limit): one line fails.
  std::size_t failing_lines = 0;
  for (std::size_t at = r.out.find("  " + name + " "); at != std::string::npos;
       at = r.out.find("  " + name + " ", at + 1)) {
    const std::string text = r.out.substr(at, r.out.find('\n', at) - at);
    if (text.find("FAIL") != std::string::npos) ++failing_lines;
  }
  EXPECT_EQ(failing_lines, 1u) << r.out;
}

TEST_F(AcceptCli, ABadSpecIsExitCode2NamingFileAndFieldAndStoresNothing) {
  const std::string db = calibrated_db("bad-spec");
  const std::string wrong_unit = spec_file(
      "wrong-unit", R"js({"parameter": "gyro_bias.*", "max_abs": 18, "unit": "deg/h"})js");
  Result r = run("accept --db " + db + " --run 1 --spec " + wrong_unit);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find(wrong_unit), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("limits[0].unit"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("deg/s"), std::string::npos) << r.out;

  const std::string typo =
      spec_file("typo", R"js({"parameter": "gyro_bias.*", "max_abs": 0.005, "units": "deg/s"})js");
  r = run("accept --db " + db + " --run 1 --spec " + typo);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("limits[0]"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("units"), std::string::npos) << r.out;

  r = run("accept --db " + db + " --run 1 --spec " + dir_ + "missing.json");
  EXPECT_EQ(r.exit_code, 2) << r.out;
  r = run("accept --db " + db + " --run 7 --spec " + spec_file("fine", kDatasheetLimits));
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("run 7"), std::string::npos) << r.out;

  // Nothing was stored by the refusals: the first verdict stored is acceptance 1.
  r = run("accept --db " + db + " --run 1 --spec " + spec_file("fine", kDatasheetLimits) +
          " --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_EQ(nlohmann::json::parse(r.out).at("units")[0].at("acceptance_id"), 1);
}

TEST_F(AcceptCli, AnIndeterminateUnitIsExitCode1) {
  // A limit exactly on the record's own value: for any sigma > 0 the interval value +- 2 sigma
  // straddles it, whatever the value is.
  const std::string db = calibrated_db("indeterminate");
  const nlohmann::json record = nlohmann::json::parse(read_text(dir_ + "indeterminate.json"));
  double value = 0.0;
  for (const auto& p : record.at("parameters")) {
    if (p.at("name") == "accel_scale.z") value = p.at("value").get<double>();
  }
  const std::string on_the_value = spec_file(
      "on-the-value", R"js({"parameter": "accel_scale.z", "max_abs": )js" +
                          nlohmann::json(std::abs(value)).dump() + R"js(, "unit": "ppm"})js");
  const Result r = run("accept --db " + db + " --run 1 --spec " + on_the_value + " --json");
  EXPECT_EQ(r.exit_code, 1) << r.out;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j.at("units")[0].at("verdict"), "indeterminate") << r.out;
}

}  // namespace
