// The factory line as a user runs it, on the simulator: a fixture of three LN200-class units on
// different mounts, each with its serial (two read from the simulated device, one given with
// the run), one unit built with a gyro bias ten times its specification. One six-position run
// calibrates all three; acceptance passes two and fails the third naming the parameter; each
// unit gets a one-page certificate; the lot flags the odd unit; every export reads back.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

#include "cli_runner.hpp"

namespace {

using calstand::testing::read_text;
using calstand::testing::Result;
using calstand::testing::run;
using calstand::testing::write_text;

constexpr const char* kModel = "accel_bias,accel_scale,accel_misalignment,gyro_bias,earth_rate";
/// The odd unit's gyro x bias: 180 deg/h, ten times the specification's 18 deg/h [deg/s].
constexpr double kOddGyroBiasDps = 0.05;

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

class FactoryLine : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = ::testing::TempDir() + "calstand-factory-" + std::to_string(::getpid()) + "/";
    std::filesystem::create_directories(dir_);
    db_ = dir_ + "line.db";
    // Three units drawn from the LN200 datasheet (turn-on bias, bias instability, random walks),
    // the third with its gyro x bias out of specification.
    nlohmann::json station = nlohmann::json::parse(
        read_text(std::string(CALSTAND_SOURCE_DIR) + "/sim/stations/default.json"));
    const nlohmann::json base = station["imus"][0];
    station["imus"] = nlohmann::json::array();
    const std::vector<std::vector<double>> mounts = {{0, 0, 0}, {0, 0, 90}, {180, 0, 0}};
    for (int i = 0; i < 3; ++i) {
      const std::string truth = dir_ + "unit" + std::to_string(i) + ".truth.json";
      const Result drawn =
          run("truth-from-spec ln200 --seed " + std::to_string(11 + i) + " --out " + truth);
      ASSERT_EQ(drawn.exit_code, 0) << drawn.out;
      if (i == 2) {
        nlohmann::json t = nlohmann::json::parse(read_text(truth));
        t["parameters"]["gyro_bias.x"] = kOddGyroBiasDps;
        write_text(truth, t.dump(2));
      }
      nlohmann::json imu = base;
      imu.erase("model");
      imu["name"] = "imu" + std::to_string(i);
      imu["truth_file"] = truth;
      imu["mount_rpy_deg"] = mounts[i];
      if (i != 1) imu["serial"] = "FX-100" + std::to_string(i + 1);  // imu1's plate is unread
      station["imus"].push_back(imu);
    }
    station["require_serial"] = true;
    station["equipment"] = {{{"name", "table encoders"},
                             {"id", "AC-1"},
                             {"calibrated", "2026-01-10"},
                             {"due", "2099-01-10"}},
                            {{"name", "chamber sensor"},
                             {"id", "PT-7"},
                             {"calibrated", "2020-01-10"},
                             {"due", "2021-01-10"}}};
    station_ = dir_ + "fixture.json";
    write_text(station_, station.dump(2));
    spec_ = dir_ + "spec.json";
    // The issue's form: gyro bias and scale-type limits by pattern, k = 2.
    write_text(spec_, R"js({"format": "calstand-acceptance/1", "name": "LN200 line rev A", "k": 2,
      "limits": [{"parameter": "gyro_bias.*", "max_abs": 0.005, "unit": "deg/s"},
                 {"parameter": "accel_bias.*", "max_abs": 0.049, "unit": "m/s^2"},
                 {"parameter": "accel_scale.*", "max_abs": 2000, "unit": "ppm"}]})js");
  }
  static void TearDownTestSuite() { std::filesystem::remove_all(dir_); }

  static inline std::string dir_;
  static inline std::string db_;
  static inline std::string station_;
  static inline std::string spec_;
};

TEST_F(FactoryLine, OneRunCalibratesTheFixtureJudgesCertifiesAndExportsEveryUnit) {
  // The plan checks every unit's mount: six positions determine each unit's accelerometer.
  Result r = run("plan six-position --json --station " + station_ + " --model " + kModel);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const nlohmann::json coverage = nlohmann::json::parse(r.out)["coverage"];
  ASSERT_EQ(coverage["units"].size(), 3u);
  for (const auto& u : coverage["units"]) EXPECT_EQ(u["undetermined"].size(), 0u) << u.dump();

  // A production station refuses a unit without a serial before anything is written.
  r = run("run six-position --quiet --station " + station_ + " --db " + db_);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("units.imu1"), std::string::npos) << r.out;
  EXPECT_FALSE(std::filesystem::exists(db_));

  r = run("run six-position --quiet --set capture_s=60 --station " + station_ + " --db " + db_ +
          " --unit imu1=FX-1002");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  r = run("show --json --db " + db_ + " --run 1");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const nlohmann::json units = nlohmann::json::parse(r.out)["units"];
  ASSERT_EQ(units.size(), 3u);
  EXPECT_EQ(units[0]["serial"], "FX-1001");
  EXPECT_EQ(units[0]["source"], "device");
  EXPECT_EQ(units[1]["serial"], "FX-1002");
  EXPECT_EQ(units[1]["source"], "submitted");

  // calibrate: one record per unit, each naming its unit.
  r = run("calibrate --json --db " + db_ + " --run 1 --model " + kModel + " --out-dir " + dir_);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const nlohmann::json calibrations = nlohmann::json::parse(r.out)["calibrations"];
  ASSERT_EQ(calibrations.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(calibrations[i]["record"]["device"]["serial"], "FX-100" + std::to_string(i + 1));
    EXPECT_TRUE(std::filesystem::exists(calibrations[i]["file"].get<std::string>()));
  }

  // accept: two passes and a fail naming the odd unit's parameter; exit 1, JUnit for CI.
  r = run(
      "accept --json --db " + db_ + " --run 1 --spec " + spec_ + " --junit " + dir_ + "junit.xml",
      dir_ + "accept.err");
  EXPECT_EQ(r.exit_code, 1) << r.out << read_text(dir_ + "accept.err");
  const nlohmann::json accepted = nlohmann::json::parse(r.out);
  ASSERT_EQ(accepted["units"].size(), 3u);
  EXPECT_EQ(accepted["units"][0]["verdict"], "pass") << accepted["units"][0].dump();
  EXPECT_EQ(accepted["units"][1]["verdict"], "pass") << accepted["units"][1].dump();
  EXPECT_EQ(accepted["units"][2]["verdict"], "fail");
  EXPECT_EQ(accepted["units"][2]["serial"], "FX-1003");
  std::vector<std::string> failed;
  for (const auto& c : accepted["units"][2]["checks"]) {
    if (c["verdict"] == "fail") failed.push_back(c["check"]);
  }
  EXPECT_EQ(failed, std::vector<std::string>{"gyro_bias.x"});
  const std::string junit = read_text(dir_ + "junit.xml");
  EXPECT_EQ(count(junit, "<testsuite "), 3u);
  EXPECT_EQ(count(junit, "<failure"), 1u) << junit;

  // The record in force: the passing unit's, never the failed one's.
  r = run("calibrations --json --db " + db_ + " --serial FX-1003");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const nlohmann::json odd = nlohmann::json::parse(r.out)["calibrations"];
  ASSERT_EQ(odd.size(), 1u);
  EXPECT_EQ(odd[0]["verdict"], "fail");
  EXPECT_FALSE(odd[0]["in_force"].get<bool>());
  r = run("calibrations --json --db " + db_ + " --serial FX-1001");
  EXPECT_TRUE(nlohmann::json::parse(r.out)["calibrations"][0]["in_force"].get<bool>()) << r.out;

  // The lot: yield 2 of 3, and the odd unit far from its siblings on gyro_bias.x.
  r = run("lot --json --db " + db_ + " --html " + dir_ + "lot.html");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const nlohmann::json lot = nlohmann::json::parse(r.out);
  EXPECT_NEAR(lot["yield"].get<double>(), 2.0 / 3.0, 1e-12);
  bool flagged = false;
  for (const auto& p : lot["parameters"]) {
    for (const auto& o : p["outliers"]) {
      if (p["name"] == "gyro_bias.x" && o["serial"] == "FX-1003") flagged = true;
    }
  }
  EXPECT_TRUE(flagged) << lot.dump();
  EXPECT_GE(count(read_text(dir_ + "lot.html"), "<svg"), 10u);

  // Every export of a passing unit's record reads back to the record's numbers (the CSV here;
  // each format's own read-back is in tests/unit/analysis/export_*_test.cpp).
  const std::string record = calibrations[0]["file"];
  for (const std::string format : {"px4", "ardupilot", "openvins", "csv"}) {
    r = run("export-calibration --record " + record + " --format " + format + " --out " + dir_ +
                "unit1." + format + " --update-rate 400",
            dir_ + "export.err");
    EXPECT_EQ(r.exit_code, 0) << format << ": " << r.out << read_text(dir_ + "export.err");
  }
  const nlohmann::json doc = nlohmann::json::parse(read_text(record));
  std::istringstream csv(read_text(dir_ + "unit1.csv"));
  std::map<std::string, double> exported;
  for (std::string line; std::getline(csv, line);) {
    std::vector<std::string> cells;
    std::stringstream row(line);
    for (std::string cell; std::getline(row, cell, ',');) cells.push_back(cell);
    if (cells.size() > 10 && !cells[10].empty() && cells[9] != "parameter") {
      exported[cells[9]] = std::stod(cells[10]);
    }
  }
  for (const auto& p : doc["parameters"]) {
    ASSERT_TRUE(exported.count(p["name"])) << p["name"];
    EXPECT_EQ(exported[p["name"]], p["value"].get<double>()) << p["name"];
  }
}

TEST_F(FactoryLine, EachUnitsCertificateIsOnePageNamingItsUnitVerdictAndEquipment) {
  // Relies on the first test's database when run in order; makes its own otherwise.
  if (!std::filesystem::exists(db_)) {
    ASSERT_EQ(run("run six-position --quiet --set capture_s=60 --station " + station_ + " --db " +
                  db_ + " --unit imu1=FX-1002")
                  .exit_code,
              0);
    ASSERT_EQ(run("calibrate --db " + db_ + " --run 1 --model " + kModel + " --out-dir " + dir_)
                  .exit_code,
              0);
    run("accept --db " + db_ + " --run 1 --spec " + spec_);
  }
  for (int i = 0; i < 3; ++i) {
    const std::string device = "imu" + std::to_string(i);
    const std::string html = dir_ + device + ".html";
    Result r = run("certificate --db " + db_ + " --run 1 --device " + device + " --out " + html);
    ASSERT_EQ(r.exit_code, 0) << r.out;
    const std::string page = read_text(html);
    EXPECT_NE(page.find("FX-100" + std::to_string(i + 1)), std::string::npos);
    EXPECT_NE(page.find(i == 2 ? "verdict fail" : "verdict pass"), std::string::npos) << device;
    EXPECT_NE(page.find("overdue at the run"), std::string::npos) << "the chamber sensor's";
    EXPECT_EQ(count(page, "<svg"), 1u) << "the residual plot";

    const std::string pdf = dir_ + device + ".pdf";
    r = run("certificate --db " + db_ + " --run 1 --device " + device + " --out " + pdf);
    if (r.exit_code != 0 && r.out.find("chromium") != std::string::npos &&
        std::getenv("CALSTAND_REQUIRE_BROWSER") == nullptr) {
      GTEST_SKIP() << "no chromium here (scripts/setup-deps.sh installs it): " << r.out;
    }
    ASSERT_EQ(r.exit_code, 0) << r.out;
    const std::string printed = read_text(pdf);
    ASSERT_EQ(printed.rfind("%PDF-", 0), 0u);
    // One page object per page in Chromium's PDF; "/Type /Pages" is the page tree.
    EXPECT_EQ(count(printed, "/Type /Page") - count(printed, "/Type /Pages"), 1u) << device;
  }
  // The page as a person sees it: an A4 screenshot holds tables and a plot, not a blank page.
  write_text(dir_ + "blank.html", "<!DOCTYPE html><html><body></body></html>");
  const auto shoot = [&](const std::string& page, const std::string& png) {
    const std::string command =
        "chromium --headless --no-sandbox --disable-gpu --hide-scrollbars "
        "--window-size=794,1123 --screenshot=" +
        png + " file://" + page + " >/dev/null 2>&1";
    return std::system(command.c_str());
  };
  ASSERT_EQ(shoot(dir_ + "imu2.html", dir_ + "imu2.png"), 0);
  ASSERT_EQ(shoot(dir_ + "blank.html", dir_ + "blank.png"), 0);
  const std::string png = read_text(dir_ + "imu2.png");
  ASSERT_EQ(png.substr(1, 3), "PNG");
  EXPECT_GT(png.size(), 50u * 1024u);
  EXPECT_GT(png.size(), 5u * read_text(dir_ + "blank.png").size());
}

}  // namespace
