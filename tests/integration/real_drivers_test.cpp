// The real drivers end to end: `calstand sim-station` serves a simulated world behind the real
// protocols (table commands on TCP, the chamber as a Watlow F4T over Modbus TCP, IMU frames on a
// pseudo-terminal), and `calstand run` drives it through the acutrol, modbus and serial drivers
// with the station file sim-station wrote. The fits recover the simulator's truth as well as a
// run on the in-process simulator does; faults (Modbus gone, interlock open, IMU silent) take
// the station to its safe state with the reason recorded.
#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <future>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "cli_runner.hpp"
#include "sim_station_process.hpp"

namespace {

using calstand::testing::read_text;
using calstand::testing::run;
using calstand::testing::SimStationProcess;
using calstand::testing::write_text;
using nlohmann::json;

// World seconds per wall second of the protocol simulator. High enough for a short suite, low
// enough that the engine's 0.1 s ticks (5 ms of wall time) keep up on a busy 2-core machine.
constexpr const char* kTimeScale = "20";

constexpr const char* kTruthParameters = R"({
  "gyro_bias.x": 0.002, "gyro_bias.y": -0.001, "gyro_bias.z": 0.003,
  "gyro_scale.x": 300, "gyro_scale.y": -200, "gyro_scale.z": 150,
  "gyro_misalignment.xy": 0.0005, "gyro_misalignment.zx": -0.0003,
  "accel_bias.x": 0.01, "accel_bias.y": -0.02, "accel_bias.z": 0.005,
  "accel_scale.x": -400, "accel_scale.y": 250, "accel_scale.z": 100,
  "accel_misalignment.yx": 0.0004, "accel_misalignment.xz": -0.0002})";

double truth(const std::string& name) {
  return json::parse(kTruthParameters).value(name, 0.0);
}

class RealDrivers : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = ::testing::TempDir() + "calstand-real-drivers-" + std::to_string(::getpid()) + "/";
    std::filesystem::create_directories(dir_);
    sim_station_ = dir_ + "sim.json";
    write_text(sim_station_, std::string(R"({"format": "calstand-station/1", "name": "drivers-test", "seed": 5,
      "site": {"latitude_deg": 30.5, "height_m": 25},
      "table": {"backend": "sim", "outer_axis": [0, 1, 0], "inner_axis": [0, 0, 1],
                "outer": {"max_rate_dps": 400, "max_accel_dps2": 300},
                "inner": {"max_rate_dps": 1000, "max_accel_dps2": 500}},
      "chamber": {"backend": "sim", "min_c": -55, "max_c": 125, "max_ramp_c_per_min": 5},
      "imus": [{"name": "imu0", "backend": "sim", "truth": {"format": "calstand-truth/1",
        "parameters": )") + kTruthParameters + R"(,
        "noise": {"gyro": {"arw_deg_per_sqrt_h": 0.1}, "accel": {"vrw_mps_per_sqrt_h": 0.03}},
        "output": {"sample_rate_hz": 200}}}]})");
  }
  static void TearDownTestSuite() { std::filesystem::remove_all(dir_); }

  /// A sim-station serving the test station; its client station file is `lab`.
  static std::unique_ptr<SimStationProcess> serve(const std::string& lab) {
    return std::make_unique<SimStationProcess>(std::vector<std::string>{
        "--station", sim_station_, "--time-scale", kTimeScale, "--station-out", lab});
  }

  static json fit_json(const std::string& db, const std::string& args) {
    const auto r = run("fit --db " + db + " --run 1 " + args + " --json", dir_ + "stderr.txt");
    EXPECT_EQ(r.exit_code, 0) << read_text(dir_ + "stderr.txt");
    return json::parse(r.out);
  }

  static json show_json(const std::string& db) {
    const auto r = run("show --db " + db + " --run 1 --json", dir_ + "stderr.txt");
    EXPECT_EQ(r.exit_code, 0) << read_text(dir_ + "stderr.txt");
    return json::parse(r.out);
  }

  /// Runs `procedure` on the station file `station` into `db`; returns the exit code and output.
  static calstand::testing::Result run_procedure(const std::string& procedure,
                                                 const std::string& station,
                                                 const std::string& db) {
    return run("run " + procedure + " --station " + station + " --db " + db + " --quiet");
  }

  /// Both fits within `k` sigma of the truth, parameter by parameter; and the real drivers'
  /// fit as good as the in-process one: chi2/dof, and the RMS of the normalised errors (about 1
  /// for an honest fit; each run has its own noise, so they are compared loosely).
  static void expect_same_quality(const json& in_process, const json& real, double k) {
    ASSERT_EQ(in_process["parameters"].size(), real["parameters"].size());
    auto rms_z = [&](const json& fit, const char* which) {
      double sum = 0.0;
      for (const auto& p : fit["parameters"]) {
        const std::string name = p["name"];
        const double z = (p["value"].get<double>() - truth(name)) / p["sigma"].get<double>();
        EXPECT_LT(std::abs(z), k) << name << " (" << which << ")";
        sum += z * z;
      }
      return std::sqrt(sum / static_cast<double>(fit["parameters"].size()));
    };
    const double in_process_rms = rms_z(in_process, "in process");
    const double real_rms = rms_z(real, "real drivers");
    EXPECT_LT(real["chi2_dof"].get<double>(), 2.0 * in_process["chi2_dof"].get<double>() + 0.5)
        << "in process " << in_process["chi2_dof"] << ", real drivers " << real["chi2_dof"];
    EXPECT_LT(real_rms, std::max(2.0 * in_process_rms, 2.0))
        << "in process " << in_process_rms << ", real drivers " << real_rms;
  }

  static json table_state(const std::string& lab) {
    const auto r = run("device --station " + lab + " table get", dir_ + "stderr.txt");
    EXPECT_EQ(r.exit_code, 0) << read_text(dir_ + "stderr.txt");
    return json::parse(r.out);
  }

  static std::string events_text(const json& shown) {
    std::string text;
    for (const auto& e : shown["events"]) text += e.dump() + "\n";
    return text;
  }

  static inline std::string dir_, sim_station_;
};

TEST_F(RealDrivers, SixPositionRecoversTheAccelerometerAsWellAsInProcess) {
  const std::string procedure = "six-position --set capture_s=20";
  ASSERT_EQ(run_procedure(procedure, sim_station_, dir_ + "six-sim.db").exit_code, 0);
  const std::string lab = dir_ + "six-lab.json";
  auto station = serve(lab);
  const auto r = run_procedure(procedure, lab, dir_ + "six-real.db");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const std::string model = "--sensor accel --model accel_bias,accel_scale,accel_misalignment";
  expect_same_quality(fit_json(dir_ + "six-sim.db", model), fit_json(dir_ + "six-real.db", model),
                      4.0);
}

TEST_F(RealDrivers, RateLadderRecoversTheGyroAsWellAsInProcess) {
  const std::string procedure = "rate-ladder --set rates=[30,90] --set revolutions=2";
  ASSERT_EQ(run_procedure(procedure, sim_station_, dir_ + "ladder-sim.db").exit_code, 0);
  const std::string lab = dir_ + "ladder-lab.json";
  auto station = serve(lab);
  const auto r = run_procedure(procedure, lab, dir_ + "ladder-real.db");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const std::string model = "--sensor gyro --model gyro_bias,gyro_scale,gyro_misalignment,earth_rate";
  expect_same_quality(fit_json(dir_ + "ladder-sim.db", model),
                      fit_json(dir_ + "ladder-real.db", model), 4.0);
}

/// Starts `procedure` against a fresh sim-station, sends `fault` after `after_wall_s`, and
/// returns the run as `show --json` gives it, with the station still served for inspection.
struct FaultedRun {
  std::unique_ptr<SimStationProcess> station;
  std::string lab;
  calstand::testing::Result result;
  json shown;
};

FaultedRun run_with_fault(const std::string& name, const std::string& procedure,
                          const std::string& fault, double after_wall_s,
                          const std::function<std::unique_ptr<SimStationProcess>(const std::string&)>& serve,
                          const std::string& dir) {
  FaultedRun out;
  out.lab = dir + name + "-lab.json";
  out.station = serve(out.lab);
  const std::string db = dir + name + ".db";
  auto running = std::async(std::launch::async, [&] {
    return run("run " + procedure + " --station " + out.lab + " --db " + db + " --quiet");
  });
  std::this_thread::sleep_for(std::chrono::duration<double>(after_wall_s));
  const auto answer = out.station->command(fault);
  EXPECT_TRUE(answer.value("ok", false)) << answer.dump();
  out.result = running.get();
  const auto shown = run("show --db " + db + " --run 1 --json");
  out.shown = json::parse(shown.out);
  return out;
}

TEST_F(RealDrivers, ModbusControllerGoneMidRunAbortsToSafeStateWithTheReason) {
  auto f = run_with_fault("modbus-gone", "six-position --set capture_s=60", "modbus stop", 2.0,
                          &RealDrivers::serve, dir_);
  EXPECT_NE(f.result.exit_code, 0) << f.result.out;
  EXPECT_EQ(f.shown["status"], "aborted") << f.shown.dump(2);
  const std::string reason = f.shown.value("exit_reason", "");
  EXPECT_NE(reason.find("chamber"), std::string::npos) << reason;
  EXPECT_NE(events_text(f.shown).find("chamber"), std::string::npos) << events_text(f.shown);
  const auto t = table_state(f.lab);
  EXPECT_NEAR(t["outer"]["rate_dps"].get<double>(), 0.0, 1e-3);
  EXPECT_NEAR(t["inner"]["rate_dps"].get<double>(), 0.0, 1e-3);
}

TEST_F(RealDrivers, InterlockOpeningMidRunStopsTheTableAndSaysWhy) {
  auto f = run_with_fault("interlock", "rate-ladder --set rates=[30,90] --set revolutions=4",
                          "interlock open outer door opened", 2.0, &RealDrivers::serve, dir_);
  EXPECT_NE(f.result.exit_code, 0) << f.result.out;
  EXPECT_EQ(f.shown["status"], "aborted") << f.shown.dump(2);
  const std::string reason = f.shown.value("exit_reason", "");
  EXPECT_NE(reason.find("door opened"), std::string::npos) << reason;
  EXPECT_NE(events_text(f.shown).find("interlock"), std::string::npos) << events_text(f.shown);
  // Both axes brought to rest, the other one by the engine's safe state.
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  const auto t = table_state(f.lab);
  EXPECT_NEAR(t["outer"]["rate_dps"].get<double>(), 0.0, 1e-3) << t.dump();
  EXPECT_NEAR(t["inner"]["rate_dps"].get<double>(), 0.0, 1e-3) << t.dump();
  EXPECT_TRUE(t["outer"]["fault"].get<bool>()) << "the interlock stays open until closed";
}

TEST_F(RealDrivers, ImuStreamStoppingFailsTheCaptureAndRecordsWhy) {
  auto f = run_with_fault("imu-silent", "six-position --set capture_s=60", "imu silent imu0", 2.0,
                          &RealDrivers::serve, dir_);
  EXPECT_NE(f.result.exit_code, 0) << f.result.out;
  EXPECT_EQ(f.shown["status"], "failed") << f.shown.dump(2);
  const std::string reason = f.shown.value("exit_reason", "");
  EXPECT_NE(reason.find("imu0 stream stale"), std::string::npos) << reason;
  EXPECT_NE(events_text(f.shown).find("stream stale"), std::string::npos) << events_text(f.shown);
  const auto t = table_state(f.lab);
  EXPECT_EQ(t["outer"]["mode"], "rest") << t.dump();
}

}  // namespace
