// The loop of issue 5 through the command line, on data that went through `calstand export` and
// `calstand import`: a campaign on the demo station (whose IMU has three effects the classical
// model lacks), then diagnose -> add the suggested term -> again, until nothing is missing.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "cli_runner.hpp"

namespace {

using calstand::testing::read_text;
using calstand::testing::run;

std::string trim(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == ' ')) s.pop_back();
  return s;
}

TEST(DiagnoseCli, TheLoopFindsTheDemoImusEffectsOnImportedData) {
  const std::string dir =
      ::testing::TempDir() + "calstand-diagnose-cli-" + std::to_string(::getpid()) + "/";
  std::filesystem::create_directories(dir);
  const std::string recorded = dir + "recorded.db";
  auto r =
      run("run thermal-calibration --station " CALSTAND_SOURCE_DIR "/sim/stations/demo.json --db " +
          recorded +
          " --quiet --set 'temperatures=[-10,25,60]' --set soak_s=300 --set capture_s=20"
          " --set 'outer_angles=[0,90,180,270]' --set 'inner_angles=[0,90]'"
          " --set 'rates=[30,100,300]'");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  ASSERT_EQ(run("export --db " + recorded + " --run 1 --out " + dir + "export").exit_code, 0);
  const std::string db = dir + "imported.db";
  r = run("import " + dir + "export --db " + db);
  ASSERT_EQ(r.exit_code, 0) << r.out;

  std::string model =
      "gyro_bias,gyro_scale,gyro_misalignment,earth_rate,accel_bias,accel_scale,accel_misalignment";
  std::set<std::string> added;
  for (int round = 0; round < 6; ++round) {
    r = run("diagnose --db " + db + " --run 1 --model " + model, dir + "stderr.txt");
    ASSERT_EQ(r.exit_code, 0) << read_text(dir + "stderr.txt");
    const std::string next =
        trim(run("diagnose --db " + db + " --run 1 --model " + model + " --suggest").out);
    if (next.empty()) break;
    added.insert(next);
    model += "," + next;
  }
  EXPECT_EQ(added,
            (std::set<std::string>{"accel_temp_bias", "gyro_temp_bias", "gyro_g_sensitivity"}));
  const auto diagnosis = nlohmann::json::parse(
      run("diagnose --db " + db + " --run 1 --model " + model + " --json").out);
  EXPECT_LT(diagnosis["chi2_dof"].get<double>(), 1.3);
  EXPECT_TRUE(diagnosis["explained"].get<bool>());
  for (const char* key : {"candidates", "signals", "groups", "worst_steps"}) {
    EXPECT_TRUE(diagnosis.contains(key)) << key;
  }

  // The history shows the error falling as the effects were added.
  const auto history = nlohmann::json::parse(run("history --db " + db + " --run 1 --json").out);
  ASSERT_GE(history.size(), 4u);
  double previous = 1e300;
  for (const auto& h : history) {
    const double chi2 = h["chi2_dof"].get<double>();
    EXPECT_LE(chi2, previous * 1.0001) << h.dump();
    previous = chi2;
  }
  // The classical model is well above the noise floor (chi2/dof 2-4 against the demo IMU's
  // honest noise, with its wandering accelerometer bias, over some 450 degrees of freedom).
  EXPECT_GT(history.front()["chi2_dof"].get<double>(), 2.0);

  // The classical thermal calibration (per-plateau fits, then a line in temperature) finds the
  // demo IMU's accelerometer temperature drift (sim/stations/demo.json: x1 = 1e-4 m/s^2/degC).
  const auto thermal =
      nlohmann::json::parse(run("fit --db " + db + " --run 1 --per-plateau 1 --json").out);
  bool found = false;
  for (const auto& c : thermal["coefficients"]) {
    if (c["name"] == "accel_temp_bias.x1") {
      found = true;
      EXPECT_NEAR(c["value"].get<double>(), 1e-4, 4.0 * c["sigma"].get<double>());
    }
  }
  EXPECT_TRUE(found) << thermal.dump(2);
  std::filesystem::remove_all(dir);
}

}  // namespace
