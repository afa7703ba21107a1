// The real drivers end to end: `calstand sim-station` serves a simulated world behind the real
// protocols (table commands on TCP, the chamber as a Watlow F4T over Modbus TCP, IMU frames on a
// pseudo-terminal), and `calstand run` drives it through the acutrol, modbus and serial drivers
// with the station file sim-station wrote. The fits recover the simulator's truth as well as a
// run on the in-process simulator does; faults (Modbus gone, interlock open, IMU silent) take
// the station to its safe state with the reason recorded.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <future>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "cli_runner.hpp"
#include "fit_quality.hpp"
#include "known_imu_station.hpp"
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

class RealDrivers : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = ::testing::TempDir() + "calstand-real-drivers-" + std::to_string(::getpid()) + "/";
    std::filesystem::create_directories(dir_);
    sim_station_ = dir_ + "sim.json";
    write_text(sim_station_, calstand::testing::known_imu_station("drivers-test", 5));
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

  static void expect_same_quality(const json& in_process, const json& real, double k) {
    calstand::testing::expect_same_quality(in_process, real, k);
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
  const std::string model =
      "--sensor gyro --model gyro_bias,gyro_scale,gyro_misalignment,earth_rate";
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

/// Waits (up to 60 s) until the run in `db` is in its first capture or rate step, or `running`
/// (the `calstand run` process) has ended; says whether it is capturing (false when it ended or
/// the time ran out).
bool wait_until_capturing(const std::string& db,
                          const std::future<calstand::testing::Result>& running) {
  for (int i = 0; i < 600; ++i) {
    const auto r = run("show --db " + db + " --run 1 --json");
    if (r.exit_code == 0) {
      const auto shown = json::parse(r.out, nullptr, false);
      if (!shown.is_discarded()) {
        for (const auto& step : shown["steps"]) {
          const bool records = step["kind"] == "capture" || step["kind"] == "rate";
          if (records && step["status"] == "running") return true;
        }
      }
    }
    if (running.wait_for(std::chrono::milliseconds(100)) == std::future_status::ready) {
      return false;
    }
  }
  return false;
}

FaultedRun run_with_fault(
    const std::string& name, const std::string& procedure, const std::string& fault,
    double after_wall_s,
    const std::function<std::unique_ptr<SimStationProcess>(const std::string&)>& serve,
    const std::string& dir, const std::function<void(FaultedRun&)>& before = {},
    const std::function<void(FaultedRun&)>& after_fault = {}) {
  FaultedRun out;
  out.lab = dir + name + "-lab.json";
  out.station = serve(out.lab);
  if (before) before(out);
  const std::string db = dir + name + ".db";
  auto running = std::async(std::launch::async, [&] {
    return run("run " + procedure + " --station " + out.lab + " --db " + db + " --quiet");
  });
  // The fault strikes during the first capture, whatever the machine's load.
  if (!wait_until_capturing(db, running)) {
    if (running.wait_for(std::chrono::seconds(0)) == std::future_status::ready) {
      const auto r = running.get();
      ADD_FAILURE() << "the run ended before capturing; calstand run exited " << r.exit_code
                    << ":\n"
                    << r.out;
      out.result = r;
      return out;
    }
    // Still going after 60 s: the fault below ends it, rather than a 60 s capture per step.
    ADD_FAILURE() << "the run did not start capturing within 60 s";
  }
  std::this_thread::sleep_for(std::chrono::duration<double>(after_wall_s));
  const auto answer = out.station->command(fault);
  EXPECT_TRUE(answer.value("ok", false)) << answer.dump();
  if (after_fault) after_fault(out);
  out.result = running.get();
  const auto shown = run("show --db " + db + " --run 1 --json");
  out.shown = json::parse(shown.out, nullptr, false);
  if (out.shown.is_discarded()) {
    ADD_FAILURE() << "show after the run: " << shown.out << "\ncalstand run said:\n"
                  << out.result.out;
    out.shown = json::object();
  }
  return out;
}

TEST_F(RealDrivers, ModbusControllerGoneMidRunAbortsToSafeStateWithTheReason) {
  // The chamber is controlling at 30 degC when its controller vanishes mid-capture; it comes
  // back while the engine is still trying to put it in standby, which must then succeed.
  auto set_chamber = [&](FaultedRun& f) {
    const auto r = run("device --station " + f.lab + " chamber set 30 --ramp 5");
    ASSERT_EQ(r.exit_code, 0) << r.out;
  };
  auto controller_back = [](FaultedRun& f) {
    std::this_thread::sleep_for(std::chrono::seconds(2));
    EXPECT_TRUE(f.station->command("modbus start").value("ok", false));
  };
  auto f = run_with_fault("modbus-gone", "six-position --set capture_s=60", "modbus stop", 0.5,
                          &RealDrivers::serve, dir_, set_chamber, controller_back);
  EXPECT_NE(f.result.exit_code, 0) << f.result.out;
  EXPECT_EQ(f.shown["status"], "aborted") << f.shown.dump(2);
  const std::string reason = f.shown.value("exit_reason", "");
  EXPECT_NE(reason.find("chamber"), std::string::npos) << reason;
  EXPECT_EQ(reason.find("NOT safe"), std::string::npos) << reason;
  const std::string events = events_text(f.shown);
  EXPECT_NE(events.find("station safe"), std::string::npos) << events;
  const auto t = table_state(f.lab);
  EXPECT_NEAR(t["outer"]["rate_dps"].get<double>(), 0.0, 1e-3);
  EXPECT_NEAR(t["inner"]["rate_dps"].get<double>(), 0.0, 1e-3);
  const auto c = run("device --station " + f.lab + " chamber get", dir_ + "stderr.txt");
  ASSERT_EQ(c.exit_code, 0) << read_text(dir_ + "stderr.txt");
  EXPECT_EQ(json::parse(c.out)["mode"], "standby") << c.out;
}

TEST_F(RealDrivers, InterlockOpeningMidRunStopsTheTableAndSaysWhy) {
  auto f = run_with_fault("interlock", "rate-ladder --set rates=[30,90] --set revolutions=4",
                          "interlock open outer door opened", 0.5, &RealDrivers::serve, dir_);
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

  // The cause gone, the interlock stays latched: a manual move does not close it on its way.
  ASSERT_TRUE(f.station->command("interlock clear outer").value("ok", false));
  auto moved =
      run("device --station " + f.lab + " table move --outer 10 --inner 0", dir_ + "stderr.txt");
  EXPECT_NE(moved.exit_code, 0) << moved.out;
  const std::string refusal = read_text(dir_ + "stderr.txt");
  EXPECT_NE(refusal.find("interlock latched open (door opened)"), std::string::npos) << refusal;
  EXPECT_TRUE(table_state(f.lab)["outer"]["fault"].get<bool>());
  // Only the operator's explicit act closes it, and says who did.
  const auto closed =
      run("device --station " + f.lab + " table close-interlock --by alice", dir_ + "stderr.txt");
  ASSERT_EQ(closed.exit_code, 0) << read_text(dir_ + "stderr.txt");
  const auto record = json::parse(closed.out);
  EXPECT_EQ(record["by"], "alice");
  ASSERT_EQ(record["closed"].size(), 1u) << closed.out;
  EXPECT_EQ(record["closed"][0], "outer axis interlock (door opened)");
  EXPECT_FALSE(record["wall_utc"].get<std::string>().empty());
  moved =
      run("device --station " + f.lab + " table move --outer 10 --inner 0", dir_ + "stderr.txt");
  EXPECT_EQ(moved.exit_code, 0) << read_text(dir_ + "stderr.txt");
}

// The chamber's Modbus controller coming and going every few station seconds: each outage is
// recorded and ridden out (the controller keeps its setpoint by itself), the run completes.
TEST_F(RealDrivers, ModbusControllerFlappingIsRiddenOutAndRecorded) {
  const std::string lab = dir_ + "flap-lab.json";
  auto station = serve(lab);
  json lab_file = json::parse(read_text(lab));
  // Outages of a few station seconds each; the driver's reconnect backoff is in wall time, so
  // at this time scale an outage may stretch: the limit is generous on purpose here.
  lab_file["policy"]["link_outage_s"] = 600;
  write_text(lab, lab_file.dump(2));
  std::atomic<bool> done{false};
  int flaps = 0;
  // The flapping is in wall time, like the driver's reconnect: a sanitizer build connects
  // several times slower, so its up and down times (and the run that must see two outages)
  // stretch by the same factor.
  const auto half_period = calstand::testing::scaled(std::chrono::milliseconds(300));
  std::thread flapper([&] {
    bool down = false;
    while (!done) {
      std::this_thread::sleep_for(half_period);
      if (done) break;
      station->command(down ? "modbus start" : "modbus stop");
      down = !down;
      if (down) ++flaps;
    }
    if (down) station->command("modbus start");
  });
  const std::string db = dir_ + "flap.db";
  const auto r = run(
      "run six-position --set capture_s=" + std::to_string(4 * calstand::testing::kTestTimeFactor) +
          " --station " + lab + " --db " + db + " --quiet",
      dir_ + "stderr.txt");
  done = true;
  flapper.join();
  EXPECT_EQ(r.exit_code, 0) << r.out << read_text(dir_ + "stderr.txt");
  EXPECT_GE(flaps, 2) << "the run ended before the controller flapped";
  const auto shown = show_json(db);
  EXPECT_EQ(shown["status"], "completed") << shown.value("exit_reason", "");
  const std::string events = events_text(shown);
  EXPECT_NE(events.find("link lost"), std::string::npos) << events;
  EXPECT_NE(events.find("link back after"), std::string::npos) << events;
}

/// Sets the lab file's policy.link_outage_s [station s].
void set_link_outage(const std::string& lab, double seconds) {
  json lab_file = json::parse(read_text(lab));
  lab_file["policy"]["link_outage_s"] = seconds;
  write_text(lab, lab_file.dump(2));
}

/// The events of `source` in a run shown by `show --json`, one JSON line each.
std::string events_of(const json& shown, const std::string& source) {
  std::string text;
  for (const auto& e : shown["events"]) {
    if (e.value("source", "") == source) text += e.dump() + "\n";
  }
  return text;
}

// One rate step long enough (4 turns at 30 deg/s: 2.4 s of wall time at 20x) for the table's
// link to drop and come back while it turns.
constexpr const char* kLongRateStep =
    "rate-ladder --set rates=[30] --set 'axes=[\"inner\"]' --set revolutions=4";

// The table's TCP link drops mid-rate for less than the policy's link_outage_s: the controller
// keeps turning by itself, the engine rides the outage out, and the run completes saying that
// the link was lost and came back.
TEST_F(RealDrivers, TableLinkDroppedMidRateBrieflyIsRiddenOut) {
  auto generous_policy = [](FaultedRun& f) { set_link_outage(f.lab, 120.0); };
  auto restore = [](FaultedRun& f) {
    std::this_thread::sleep_for(std::chrono::seconds(1));  // 20 s of station time
    EXPECT_TRUE(f.station->command("table restore").value("ok", false));
  };
  auto f = run_with_fault("table-drop-short", kLongRateStep, "table drop", 0.3, &RealDrivers::serve,
                          dir_, generous_policy, restore);
  EXPECT_EQ(f.result.exit_code, 0) << f.result.out;
  EXPECT_EQ(f.shown["status"], "completed") << f.shown.value("exit_reason", "");
  const std::string table = events_of(f.shown, "table");
  EXPECT_NE(table.find("link lost"), std::string::npos) << events_text(f.shown);
  EXPECT_NE(table.find("link back after"), std::string::npos) << events_text(f.shown);
}

// Dropped for longer than link_outage_s: the run aborts naming the table's link, and the table
// is brought to rest once the link is back (the engine keeps trying its safe state meanwhile).
TEST_F(RealDrivers, TableLinkDroppedMidRateTooLongAbortsWithTheTableAtRest) {
  auto short_policy = [](FaultedRun& f) { set_link_outage(f.lab, 10.0); };  // 0.5 s of wall time
  auto restore = [](FaultedRun& f) {
    std::this_thread::sleep_for(std::chrono::seconds(3));  // 60 s of station time
    EXPECT_TRUE(f.station->command("table restore").value("ok", false));
  };
  auto f = run_with_fault("table-drop-long", kLongRateStep, "table drop", 0.3, &RealDrivers::serve,
                          dir_, short_policy, restore);
  EXPECT_NE(f.result.exit_code, 0) << f.result.out;
  EXPECT_EQ(f.shown["status"], "aborted") << f.shown.dump(2);
  const std::string reason = f.shown.value("exit_reason", "");
  EXPECT_NE(reason.find("table link down for"), std::string::npos) << reason;
  EXPECT_EQ(reason.find("NOT safe"), std::string::npos) << reason;
  EXPECT_NE(events_of(f.shown, "table").find("link lost"), std::string::npos)
      << events_text(f.shown);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // 6 s of world time to brake
  const auto t = table_state(f.lab);
  EXPECT_FALSE(t.value("link_lost", true)) << t.dump();
  EXPECT_NEAR(t["outer"]["rate_dps"].get<double>(), 0.0, 1e-3) << t.dump();
  EXPECT_NEAR(t["inner"]["rate_dps"].get<double>(), 0.0, 1e-3) << t.dump();
}

// An IMU that delivers a burst (frames held back, then all at once), garbage on the line and a
// jump of its own clock, all during captures: each is recorded and ridden out, the run ends
// completed with whole captures (policy on_sequence_gap: record).
TEST_F(RealDrivers, ImuBurstsGarbageAndAClockJumpAreRiddenOut) {
  const std::string lab = dir_ + "imu-faults-lab.json";
  auto station = serve(lab);
  const std::string db = dir_ + "imu-faults.db";
  auto running = std::async(std::launch::async, [&] {
    return run("run six-position --set capture_s=8 --station " + lab + " --db " + db + " --quiet");
  });
  ASSERT_TRUE(wait_until_capturing(db, running));
  // Held 20 ms of wall time (0.4 s of station time, less than the 1 s that makes a stream
  // stale), then delivered at once.
  ASSERT_TRUE(station->command("imu hold imu0").value("ok", false));
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  ASSERT_TRUE(station->command("imu release imu0").value("ok", false));
  ASSERT_TRUE(station->command("imu garbage imu0 300").value("ok", false));
  ASSERT_TRUE(station->command("imu clock-jump imu0 1000").value("ok", false));
  const auto r = running.get();
  EXPECT_EQ(r.exit_code, 0) << r.out;
  const auto shown = show_json(db);
  EXPECT_EQ(shown["status"], "completed") << shown.value("exit_reason", "");
  const std::string events = events_text(shown);
  EXPECT_NE(events.find("device clock jumped"), std::string::npos) << events;
  EXPECT_NE(events.find("frame errors"), std::string::npos) << events;
  for (const auto& step : shown["steps"]) {
    if (step["kind"] != "capture") continue;
    EXPECT_EQ(step["status"], "completed") << step.dump();
  }
}

TEST_F(RealDrivers, ImuStreamStoppingFailsTheCaptureAndRecordsWhy) {
  auto f = run_with_fault("imu-silent", "six-position --set capture_s=60", "imu silent imu0", 0.5,
                          &RealDrivers::serve, dir_);
  EXPECT_NE(f.result.exit_code, 0) << f.result.out;
  EXPECT_EQ(f.shown["status"], "failed") << f.shown.dump(2);
  const std::string reason = f.shown.value("exit_reason", "");
  EXPECT_NE(reason.find("imu0 stream stale"), std::string::npos) << reason;
  EXPECT_NE(events_text(f.shown).find("stream stale"), std::string::npos) << events_text(f.shown);
  const auto t = table_state(f.lab);
  EXPECT_EQ(t["outer"]["mode"], "rest") << t.dump();
}

TEST_F(RealDrivers, DeviceCommandsDriveTheStationByHand) {
  const std::string lab = dir_ + "device-lab.json";
  auto station = serve(lab);
  const std::string device = "device --station " + lab + " ";
  auto json_of = [&](const std::string& args) {
    const auto r = run(device + args, dir_ + "stderr.txt");
    EXPECT_EQ(r.exit_code, 0) << args << ": " << read_text(dir_ + "stderr.txt");
    return json::parse(r.out);
  };

  const auto status = json_of("status");
  ASSERT_EQ(status["devices"].size(), 3u) << status.dump(2);
  for (const auto& d : status["devices"]) EXPECT_EQ(d["configure"], "ok") << d.dump();

  const auto moved = json_of("table move --outer 90 --inner -45");
  EXPECT_NEAR(moved["outer"]["angle_deg"].get<double>(), 90.0, 1e-3) << moved.dump();
  EXPECT_NEAR(moved["inner"]["angle_deg"].get<double>(), -45.0, 1e-3) << moved.dump();
  EXPECT_TRUE(moved["outer"]["in_position"].get<bool>());

  const auto turning = json_of("table rate --axis inner --dps 20");
  EXPECT_NEAR(turning["inner"]["rate_dps"].get<double>(), 20.0, 0.01) << turning.dump();
  json_of("table stop");
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // 6 s of world time to brake
  const auto stopped = json_of("table get");
  EXPECT_NEAR(stopped["inner"]["rate_dps"].get<double>(), 0.0, 1e-3) << stopped.dump();

  const auto set = json_of("chamber set 30 --ramp 5");  // stays while the driver steps
  EXPECT_NEAR(set["setpoint_c"].get<double>(), 30.0, 0.05) << set.dump();
  EXPECT_EQ(set["mode"], "active") << set.dump();
  const auto standby = json_of("chamber standby");
  EXPECT_EQ(standby["mode"], "standby") << standby.dump();

  const auto r = run(device + "imu stream --count 50", dir_ + "stderr.txt");
  ASSERT_EQ(r.exit_code, 0) << read_text(dir_ + "stderr.txt");
  std::istringstream lines(r.out);
  std::string line;
  std::vector<json> samples;
  while (std::getline(lines, line)) samples.push_back(json::parse(line));
  ASSERT_EQ(samples.size(), 50u);
  for (std::size_t i = 1; i < samples.size(); ++i) {
    EXPECT_EQ(samples[i]["sequence"].get<int>(),
              (samples[i - 1]["sequence"].get<int>() + 1) % 65536);
    EXPECT_NEAR(samples[i]["accel_mps2"][2].get<double>(),
                samples[0]["accel_mps2"][2].get<double>(), 0.5);
  }

  // Mistakes are refused with where and why.
  const auto unknown = run(device + "imu stream --imu nope --count 1");
  EXPECT_EQ(unknown.exit_code, 2) << unknown.out;
  EXPECT_NE(unknown.out.find("no IMU \"nope\""), std::string::npos) << unknown.out;
  const auto simulated = run("device --station " + sim_station_ + " table get");
  EXPECT_EQ(simulated.exit_code, 2) << simulated.out;
  EXPECT_NE(simulated.out.find("simulated in process"), std::string::npos) << simulated.out;
  const auto bad = station->command("levitate table");
  EXPECT_FALSE(bad.value("ok", true));
  EXPECT_NE(bad.value("error", "").find("not understood"), std::string::npos) << bad.dump();
}

// `calstand device` rides out a dropped link as a run does: a read that finds the table's or the
// chamber's link down waits for it (reconnecting with backoff) and answers once it is back;
// down for longer than the policy's link_outage_s, it fails naming the device and how long.
TEST_F(RealDrivers, DeviceCommandsRideOutADroppedLink) {
  const std::string lab = dir_ + "device-ride-lab.json";
  auto station = serve(lab);
  set_link_outage(lab, 200.0);  // 10 s of wall time at 20x: far more than the outages below
  const std::string device = "device --station " + lab + " ";
  // Starts `args` with the link already down, brings the link back after a second of wall
  // time, and returns the command's JSON.
  auto across_outage = [&](const std::string& args, const std::string& down,
                           const std::string& up) {
    EXPECT_TRUE(station->command(down).value("ok", false)) << down;
    auto waiting = std::async(std::launch::async,
                              [&] { return run(device + args, dir_ + "ride-stderr.txt"); });
    std::this_thread::sleep_for(std::chrono::seconds(1));
    EXPECT_EQ(waiting.wait_for(std::chrono::seconds(0)), std::future_status::timeout)
        << args << " did not wait for the link";
    EXPECT_TRUE(station->command(up).value("ok", false)) << up;
    const auto r = waiting.get();
    EXPECT_EQ(r.exit_code, 0) << args << ": " << read_text(dir_ + "ride-stderr.txt");
    return json::parse(r.out, nullptr, false);
  };

  const auto table = across_outage("table get", "table drop", "table restore");
  EXPECT_FALSE(table.value("link_lost", true)) << table.dump();
  EXPECT_FALSE(table["outer"].value("fault", true)) << table.dump();
  const auto moved =
      across_outage("table move --outer 30 --inner 0", "table drop", "table restore");
  EXPECT_NEAR(moved["outer"]["angle_deg"].get<double>(), 30.0, 1e-3) << moved.dump();
  const auto chamber = across_outage("chamber get", "modbus stop", "modbus start");
  EXPECT_FALSE(chamber.value("link_lost", true)) << chamber.dump();
  EXPECT_FALSE(chamber.value("fault", true)) << chamber.dump();

  // Down for longer than the policy allows: the error says which device and for how long.
  set_link_outage(lab, 10.0);  // 0.5 s of wall time
  ASSERT_TRUE(station->command("table drop").value("ok", false));
  const auto gone = run(device + "table get", dir_ + "ride-stderr.txt");
  EXPECT_NE(gone.exit_code, 0) << gone.out;
  const std::string why = read_text(dir_ + "ride-stderr.txt");
  EXPECT_NE(why.find("table link down for"), std::string::npos) << why;
  EXPECT_NE(why.find("more than the policy's 10 s"), std::string::npos) << why;
  ASSERT_TRUE(station->command("table restore").value("ok", false));
}

// sim-station serves the chamber in the map --chamber-protocol names (CSZ EZT-570 here): the
// endpoints and the station file follow it, and the real Modbus driver sets, reads and stands
// the chamber by through it. An unknown name is refused with the names it knows.
TEST_F(RealDrivers, SimStationServesTheChamberInTheChosenMap) {
  const std::string lab = dir_ + "csz-lab.json";
  SimStationProcess station({"--station", sim_station_, "--time-scale", kTimeScale, "--station-out",
                             lab, "--chamber-protocol", "csz-ezt570"});
  EXPECT_EQ(station.endpoints()["chamber"]["map"], "csz-ezt570") << station.endpoints().dump();
  EXPECT_EQ(station.endpoints()["table"]["protocol"], "acutrol");
  EXPECT_EQ(json::parse(read_text(lab))["chamber"]["connection"]["map"], "csz-ezt570");
  const std::string device = "device --station " + lab + " ";
  auto json_of = [&](const std::string& args) {
    const auto r = run(device + args, dir_ + "stderr.txt");
    EXPECT_EQ(r.exit_code, 0) << args << ": " << read_text(dir_ + "stderr.txt");
    return json::parse(r.out, nullptr, false);
  };
  const auto set = json_of("chamber set 30 --ramp 5");
  EXPECT_NEAR(set["setpoint_c"].get<double>(), 30.0, 0.05) << set.dump();
  EXPECT_EQ(set["mode"], "active") << set.dump();
  EXPECT_EQ(json_of("chamber standby")["mode"], "standby");
  // A run through the map: a setpoint, a soak, a capture, the chamber to standby at its end.
  const std::string procedure = dir_ + "csz-plateau.json";
  write_text(procedure, R"({"format": "calstand-procedure/1", "name": "csz-plateau",
    "description": "one plateau near the lab's air, through the chamber's register map",
    "steps": [
      {"kind": "set_temperature", "target_c": 26, "ramp_c_per_min": 5, "label": "to 26 degC",
       "soak": {"tolerance_c": 3, "stable_s": 1, "timeout_s": 600}},
      {"kind": "capture", "duration_s": 2, "label": "at 26 degC"}]})");
  const std::string db = dir_ + "csz.db";
  const auto r = run_procedure(procedure, lab, db);
  EXPECT_EQ(r.exit_code, 0) << r.out << read_text(dir_ + "stderr.txt");
  EXPECT_EQ(show_json(db).value("status", ""), "completed");
  EXPECT_EQ(json_of("chamber get")["mode"], "standby");

  const auto refused =
      run("sim-station --chamber-protocol nosuch --duration 1", dir_ + "stderr.txt");
  EXPECT_NE(refused.exit_code, 0);
  const std::string why = refused.out + read_text(dir_ + "stderr.txt");
  EXPECT_NE(why.find("--chamber-protocol"), std::string::npos) << why;
  EXPECT_NE(why.find("csz-ezt570"), std::string::npos) << why;
  const auto no_table =
      run("sim-station --table-protocol nosuch --duration 1", dir_ + "stderr.txt");
  EXPECT_NE(no_table.exit_code, 0);
  // The refusal lists what is served: the ACUTROL-style server and the table command sets.
  EXPECT_NE(read_text(dir_ + "stderr.txt").find("acutrol, "), std::string::npos);
  EXPECT_NE(read_text(dir_ + "stderr.txt").find("aerotech"), std::string::npos);
}

}  // namespace

namespace {

// Power cycles through a bench supply speaking SCPI: sim-station serves the station's supply on
// TCP, the lab file points the real SCPI driver at it, and the repeatability procedure switches
// the unit off and on; every power-up draws a new turn-on bias, so the cycles' means differ by
// far more than the noise of one mean.
TEST_F(RealDrivers, PowerCyclesThroughTheScpiSupplyGiveANewTurnOnBiasEachTime) {
  json sim = json::parse(read_text(sim_station_));
  // The known IMU has a fixed bias; an LN200-class unit drawn from its sheet has a turn-on bias
  // (500 ug, 1 sigma) drawn anew at every power-up.
  for (const char* key : {"truth", "truth_file", "spec_file"}) sim["imus"][0].erase(key);
  sim["imus"][0]["model"] = "ln200";
  sim["power_supplies"] = {{{"name", "psu0"},
                            {"backend", "sim"},
                            {"imu", sim["imus"][0]["name"]},
                            {"voltage_v", 28.0},
                            {"current_limit_a", 1.5},
                            {"safe_state", "on"}}};
  const std::string sim_file = dir_ + "psu-sim.json";
  write_text(sim_file, sim.dump());
  const std::string lab = dir_ + "psu-lab.json";
  auto station = std::make_unique<SimStationProcess>(std::vector<std::string>{
      "--station", sim_file, "--time-scale", kTimeScale, "--station-out", lab});
  const json lab_doc = json::parse(read_text(lab));
  ASSERT_EQ(lab_doc["power_supplies"].size(), 1u) << lab_doc.dump();
  EXPECT_EQ(lab_doc["power_supplies"][0]["backend"], "scpi");
  const std::string db = dir_ + "psu-real.db";
  const auto r =
      run("run repeatability --set cycles=3 --set off_s=2 --set settle_s=5 --set rates=[200] "
          "--set revolutions=1 "
          "--set capture_s=20 --quiet --station " +
          lab + " --db " + db);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const auto a = run("analyze repeatability --json --db " + db + " --run 1", dir_ + "stderr.txt");
  ASSERT_EQ(a.exit_code, 0) << read_text(dir_ + "stderr.txt");
  const json rep = json::parse(a.out);
  EXPECT_EQ(rep["cycles"], 3);
  for (int axis = 0; axis < 3; ++axis) {
    EXPECT_GT(rep["accel"]["spread_ug"][axis].get<double>(),
              3.0 * rep["accel"]["noise_of_means_ug"][axis].get<double>())
        << "axis " << axis << ": " << rep["accel"].dump();
    // The turns through the ACUTROL driver give each cycle's gyro scale about every body axis.
    EXPECT_EQ(rep["gyro"]["scale_rates_dps"][axis], json::array({200.0})) << rep["gyro"].dump();
    EXPECT_EQ(rep["gyro"]["scale_per_cycle_ppm"][axis].size(), 3u);
  }
}

}  // namespace

namespace {

/// A real unit's wire format on sim-station's IMU line, and a rate that unit makes.
struct ImuFormatCase {
  const char* format;
  int rate_hz;
};

/// The case by its format in ctest's test names (not the struct's bytes).
void PrintTo(const ImuFormatCase& c, std::ostream* os) {
  *os << c.format << " at " << c.rate_hz << " Hz";
}

class RealImuFormats : public RealDrivers, public ::testing::WithParamInterface<ImuFormatCase> {
 protected:
  static std::vector<json> stream(const std::string& lab, int count) {
    const auto r = run("device --station " + lab + " imu stream --count " + std::to_string(count));
    EXPECT_EQ(r.exit_code, 0) << r.out;
    std::vector<json> out;
    std::istringstream lines(r.out);
    for (std::string line; std::getline(lines, line);) {
      auto j = json::parse(line, nullptr, false);
      if (j.is_object()) out.push_back(std::move(j));
    }
    return out;
  }

  /// `device imu stream` through the unit's protocol gives the simulator's samples: two
  /// sim-stations of the same station file (the same world, sample for sample) serve it, one
  /// in calstand frames (f32, the simulator's values) and one as the unit; the unit's stream is
  /// found in the calstand stream by its values and must equal it sample after sample, to the
  /// format's resolution. Real time (x1), so that both streams overlap.
  static void expect_stream_equals_calstand_frames(const std::string& sim, const char* format) {
    const std::string frames_lab = dir_ + format + "-frames-x1.json";
    const std::string unit_lab = dir_ + format + "-unit-x1.json";
    SimStationProcess frames({"--station", sim, "--station-out", frames_lab});
    SimStationProcess unit({"--station", sim, "--station-out", unit_lab, "--imu-format", format});
    auto reference = std::async(std::launch::async, [&] { return stream(frames_lab, 600); });
    const std::vector<json> got = stream(unit_lab, 600);
    const std::vector<json> want = reference.get();
    ASSERT_EQ(got.size(), 600u);
    ASSERT_EQ(want.size(), 600u);
    auto same = [](const json& a, const json& b) {
      for (int i = 0; i < 3; ++i) {
        if (std::abs(a["gyro_dps"][i].get<double>() - b["gyro_dps"][i].get<double>()) > 1e-3 ||
            std::abs(a["accel_mps2"][i].get<double>() - b["accel_mps2"][i].get<double>()) > 1e-4) {
          return false;
        }
      }
      return std::abs(a["temperature_c"].get<double>() - b["temperature_c"].get<double>()) < 0.02;
    };
    // Whichever stream started later begins inside the other.
    std::size_t in_want = 0, in_got = 0;
    while (in_want < want.size() && !same(want[in_want], got[0])) ++in_want;
    if (in_want == want.size()) {
      in_want = 0;
      while (in_got < got.size() && !same(want[0], got[in_got])) ++in_got;
    }
    const std::size_t overlap = std::min(want.size() - in_want, got.size() - in_got);
    ASSERT_GE(overlap, 100u) << "the two streams of the same world do not overlap: the unit's "
                                "samples are not the simulator's";
    for (std::size_t k = 0; k < overlap; ++k) {
      EXPECT_TRUE(same(want[in_want + k], got[in_got + k]))
          << format << " sample " << k << ": " << got[in_got + k].dump() << " vs "
          << want[in_want + k].dump();
    }
  }
};

// A whole campaign (the thermal calibration at one plateau, shortened) through each real unit's
// protocol: sim-station answers the driver's configuration dialogue as the unit does and streams
// its frames; the fits are as good as the in-process simulator's, the unit's identity as read
// over the wire is the run's, and the reader's start is no fault.
TEST_P(RealImuFormats, ACampaignThroughTheUnitsProtocolFitsAsWellAsInProcess) {
  const ImuFormatCase c = GetParam();
  const std::string name = std::string("format-") + c.format;
  const std::string sim = dir_ + name + "-sim.json";
  write_text(sim, calstand::testing::known_imu_station(name, 7, c.rate_hz));
  const std::string procedure =
      "thermal-calibration --set temperatures=[25] --set soak_s=5 --set final_soak_s=5 "
      "--set capture_s=10 --set ramp_c_per_min=5 --set outer_angles=[0,90,180,270] "
      "--set inner_angles=[0,90] --set rates=[30,90] --set revolutions=1";
  ASSERT_EQ(run_procedure(procedure, sim, dir_ + name + "-inproc.db").exit_code, 0);
  // The accelerometers from their own procedure: in the campaign's turns about a horizontal
  // axis the table's telemetry and the IMU's stamps still disagree by a fraction of a
  // millisecond of wall time, which at 20x moves the gravity a turn's window sees by ~1e-4
  // m/s^2, about a step mean's white noise (accel chi2/dof 1.5 to 2.3 against 0.96 in process).
  const std::string six = "six-position --set capture_s=10";
  ASSERT_EQ(run_procedure(six, sim, dir_ + name + "-six-inproc.db").exit_code, 0);

  const std::string lab = dir_ + name + "-lab.json";
  SimStationProcess station({"--station", sim, "--time-scale", kTimeScale, "--station-out", lab,
                             "--imu-format", c.format});
  EXPECT_EQ(station.endpoints()["imus"][0]["format"], c.format);
  const auto info = run("device --station " + lab + " imu info", dir_ + "stderr.txt");
  ASSERT_EQ(info.exit_code, 0) << read_text(dir_ + "stderr.txt");
  const json identity = json::parse(info.out);
  // sim-station's unit without a serial in its station entry: 29000001 (the first IMU).
  EXPECT_EQ(identity["serial"], "29000001") << info.out;

  expect_stream_equals_calstand_frames(sim, c.format);

  const std::string db = dir_ + name + "-real.db";
  const auto r = run_procedure(procedure, lab, db);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const std::string gyro =
      "--sensor gyro --model gyro_bias,gyro_scale,gyro_misalignment,earth_rate";
  const std::string accel = "--sensor accel --model accel_bias,accel_scale,accel_misalignment";
  expect_same_quality(fit_json(dir_ + name + "-inproc.db", gyro), fit_json(db, gyro), 4.0);
  const std::string six_db = dir_ + name + "-six-real.db";
  ASSERT_EQ(run_procedure(six, lab, six_db).exit_code, 0);
  expect_same_quality(fit_json(dir_ + name + "-six-inproc.db", accel), fit_json(six_db, accel),
                      4.0);

  const std::string events = events_text(show_json(db));
  EXPECT_NE(events.find("unit " + identity["serial"].get<std::string>()), std::string::npos)
      << events;
  // The reader's start and its stream are clean. A busy test machine can stall the reader for a
  // wall second (20 s of world time here): the emulator's write then times out and a cut frame
  // follows, as on a real line, and the reader says so after the stream stale it reports first.
  // Frame errors without such a cut before them are the reader's fault.
  const auto frame_errors = events.find("frame errors");
  if (frame_errors != std::string::npos) {
    EXPECT_NE(events.rfind("stream stale", frame_errors), std::string::npos) << events;
  }
}

INSTANTIATE_TEST_SUITE_P(Formats, RealImuFormats,
                         ::testing::Values(ImuFormatCase{"xsens", 200},
                                           ImuFormatCase{"vectornav", 200},
                                           ImuFormatCase{"epson", 200},
                                           ImuFormatCase{"stim300", 250}),
                         [](const auto& test_info) { return std::string(test_info.param.format); });

}  // namespace
