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
  EXPECT_GE(out["calibration_id"].get<int>(), 1);
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
