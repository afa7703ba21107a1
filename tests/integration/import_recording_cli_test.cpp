// calstand import of recordings as a user runs it (issue 32): an MCAP file, a ROS 2 bag
// folder, a ROS 1 bag and a EuRoC folder written by tests/support/write_recordings.py become
// table-free runs that the analyses read; ambiguous topics and broken files are refused with
// exit code 2, the reason, and no run.

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "cli_runner.hpp"

namespace {

using calstand::testing::Result;
using calstand::testing::run;

class ImportRecordingCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new std::string(::testing::TempDir() + "cli_recordings_" + std::to_string(getpid()));
    std::filesystem::remove_all(*dir_);
    const std::string cmd = "/usr/bin/python3 " + std::string(CALSTAND_SOURCE_DIR) +
                            "/tests/support/write_recordings.py " + *dir_ + " --samples 3000";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  }
  static void TearDownTestSuite() {
    std::filesystem::remove_all(*dir_);
    delete dir_;
  }
  static std::string path(const std::string& name) { return *dir_ + "/" + name; }
  static int runs_in(const std::string& db) {
    const Result r = run("runs --json --db " + db);
    return r.exit_code == 0 ? static_cast<int>(nlohmann::json::parse(r.out).size()) : -1;
  }
  static inline std::string* dir_ = nullptr;
};

TEST_F(ImportRecordingCli, McapPrintsTheRunIdThenTheSummaryWithTheDefaultSite) {
  const std::string db = path("mcap.db");
  const Result r = run("import " + path("none.mcap") + " --db " + db, path("mcap.err"));
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_EQ(r.out, "1\n");  // stdout: the id alone, as for folders
  const std::string err = calstand::testing::read_text(path("mcap.err"));
  EXPECT_NE(err.find("/imu/data (sensor_msgs/msg/Imu, cdr): 3000 samples"), std::string::npos)
      << err;
  EXPECT_NE(err.find("default: no site given, latitude 45 deg"), std::string::npos) << err;
  EXPECT_NE(err.find("gaps: 2"), std::string::npos) << err;
  EXPECT_NE(err.find("1 out of order"), std::string::npos) << err;
  // The run reads as any table-free import.
  const Result show = run("runs --json --db " + db);
  ASSERT_EQ(show.exit_code, 0) << show.out;
  EXPECT_EQ(nlohmann::json::parse(show.out)[0]["procedure"], "calstand-import/2") << show.out;
  const Result noise = run("noise --run 1 --json --db " + db);
  EXPECT_EQ(noise.exit_code, 0) << noise.out;
}

TEST_F(ImportRecordingCli, JsonSummaryOfEachFormat) {
  const std::string db = path("formats.db");
  for (const std::string& args :
       {path("db3"), path("none.bag"), path("euroc") + " --topic /imu0", path("ros1.mcap")}) {
    if (args == path("none.bag") && !std::filesystem::exists(path("none.bag"))) continue;
    const Result r =
        run("import " + args + " --latitude 48.1 --height 520 --json --db " + db, "/dev/null");
    ASSERT_EQ(r.exit_code, 0) << args << ": " << r.out;
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["samples"], 3000) << r.out;
    EXPECT_EQ(j["site"]["source"], "given; gravity is the normal gravity there") << r.out;
    EXPECT_NEAR(j["site"]["gravity_mps2"].get<double>(), 9.8075, 1e-3) << r.out;
    EXPECT_EQ(j["gaps"]["count"], 2) << r.out;
  }
  EXPECT_EQ(runs_in(db), std::filesystem::exists(path("none.bag")) ? 4 : 3);
}

TEST_F(ImportRecordingCli, RefusalsAreExitCode2WithTheReasonAndWriteNothing) {
  const std::string db = path("refused.db");
  Result r = run("import " + path("two_imu.mcap") + " --db " + db);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("2 IMU topics; choose one with --topic"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("/imu2 (sensor_msgs/msg/Imu, 3000 messages"), std::string::npos) << r.out;
  r = run("import " + path("none.mcap") + " --topic /status --db " + db);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("not an IMU topic"), std::string::npos) << r.out;
  r = run("import " + path("crc.mcap") + " --db " + db);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("CRC mismatch"), std::string::npos) << r.out;
  r = run("import " + path("csv") + " --topic /imu --db " + db);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("only for recordings"), std::string::npos) << r.out;
  EXPECT_LE(runs_in(db), 0);  // no database, or one without runs
}

TEST_F(ImportRecordingCli, TheCsvFolderStillImports) {
  const Result r = run("import " + path("csv") + " --json --db " + path("csv.db"));
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_EQ(nlohmann::json::parse(r.out)["samples"], 3000) << r.out;
}

// Every number of `a` and `b` (same shape) within a relative 1e-6 (absolute 1e-12 near zero).
void expect_close(const nlohmann::json& a, const nlohmann::json& b, const std::string& at) {
  if (a.is_number() && b.is_number()) {
    const double x = a.get<double>();
    const double y = b.get<double>();
    EXPECT_NEAR(x, y, 1e-6 * std::max(std::abs(x), std::abs(y)) + 1e-12) << at;
    return;
  }
  ASSERT_EQ(a.type(), b.type()) << at;
  if (a.is_array()) {
    ASSERT_EQ(a.size(), b.size()) << at;
    for (std::size_t i = 0; i < a.size(); ++i) {
      expect_close(a[i], b[i], at + "[" + std::to_string(i) + "]");
    }
  } else if (a.is_object()) {
    for (const auto& [k, v] : a.items()) {
      ASSERT_TRUE(b.contains(k)) << at << "." << k;
      expect_close(v, b[k], at + "." + k);
    }
  } else {
    EXPECT_EQ(a, b) << at;
  }
}

// The table-free calibration of a hand-held session is the same whether the session comes as
// its calstand-import/2 CSV or as the MCAP file a ROS 2 recorder would have written (angular
// rate in rad/s, stamps in sec + nanosec).
TEST_F(ImportRecordingCli, AHandHeldSessionFromMcapCalibratesAsFromCsv) {
  Result r = run("sim-session --kind hand --model adis16488 --seed 5 --poses 16 --rate 200 --out " +
                 path("hand"));
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const std::string cmd = "/usr/bin/python3 " + std::string(CALSTAND_SOURCE_DIR) +
                          "/tests/support/write_recordings.py --from-csv " + path("hand") + " " +
                          path("hand.mcap");
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const auto meta =
      nlohmann::json::parse(calstand::testing::read_text(path("hand") + "/meta.json"));
  const auto& site = meta.at("site");
  const std::string db = path("hand.db");
  r = run("import " + path("hand") + " --db " + db, "/dev/null");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  r = run("import " + path("hand.mcap") + " --db " + db + " --latitude " +
              site.at("latitude_deg").dump() + " --height " + site.at("height_m").dump() +
              " --gravity " + site.at("gravity_mps2").dump(),
          "/dev/null");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const Result csv = run("fit --db " + db + " --run 1 --json", "/dev/null");
  const Result mcap = run("fit --db " + db + " --run 2 --json", "/dev/null");
  ASSERT_EQ(csv.exit_code, 0) << csv.out;
  ASSERT_EQ(mcap.exit_code, 0) << mcap.out;
  const auto a = nlohmann::json::parse(csv.out);
  const auto b = nlohmann::json::parse(mcap.out);
  EXPECT_EQ(a.at("method"), b.at("method"));
  expect_close(a.at("parameters"), b.at("parameters"), "parameters");
}

}  // namespace
