// The calstand command as a user runs it: exit codes, error text and the demo's results.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <string>
#include <sys/wait.h>

namespace {

struct Result {
  int exit_code;
  std::string out;  // stdout and stderr together
};

Result run(const std::string& args) {
  const std::string command = std::string(CALSTAND_BIN) + " " + args + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return {-1, ""};
  std::string out;
  std::array<char, 4096> buf{};
  while (std::size_t n = fread(buf.data(), 1, buf.size(), pipe)) out.append(buf.data(), n);
  const int status = pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

TEST(CliDemo, SixPositionsRateTestAndThermalStepOnTheSimulator) {
  const Result r = run("demo --json --capture 5");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  const double g = j["site"]["gravity_mps2"].get<double>();
  ASSERT_EQ(j["six_position"].size(), 6u);
  // Each position: the named axis reads +/-g within a few mg, the others near zero.
  for (const auto& p : j["six_position"]) {
    const std::string label = p["position"];
    const int axis = label[0] - 'x';
    const double sign = label.find("up") != std::string::npos ? 1.0 : -1.0;
    for (int i = 0; i < 3; ++i) {
      const double want = i == axis ? sign * g : 0.0;
      EXPECT_NEAR(p["accel_mps2"][i].get<double>(), want, 0.02) << label << " axis " << i;
    }
    EXPECT_EQ(p["samples"].get<int>(), 2000) << label;  // 5 s at 400 Hz
  }
  // Two-position estimates agree with the noise-free IMU to the noise of 5 s captures.
  for (const auto& a : j["accel_two_position"]) {
    EXPECT_NEAR(a["bias_mps2"].get<double>(), a["noise_free_bias_mps2"].get<double>(), 2e-3);
    EXPECT_NEAR(a["scale_ppm"].get<double>(), a["noise_free_scale_ppm"].get<double>(), 100.0);
  }
  // CW/CCW over whole revolutions recovers the gyro scale error to a few ppm.
  const auto& rate = j["rate_test"];
  EXPECT_NEAR(rate["gyro_z_scale_ppm"].get<double>(), rate["true_gyro_z_scale_ppm"].get<double>(), 10.0);
  EXPECT_NEAR(rate["gyro_z_bias_dph"].get<double>(), rate["true_gyro_z_bias_dph"].get<double>(), 2.0);
  // The IMU lags the air early on and ends above it by the self-heating.
  const auto& th = j["thermal_step"];
  EXPECT_LT(th[1]["imu_c"].get<double>(), th[1]["air_c"].get<double>() - 5.0);
  EXPECT_GT(th.back()["imu_c"].get<double>(), th.back()["air_c"].get<double>() + 2.0);
  EXPECT_GT(j["simulated_s"].get<double>(), 3600.0);
}

TEST(CliDemo, BadStationFileIsExitCode2WithEveryViolation) {
  const std::string path = ::testing::TempDir() + "bad_station.json";
  FILE* f = fopen(path.c_str(), "w");
  ASSERT_NE(f, nullptr);
  fputs(R"({"format": "calstand-station/1", "name": "x",
            "site": {"latitude_deg": 99, "height_m": 0},
            "table": {"backend": "sim", "outer_axis": [0,1,0], "inner_axis": [0,0,1],
                      "outer": {"max_rate_dps": 10}, "inner": {"max_rate_dps": 10, "max_accel_dps2": 5}},
            "chamber": {"backend": "sim", "min_c": 0, "max_c": 10, "max_ramp_c_per_min": 1},
            "imus": [{"name": "a", "backend": "sim", "model": "ln200"}]})",
        f);
  fclose(f);
  const Result r = run("demo --station " + path);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("site.latitude_deg: 99 is greater than the maximum 90"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("table.outer: missing required property \"max_accel_dps2\""), std::string::npos) << r.out;
}

TEST(CliUnits, ConvertsAndRefusesMismatchedDimensions) {
  Result r = run("units \"0.15 deg/sqrt(h)\" --to \"deg/s/sqrt(Hz)\" --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NEAR(nlohmann::json::parse(r.out)["result"].get<double>(), 0.0025, 1e-15);
  r = run("units \"0.15 deg/sqrt(h)\" --to m/s");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.out.find("dimensions differ"), std::string::npos) << r.out;
}

TEST(CliTruthFromSpec, WritesATruthFileTheStationCanUse) {
  const std::string truth = ::testing::TempDir() + "adis_truth.json";
  Result r = run("truth-from-spec adis16488 --seed 3 --out " + truth);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const std::string station = ::testing::TempDir() + "station_with_truth.json";
  FILE* f = fopen(station.c_str(), "w");
  ASSERT_NE(f, nullptr);
  fprintf(f, R"({"format": "calstand-station/1", "name": "t",
               "site": {"latitude_deg": 45, "height_m": 0},
               "table": {"backend": "sim", "outer_axis": [0,1,0], "inner_axis": [0,0,1],
                         "outer": {"max_rate_dps": 100, "max_accel_dps2": 100},
                         "inner": {"max_rate_dps": 100, "max_accel_dps2": 100}},
               "chamber": {"backend": "sim", "min_c": -40, "max_c": 85, "max_ramp_c_per_min": 2},
               "imus": [{"name": "dut", "backend": "sim", "truth_file": "%s"}]})",
          truth.c_str());
  fclose(f);
  r = run("station --json --station " + station);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["derived"]["imus"][0]["truth"]["output"]["sample_rate_hz"].get<double>(), 2460.0);
  r = run("truth-from-spec no-such-imu");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.out.find("ln200"), std::string::npos) << r.out;
}

}  // namespace
