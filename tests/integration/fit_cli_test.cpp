// calstand fit, calibrate and apply on campaigns recorded on the simulator: the parameters come
// back within their sigmas of the truth the station file gives, a record applied to another run
// of the same unit takes its residual to the noise floor, and bad input is refused clearly.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "cli_runner.hpp"
#include "known_imu_station.hpp"

namespace {

using calstand::testing::read_text;
using calstand::testing::run;
using calstand::testing::write_text;

class FitCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = ::testing::TempDir() + "calstand-fit-cli-" + std::to_string(::getpid()) + "/";
    std::filesystem::create_directories(dir_);
    station_ = dir_ + "station.json";
    write_text(station_, calstand::testing::known_imu_station("fit-test", 3));
    db_ = dir_ + "fit.db";
    // Run 1: six positions; run 2: rates about body x, y and z; run 3: six positions again.
    for (const std::string args :
         {"six-position --set capture_s=20", "rate-ladder --set rates=[30,90] --set revolutions=2",
          "six-position --set capture_s=20"}) {
      const auto r = run("run " + args + " --station " + station_ + " --db " + db_ + " --quiet");
      ASSERT_EQ(r.exit_code, 0) << r.out;
    }
  }
  static void TearDownTestSuite() { std::filesystem::remove_all(dir_); }

  static nlohmann::json fit_json(const std::string& args) {
    const auto r = run("fit --db " + db_ + " " + args + " --json", dir_ + "stderr.txt");
    EXPECT_EQ(r.exit_code, 0) << read_text(dir_ + "stderr.txt");
    return nlohmann::json::parse(r.out);
  }

  static inline std::string dir_, station_, db_;
};

double truth(const std::string& name) { return calstand::testing::known_imu_truth(name); }

TEST_F(FitCli, SixPositionRecoversTheAccelerometerWithinThreeSigma) {
  const auto j =
      fit_json("--run 1 --sensor accel --model accel_bias,accel_scale,accel_misalignment");
  ASSERT_EQ(j["parameters"].size(), 12u) << j.dump(2);
  for (const auto& p : j["parameters"]) {
    const std::string name = p["name"];
    EXPECT_NEAR(p["value"].get<double>(), truth(name), 3.0 * p["sigma"].get<double>()) << name;
  }
  EXPECT_LT(j["chi2_dof"].get<double>(), 3.0);
  EXPECT_EQ(j["noise_floor"]["accel"].size(), 3u);
}

TEST_F(FitCli, RateLadderRecoversTheGyroAndReportsWhatItCannotSee) {
  const auto j = fit_json(
      "--run 2 --sensor gyro --model "
      "gyro_bias,gyro_scale,gyro_misalignment,earth_rate,gyro_temp_bias");
  std::set<std::string> fitted;
  for (const auto& p : j["parameters"]) {
    const std::string name = p["name"];
    fitted.insert(name);
    EXPECT_NEAR(p["value"].get<double>(), truth(name), 3.0 * p["sigma"].get<double>()) << name;
  }
  // The ladder turns about body x, y and z: every scale factor and misalignment.
  for (const char* name : {"gyro_scale.x", "gyro_scale.y", "gyro_scale.z", "gyro_misalignment.xy",
                           "gyro_misalignment.yx", "gyro_misalignment.zx"}) {
    EXPECT_TRUE(fitted.count(name)) << name << "\n" << j["unidentifiable"].dump(2);
  }
  // ... all at one temperature: a temperature coefficient is not seen.
  std::set<std::string> missing;
  for (const auto& u : j["unidentifiable"]) missing.insert(u["name"].get<std::string>());
  EXPECT_EQ(missing,
            (std::set<std::string>{"gyro_temp_bias.x1", "gyro_temp_bias.y1", "gyro_temp_bias.z1"}))
      << j["unidentifiable"].dump(2);
  EXPECT_LT(j["chi2_dof"].get<double>(), 3.0);
}

TEST_F(FitCli, CalibrateStoresAndApplyCorrectsAValidationRun) {
  const std::string record = dir_ + "cal.json";
  auto r = run("calibrate --db " + db_ +
               " --run 1 --model accel_bias,accel_scale,accel_misalignment,"
               "gyro_bias,earth_rate --out " +
               record + " --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto out = nlohmann::json::parse(r.out);
  ASSERT_EQ(out["calibrations"].size(), 1u);
  EXPECT_GE(out["calibrations"][0]["calibration_id"].get<int>(), 1);
  const auto doc = nlohmann::json::parse(read_text(record));
  EXPECT_EQ(doc["format"], "calstand-calibration/1");
  EXPECT_EQ(doc["device"]["name"], "imu0");
  EXPECT_EQ(doc["procedure"]["name"], "six-position");

  // Raw run 3 against the bare reference: far from the floor. Corrected: at the floor.
  const auto raw = fit_json("--run 3 --sensor accel --model earth_rate");
  EXPECT_GT(raw["chi2_dof"].get<double>(), 100.0);
  r = run("apply --record " + record + " --db " + db_ + " --run 3");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const std::string prefix = "run ";
  const int corrected = std::stoi(r.out.substr(prefix.size()));
  const auto after =
      fit_json("--run " + std::to_string(corrected) + " --sensor accel --model earth_rate");
  EXPECT_LT(after["chi2_dof"].get<double>(), 3.0);
  const double floor = after["noise_floor"]["accel"][2].get<double>();
  EXPECT_LT(after["residual_rms"]["accel"].get<double>(), 2.0 * floor);
}

TEST_F(FitCli, ImportedCopyFitsTheSame) {
  const std::string out = dir_ + "export";
  ASSERT_EQ(run("export --db " + db_ + " --run 1 --out " + out).exit_code, 0);
  const std::string other = dir_ + "imported.db";
  const auto r = run("import " + out + " --db " + other);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto a = fit_json("--run 1 --sensor accel --model accel_bias,accel_scale");
  const auto rb =
      run("fit --db " + other + " --run 1 --sensor accel --model accel_bias,accel_scale --json");
  ASSERT_EQ(rb.exit_code, 0) << rb.out;
  const auto b = nlohmann::json::parse(rb.out);
  ASSERT_EQ(a["parameters"].size(), b["parameters"].size());
  for (std::size_t i = 0; i < a["parameters"].size(); ++i) {
    EXPECT_NEAR(a["parameters"][i]["value"].get<double>(),
                b["parameters"][i]["value"].get<double>(),
                1e-9 * (1.0 + std::abs(a["parameters"][i]["value"].get<double>())));
  }
}

TEST_F(FitCli, BadInputIsRefusedWithWhereAndWhy) {
  auto r = run("fit --db " + db_ + " --run 1 --model gyro_bais");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.out.find("did you mean \"gyro_bias\""), std::string::npos) << r.out;
  r = run("fit --db " + db_ + " --run 99");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.out.find("run 99"), std::string::npos) << r.out;
  r = run("fit --db " + dir_ + "absent.db --run 1");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_FALSE(std::filesystem::exists(dir_ + "absent.db"));
  r = run("fit --db " + db_ + " --run 1 --custom 'k=gyro:rate_{axis}*nonsense'");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.out.find("nonsense"), std::string::npos) << r.out;
  write_text(dir_ + "bad-record.json", R"({"format": "calstand-calibration/1"})");
  r = run("apply --record " + dir_ + "bad-record.json --db " + db_ + " --run 1");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.out.find("bad-record.json"), std::string::npos) << r.out;
}

}  // namespace

// A recording made without a table, as a user has one from another tool: `calstand sim-session`
// writes it (calstand-import/2 without `table`), `import` reads it, and the loop runs on it:
// fit, diagnose, calibrate, history and the report, each saying what such a run can fit.
class TableFreeCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = ::testing::TempDir() + "calstand-table-free-cli-" + std::to_string(::getpid()) + "/";
    std::filesystem::create_directories(dir_);
    db_ = dir_ + "hand.db";
    auto r = run("sim-session --kind hand --model adis16488 --seed 5 --poses 16 --rate 200 --out " +
                 dir_ + "session");
    ASSERT_EQ(r.exit_code, 0) << r.out;
    r = run("import " + dir_ + "session --db " + db_ + " --json");
    ASSERT_EQ(r.exit_code, 0) << r.out;
    run_ = nlohmann::json::parse(r.out).at("run").get<int>();
  }
  static void TearDownTestSuite() { std::filesystem::remove_all(dir_); }
  static std::string on_run() { return " --db " + db_ + " --run " + std::to_string(run_); }
  static inline std::string dir_, db_;
  static inline int run_ = 0;
};

TEST_F(TableFreeCli, FitDiagnoseCalibrateAndHistoryRunWithoutATable) {
  const std::string err = dir_ + "stderr.txt";
  auto r = run("fit" + on_run() + " --json", err);
  ASSERT_EQ(r.exit_code, 0) << read_text(err);
  const auto fit = nlohmann::json::parse(r.out);
  EXPECT_EQ(fit.at("method"), "gravity_norm");
  EXPECT_EQ(fit.at("model").size(), 6u);
  EXPECT_NE(fit.at("notes")[0].get<std::string>().find("earth_rate"), std::string::npos);

  r = run("diagnose" + on_run(), err);
  ASSERT_EQ(r.exit_code, 0) << read_text(err);
  EXPECT_NE(r.out.find("gyro_g_sensitivity"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("not testable: earth_rate"), std::string::npos) << r.out;

  r = run("calibrate" + on_run() + " --model gyro_bias,gyro_g_sensitivity --out " + dir_ +
              "record.json --json",
          err);
  ASSERT_EQ(r.exit_code, 0) << read_text(err);
  const auto record = nlohmann::json::parse(read_text(dir_ + "record.json"));
  EXPECT_EQ(record.at("method"), "gravity_norm");
  EXPECT_EQ(record.at("model").back(), "gyro_g_sensitivity");

  r = run("history" + on_run() + " --json", err);
  ASSERT_EQ(r.exit_code, 0) << read_text(err);
  const auto history = nlohmann::json::parse(r.out);
  ASSERT_EQ(history.size(), 3u);
  EXPECT_EQ(history[2].at("command"), "calibrate");
  EXPECT_TRUE(history[2].at("rms_turn_deg").is_number());
  r = run("history" + on_run(), err);
  EXPECT_NE(r.out.find("turns [deg]"), std::string::npos) << r.out;

  // A term such a run cannot fit is refused by name, with nothing recorded.
  r = run("fit" + on_run() + " --model gyro_bias,gyro_temp_bias", err);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(read_text(err).find("gyro_temp_bias cannot be fitted on a run without a table"),
            std::string::npos)
      << read_text(err);
  r = run("history" + on_run() + " --json", err);
  EXPECT_EQ(nlohmann::json::parse(r.out).size(), 3u);
}

TEST_F(TableFreeCli, TheReportShowsThePosesTurnsAndCandidates) {
  const std::string err = dir_ + "stderr.txt";
  const auto r = run("report" + on_run() + " --out " + dir_ + "report.html", err);
  ASSERT_EQ(r.exit_code, 0) << read_text(err);
  const std::string page = read_text(dir_ + "report.html");
  for (const char* part : {"Recorded without a table", "id=\"residuals\"", "|f| - g at each",
                           "gravity direction after each turn", "id=\"candidates\"",
                           "gyro_g_sensitivity", "id=\"poses\"", "initial rest"}) {
    EXPECT_NE(page.find(part), std::string::npos) << part;
  }
}
