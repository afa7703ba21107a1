// The calstand command as a user runs it: exit codes, error text and the demo's results.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "cli_runner.hpp"

namespace {

using calstand::testing::read_text;
using calstand::testing::Result;
using calstand::testing::run;
using calstand::testing::write_text;

// A station file whose table and IMU mount are given; everything else as a small lab.
std::string station_file(const std::string& name, const std::string& outer_axis,
                         const std::string& inner_axis, const std::string& mount_rpy_deg) {
  const std::string path = ::testing::TempDir() + name + ".json";
  write_text(path, R"({"format": "calstand-station/1", "name": ")" + name + R"(",
      "site": {"latitude_deg": 30.5, "height_m": 25},
      "table": {"backend": "sim", "outer_axis": )" +
                       outer_axis + R"(, "inner_axis": )" + inner_axis + R"(,
                "outer": {"max_rate_dps": 400, "max_accel_dps2": 300},
                "inner": {"max_rate_dps": 1000, "max_accel_dps2": 500}},
      "chamber": {"backend": "sim", "min_c": -55, "max_c": 125, "max_ramp_c_per_min": 5},
      "imus": [{"name": "imu0", "backend": "sim", "model": "ln200",
                "mount_rpy_deg": )" +
                       mount_rpy_deg + "}]}");
  return path;
}

// A per-axis noise figure of a truth file: one number for all axes or [x, y, z].
double per_axis(const nlohmann::json& noise, const char* key, int axis) {
  if (!noise.contains(key)) return 0.0;
  const auto& v = noise.at(key);
  return v.is_array() ? v[static_cast<std::size_t>(axis)].get<double>() : v.get<double>();
}

double parameter(const nlohmann::json& truth, const std::string& name) {
  return truth["parameters"].value(name, 0.0);
}

// How far the mean of accel axis `axis` over `capture_s` may lie from its ideal reading (+-g
// on the vertical axis, 0 elsewhere), derived from the IMU's truth file (calstand station
// --json) and the turn-on bias the demo reports: the deterministic errors at |f| = g (bias,
// scale, asymmetry, quadratic, misalignment, temperature terms at `temperature_c`) plus
// `noise_only` alone: 4 standard deviations of the capture's noise.
struct AccelTolerance {
  double errors;
  double noise;
};
AccelTolerance accel_tolerance(const nlohmann::json& truth, const nlohmann::json& demo, int axis,
                               bool vertical, double capture_s, double temperature_c) {
  constexpr double g0 = 9.80665;
  const double g = demo["site"]["gravity_mps2"].get<double>();
  const std::string a(1, static_cast<char>('x' + axis));
  const double dT = temperature_c - truth["temperature_ref_c"].get<double>();
  double errors = std::abs(parameter(truth, "accel_bias." + a) +
                           demo["imu"]["turn_on_accel_bias_mps2"][axis].get<double>());
  if (vertical) {
    errors += 1e-6 * g *
              (std::abs(parameter(truth, "accel_scale." + a)) +
               std::abs(parameter(truth, "accel_scale_asymmetry." + a)) +
               std::abs(parameter(truth, "accel_temp_scale." + a) * dT));
    errors += 1e-6 * g0 * std::abs(parameter(truth, "accel_quadratic." + a)) * (g / g0) * (g / g0);
  }
  double misalignment = 0.0;
  for (const char other : std::string("xyz")) {
    if (other != a[0])
      misalignment =
          std::max(misalignment, std::abs(parameter(truth, "accel_misalignment." + a + other)));
  }
  errors += g * misalignment;
  for (int k = 1; k <= 4; ++k) {
    errors += std::abs(parameter(truth, "accel_temp_bias." + a + std::to_string(k))) *
              std::pow(std::abs(dT), k);
  }
  const auto& n = truth["noise"]["accel"];
  const double ug = 1e-6 * g0;
  const double sd = per_axis(n, "vrw_mps_per_sqrt_h", axis) / 60.0 / std::sqrt(capture_s) +
                    per_axis(n, "gauss_markov_sigma_ug", axis) * ug +
                    per_axis(n, "bias_instability_coefficient_ug", axis) * ug;
  return {errors, 4.0 * sd};
}

// Runs the demo on `station_args` and checks every position: the named body axis reads +-g and
// the others 0 within the truth-derived tolerance, and the reading is the noise-free copy's
// within the noise alone. Returns the demo's JSON.
nlohmann::json check_demo_positions(const std::string& station_args) {
  const double capture_s = 5.0;
  const Result truth_run = run("station --json" + station_args);
  EXPECT_EQ(truth_run.exit_code, 0) << truth_run.out;
  const auto truth = nlohmann::json::parse(truth_run.out)["derived"]["imus"][0]["truth"];
  const Result r = run("demo --json --capture 5" + station_args);
  EXPECT_EQ(r.exit_code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  const double g = j["site"]["gravity_mps2"].get<double>();
  EXPECT_EQ(j["six_position"].size(), 6u);
  for (const auto& p : j["six_position"]) {
    const std::string label = p["position"];
    const int axis = label[0] - 'x';
    const double sign = label.find("up") != std::string::npos ? 1.0 : -1.0;
    for (int i = 0; i < 3; ++i) {
      const auto tol =
          accel_tolerance(truth, j, i, i == axis, capture_s, p["temperature_c"].get<double>());
      const double want = i == axis ? sign * g : 0.0;
      const double got = p["accel_mps2"][i].get<double>();
      EXPECT_LT(tol.noise, 5e-3) << label;  // the noise-free comparison is mg-tight
      EXPECT_NEAR(got, want, tol.errors + tol.noise) << label << " axis " << i;
      EXPECT_NEAR(got, p["noise_free_accel_mps2"][i].get<double>(), tol.noise)
          << label << " axis " << i;
    }
    EXPECT_EQ(p["samples"].get<int>(), 2000) << label;  // 5 s at 400 Hz
  }
  return j;
}

TEST(CliDemo, SixPositionsRateTestAndThermalStepOnTheSimulator) {
  const auto j = check_demo_positions("");
  // Two-position estimates agree with the noise-free IMU to the noise of 5 s captures.
  for (const auto& a : j["accel_two_position"]) {
    EXPECT_NEAR(a["bias_mps2"].get<double>(), a["noise_free_bias_mps2"].get<double>(), 2e-3);
    EXPECT_NEAR(a["scale_ppm"].get<double>(), a["noise_free_scale_ppm"].get<double>(), 100.0);
  }
  // CW/CCW over whole revolutions recovers the gyro scale error to a few ppm.
  const auto& rate = j["rate_test"];
  EXPECT_EQ(rate["axis"], "z");
  EXPECT_NEAR(rate["gyro_scale_ppm"].get<double>(), rate["true_gyro_scale_ppm"].get<double>(),
              10.0);
  EXPECT_NEAR(rate["gyro_bias_dph"].get<double>(), rate["true_gyro_bias_dph"].get<double>(), 2.0);
  // The IMU lags the air early on and ends above it by the self-heating.
  const auto& th = j["thermal_step"];
  EXPECT_LT(th[1]["imu_c"].get<double>(), th[1]["air_c"].get<double>() - 5.0);
  EXPECT_GT(th.back()["imu_c"].get<double>(), th.back()["air_c"].get<double>() + 2.0);
  EXPECT_GT(j["simulated_s"].get<double>(), 3600.0);
}

TEST(CliDemo, PositionsComeFromTheStationsTableAndMount) {
  // Outer axis East instead of North, and the IMU turned 90 deg on the platform: the default
  // table's angles would point the wrong axes up.
  const std::string path = station_file("east_table", "[1,0,0]", "[0,0,1]", "[0,0,90]");
  const auto j = check_demo_positions(" --station " + path);
  // With yaw 90, body x lies along North at zero: x up needs the outer axis (East) turned.
  for (const auto& p : j["six_position"]) {
    if (p["position"] == "x up") {
      EXPECT_NE(p["outer_deg"].get<double>(), 0.0);
    }
  }
  const auto& rate = j["rate_test"];
  EXPECT_EQ(rate["axis"], "z");  // the inner axis is along body z at the z-up position
  EXPECT_NEAR(rate["gyro_scale_ppm"].get<double>(), rate["true_gyro_scale_ppm"].get<double>(),
              10.0);
  EXPECT_NEAR(rate["gyro_bias_dph"].get<double>(), rate["true_gyro_bias_dph"].get<double>(), 2.0);
}

TEST(CliDemo, TableThatCannotPointAnAxisUpIsRefusedNamingIt) {
  // Outer axis vertical, inner axis East: body x (East at zero) stays horizontal whatever the
  // angles, so "x up" does not exist.
  const std::string path = station_file("flat_table", "[0,0,1]", "[1,0,0]", "[0,0,0]");
  const Result r = run("demo --capture 1 --station " + path);
  EXPECT_EQ(r.exit_code, 2) << r.out;  // refused by the plan, before any station time
  EXPECT_NE(r.out.find("steps[4].up: the table cannot point body axis +x up"), std::string::npos)
      << r.out;
}

TEST(CliDemo, CaptureMustBeWithinAnHour) {
  for (const char* bad : {"0", "-1", "3601", "nan"}) {
    const Result r = run(std::string("demo --capture ") + bad);
    EXPECT_EQ(r.exit_code, 2) << bad << ": " << r.out;
    EXPECT_NE(r.out.find("--capture"), std::string::npos) << r.out;
  }
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
  EXPECT_NE(r.out.find("site.latitude_deg: 99 is greater than the maximum 90"), std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("table.outer: missing required property \"max_accel_dps2\""),
            std::string::npos)
      << r.out;
}

TEST(CliUnits, ConvertsAndRefusesMismatchedDimensions) {
  Result r = run("units \"0.15 deg/sqrt(h)\" --to \"deg/s/sqrt(Hz)\" --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_NEAR(nlohmann::json::parse(r.out)["result"].get<double>(), 0.0025, 1e-15);
  r = run("units \"0.15 deg/sqrt(h)\" --to m/s");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.out.find("dimensions differ"), std::string::npos) << r.out;
}

TEST(CliUnits, SubnormalResultsPrintAsJson) {
  // std::stod threw out_of_range on subnormals such as this one (exit 1).
  const Result r = run("units \"1e-310 rad\" --json");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j["result"].get<double>(), 1e-310);
  EXPECT_EQ(j["to"], "rad");
}

// Keys of every row of `rows`, which must all have the same ones.
std::set<std::string> row_keys(const nlohmann::json& rows) {
  std::set<std::string> keys;
  for (const auto& [k, v] : rows.at(0).items()) keys.insert(k);
  for (const auto& row : rows) {
    std::set<std::string> these;
    for (const auto& [k, v] : row.items()) these.insert(k);
    EXPECT_EQ(these, keys);
  }
  return keys;
}

TEST(CliNoiseStudy, JsonHasTheIssuesStructureAndValuesNearTheory) {
  const std::string err = ::testing::TempDir() + "noise_study_stderr.txt";
  const Result r = run("noise-study --json --runs 20 --duration 100", err);
  ASSERT_EQ(r.exit_code, 0) << r.out << read_text(err);
  // Fewer than 100 runs: a warning on stderr, and stdout stays pure JSON.
  EXPECT_NE(read_text(err).find("warning: --runs 20"), std::string::npos) << read_text(err);
  const auto j = nlohmann::json::parse(r.out);
  std::set<std::string> top;
  for (const auto& [k, v] : j.items()) top.insert(k);
  EXPECT_EQ(top, (std::set<std::string>{"white", "random_walk", "gauss_markov"}));
  // The issue's keys, plus the documented extras: the analog-bandwidth figure beside the exact
  // theory, and each Gauss-Markov row's q and within-run sigma.
  EXPECT_EQ(row_keys(j["white"]),
            (std::set<std::string>{"cutoff_hz", "rms", "theory", "theory_analog"}));
  EXPECT_EQ(row_keys(j["random_walk"]), (std::set<std::string>{"t_s", "sigma", "theory"}));
  EXPECT_EQ(row_keys(j["gauss_markov"]),
            (std::set<std::string>{"tau_s", "sigma", "theory", "q", "within_run_sigma"}));

  // Values against theory within 4 standard errors of 20 runs of 100 s at 1 kHz.
  const double runs = 20, duration = 100, fs = 1000, n = runs * duration * fs;
  ASSERT_EQ(j["white"].size(), 4u);
  for (const auto& row : j["white"]) {
    const double fc = row["cutoff_hz"].get<double>();
    // Mean square of filtered white noise: relative sd sqrt(2 * 0.75 / (n beta)) for a
    // 2nd-order Butterworth passing beta = 1.11 fc / (fs/2) of the band (1 for the raw row);
    // the filters start at rest each run, a deficit of at most 1 / (ENBW duration).
    const double beta = std::min(1.0, 1.1107 * fc / (0.5 * fs));
    const double rel = 0.5 * std::sqrt(2.0 * 0.75 / (n * beta)) * 4.0 +
                       (beta < 1.0 ? 0.5 / (1.1107 * fc * duration) : 0.0);
    EXPECT_NEAR(row["rms"].get<double>() / row["theory"].get<double>(), 1.0, rel) << fc;
  }
  ASSERT_EQ(j["random_walk"].size(), 2u);  // 10 and 60 s fit in 100 s runs
  for (const auto& row : j["random_walk"]) {
    // Sample sd over 20 runs: relative sd 1 / sqrt(2 * 19).
    EXPECT_NEAR(row["sigma"].get<double>() / row["theory"].get<double>(), 1.0,
                4.0 / std::sqrt(2.0 * (runs - 1)))
        << row["t_s"];
  }
  ASSERT_EQ(j["gauss_markov"].size(), 4u);
  for (const auto& row : j["gauss_markov"]) {
    // Pooled RMS of 20 stationary runs: relative sd 0.5 sqrt(v / runs), v the relative variance
    // of one run's mean square (2 when tau >> duration).
    const double tp = 0.5 * row["tau_s"].get<double>();
    const double v =
        2.0 * (2.0 * tp / duration) * (1.0 - tp / duration * -std::expm1(-duration / tp));
    EXPECT_NEAR(row["sigma"].get<double>() / row["theory"].get<double>(), 1.0,
                4.0 * 0.5 * std::sqrt(v / runs))
        << row["tau_s"];
  }
}

TEST(CliNoiseStudy, BadOptionsAreExitCode2NamingTheOption) {
  Result r = run("noise-study --runs x");
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("--runs"), std::string::npos) << r.out;
  r = run("noise-study --runs 1000 --duration 3600");  // 3.6e6 run-seconds
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("--runs/--duration"), std::string::npos) << r.out;
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
  // No temporary is left beside the target, after success or after a failed write.
  for (const auto& entry : std::filesystem::directory_iterator(::testing::TempDir())) {
    EXPECT_EQ(entry.path().filename().string().find("adis_truth.json.tmp"), std::string::npos)
        << entry.path();
  }
  const std::string missing_dir = ::testing::TempDir() + "no_such_dir/truth.json";
  r = run("truth-from-spec ln200 --out " + missing_dir);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_FALSE(std::filesystem::exists(::testing::TempDir() + "no_such_dir"));
}

TEST(CliStation, ATruthTheSimulatorCannotRunIsNotCalledValid) {
  // The schema and the truth checks accept it, but the flicker model needs samples faster than
  // 1 s: building the simulated IMU fails, so the station is refused before "valid".
  const std::string path = ::testing::TempDir() + "slow_imu_station.json";
  write_text(path, R"({"format": "calstand-station/1", "name": "slow",
      "site": {"latitude_deg": 30.5, "height_m": 25},
      "table": {"backend": "sim", "outer_axis": [0,1,0], "inner_axis": [0,0,1],
                "outer": {"max_rate_dps": 400, "max_accel_dps2": 300},
                "inner": {"max_rate_dps": 1000, "max_accel_dps2": 500}},
      "chamber": {"backend": "sim", "min_c": -55, "max_c": 125, "max_ramp_c_per_min": 5},
      "imus": [{"name": "slow", "backend": "sim", "truth": {"format": "calstand-truth/1",
                "noise": {"gyro": {"bias_instability_coefficient_deg_per_h": 1}},
                "output": {"sample_rate_hz": 0.5}}}]})");
  const Result r = run("station --station " + path);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_EQ(r.out.find("valid"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("imus[0]"), std::string::npos) << r.out;
}

}  // namespace

namespace {

// A recorded simulator run goes out as calstand-import/1, comes back in, and goes out again
// byte for byte; a malformed folder is refused with its line and column and writes nothing.
TEST(CliImportExport, RecordedRunRoundTripsThroughTheImportFormat) {
  const std::string dir = ::testing::TempDir() + "cli_roundtrip_" + std::to_string(getpid());
  std::system(("rm -rf " + dir + " && mkdir -p " + dir).c_str());
  const std::string db1 = dir + "/recorded.db", db2 = dir + "/imported.db";
  Result r = run("run six-position --quiet --set capture_s=2 --db " + db1);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  r = run("export --db " + db1 + " --run 1 --out " + dir + "/first");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  r = run("import " + dir + "/first --json --db " + db2);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto imported = nlohmann::json::parse(r.out);
  EXPECT_EQ(imported["steps"].get<int>(), 6);  // the six captures
  EXPECT_NEAR(imported["samples"].get<double>(), 6 * 2 * 400.0, 6.0);
  r = run("export --db " + db2 + " --run " + std::to_string(imported["run"].get<int>()) +
          " --out " + dir + "/second");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  // A second import is a new run; --limit 1 lists only the newest.
  r = run("import " + dir + "/first --db " + db2);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  r = run("runs --json --limit 1 --db " + db2);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto newest = nlohmann::json::parse(r.out);
  ASSERT_EQ(newest.size(), 1u) << r.out;
  EXPECT_EQ(newest[0]["id"].get<int>(), imported["run"].get<int>() + 1);
  EXPECT_EQ(nlohmann::json::parse(run("runs --json --db " + db2).out).size(), 2u);
  r = run("runs --limit 0 --db " + db2);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("--limit"), std::string::npos) << r.out;
  const std::string first = read_text(dir + "/first/samples.csv");
  ASSERT_GT(first.size(), 1000u);
  EXPECT_EQ(first, read_text(dir + "/second/samples.csv"));

  // Break one number on one row: exit 2 naming the line and column, and no run written.
  std::string broken = first;
  const auto line3 = broken.find('\n', broken.find('\n', broken.find('\n') + 1) + 1) + 1;
  const auto comma = broken.find(',', broken.find(',', line3) + 1);
  broken.insert(comma + 1, "x");
  std::system(("mkdir -p " + dir + "/broken && cp " + dir + "/first/meta.json " + dir + "/broken/")
                  .c_str());
  write_text(dir + "/broken/samples.csv", broken);
  const std::string db3 = dir + "/refused.db";
  r = run("import " + dir + "/broken --db " + db3);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("samples.csv:4"), std::string::npos) << r.out;
  r = run("runs --json --db " + db3);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  EXPECT_TRUE(nlohmann::json::parse(r.out).empty()) << r.out;
}

// A command that only reads a database refuses a path that does not exist, naming it, and
// leaves no file behind: a typo in --db is not a new empty database, and a poll for a database
// another process is about to create must not race that process in creating it.
TEST(CliReadOnly, MissingDatabaseIsExitCode2AndNotCreated) {
  const std::string db =
      ::testing::TempDir() + "calstand-typo-" + std::to_string(::getpid()) + ".db";
  for (const std::string& args :
       {"runs --db " + db, "show --run 1 --db " + db, "fit --run 1 --db " + db,
        "export --run 1 --out x --db " + db, "allan --run 1 --channel gx --db " + db,
        "noise --run 1 --db " + db, "report --run 1 --out r.html --db " + db}) {
    const Result r = run(args);
    EXPECT_EQ(r.exit_code, 2) << args << ": " << r.out;
    EXPECT_NE(r.out.find("no such database file"), std::string::npos) << args << ": " << r.out;
    EXPECT_FALSE(std::filesystem::exists(db)) << args << " created " << db;
    std::filesystem::remove(db);
  }
}

}  // namespace
