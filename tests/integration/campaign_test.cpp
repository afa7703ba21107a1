// Whole campaigns through the `calstand` command on the embedded simulator, as a lab engineer
// runs them: an uninterrupted run, and runs killed with SIGKILL at several points and resumed.
#include <gtest/gtest.h>
#include <signal.h>
#include <sqlite3.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>

#include "sim/sim_world.hpp"
#include "store/database.hpp"
#include "store/run_store.hpp"
#include "store/sample_reader.hpp"

namespace {

namespace fs = std::filesystem;

// A reduced thermal calibration: two plateaus, six orientations, two rates, short captures.
const char* kSetArgs =
    " --set 'temperatures=[15,35]' --set soak_s=600 --set capture_s=4"
    " --set 'outer_angles=[0,90,180]' --set 'inner_angles=[0,90]' --set 'rates=[20,90]'"
    " --set revolutions=1 --set ramp_c_per_min=2";

// ctest runs every test in its own process, two at a time: each process has its own files.
std::string db_path(const std::string& name) {
  const auto p = fs::path(::testing::TempDir()) / (std::to_string(getpid()) + "_" + name);
  fs::remove(p);
  fs::remove(p.string() + "-wal");
  fs::remove(p.string() + "-shm");
  return p.string();
}

// `calstand ARGS` with `env` (NAME=VALUE ...) before it; its exit code and, in `out`, what
// it printed.
int run_command(const std::string& args, std::string* out = nullptr, const std::string& env = "") {
  const std::string command = env + std::string(CALSTAND_BIN) + " " + args + " 2>&1";
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return -1;
  std::string text;
  std::array<char, 4096> buf{};
  while (std::size_t n = fread(buf.data(), 1, buf.size(), pipe)) text.append(buf.data(), n);
  const int status = pclose(pipe);
  if (out) *out = text;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// Completed steps of run 1, read by a separate read-only connection while the run goes on.
int completed_steps(const std::string& db) {
  sqlite3* h = nullptr;
  if (sqlite3_open_v2(db.c_str(), &h, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
    sqlite3_close(h);
    return -1;
  }
  sqlite3_busy_timeout(h, 1000);
  sqlite3_stmt* st = nullptr;
  int n = -1;
  if (sqlite3_prepare_v2(h, "SELECT count(*) FROM steps WHERE run_id = 1 AND status = 'completed'",
                         -1, &st, nullptr) == SQLITE_OK &&
      sqlite3_step(st) == SQLITE_ROW) {
    n = sqlite3_column_int(st, 0);
  }
  sqlite3_finalize(st);
  sqlite3_close(h);
  return n;
}

// Starts a run in a child process and SIGKILLs it once `kill_after` steps are completed.
// Returns false when the run finished before the kill.
bool run_and_kill(const std::string& db, int kill_after) {
  const pid_t pid = fork();
  if (pid == 0) {
    const std::string cmd = std::string(CALSTAND_BIN) + " run thermal-calibration --quiet --db " +
                            db + kSetArgs + " > /dev/null 2>&1";
    execl("/bin/sh", "sh", "-c", ("exec " + cmd).c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(3);
  while (std::chrono::steady_clock::now() < deadline) {
    int status = 0;
    if (waitpid(pid, &status, WNOHANG) == pid) return false;  // finished on its own
    if (completed_steps(db) >= kill_after) {
      kill(pid, SIGKILL);
      waitpid(pid, &status, 0);
      return true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  kill(pid, SIGKILL);
  waitpid(pid, nullptr, 0);
  return false;
}

struct StepData {
  std::string kind, label, status;
  std::size_t samples = 0;
};

// Every step of run 1 with its status and stored sample count; checks each recording step's
// samples are contiguous (no duplicate or missing sequence numbers, times increasing).
std::vector<StepData> check_run(const std::string& db_file) {
  calstand::store::Database db(db_file);
  calstand::store::RunStore runs(db);
  const auto run = runs.load_run(1);
  std::vector<StepData> out;
  for (const auto& s : run.steps) {
    StepData d{s.kind, s.label, std::string(calstand::store::to_string(s.status)), 0};
    const auto samples = calstand::store::read_samples(db, 1, s.index, "imu0");
    d.samples = samples.size();
    for (std::size_t k = 1; k < samples.size(); ++k) {
      EXPECT_EQ(samples[k].sequence, (samples[k - 1].sequence + 1) % 65536)
          << "step " << s.index << " sample " << k;
      EXPECT_GT(samples[k].receive_time_s, samples[k - 1].receive_time_s) << "step " << s.index;
      if (::testing::Test::HasFailure()) return out;
    }
    out.push_back(d);
  }
  sqlite3* h = nullptr;
  sqlite3_open_v2(db_file.c_str(), &h, SQLITE_OPEN_READONLY, nullptr);
  sqlite3_stmt* st = nullptr;
  sqlite3_prepare_v2(h, "PRAGMA integrity_check", -1, &st, nullptr);
  EXPECT_EQ(sqlite3_step(st), SQLITE_ROW);
  EXPECT_STREQ(reinterpret_cast<const char*>(sqlite3_column_text(st, 0)), "ok");
  sqlite3_finalize(st);
  sqlite3_close(h);
  return out;
}

class Campaign : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    reference_db_ = new std::string(db_path("campaign_reference.db"));
    std::string out;
    const int code =
        run_command("run thermal-calibration --quiet --db " + *reference_db_ + kSetArgs, &out);
    ASSERT_EQ(code, 0) << out;
    reference_ = new std::vector<StepData>(check_run(*reference_db_));
  }
  static void TearDownTestSuite() {
    delete reference_;
    delete reference_db_;
  }
  static std::string* reference_db_;
  static std::vector<StepData>* reference_;
};
std::string* Campaign::reference_db_ = nullptr;
std::vector<StepData>* Campaign::reference_ = nullptr;

TEST_F(Campaign, UninterruptedThermalCalibrationCompletesEveryStep) {
  ASSERT_FALSE(reference_->empty());
  for (const auto& s : *reference_) {
    EXPECT_EQ(s.status, "completed") << s.label;
    if (s.kind == "capture") {
      EXPECT_NEAR(static_cast<double>(s.samples), 4.0 * 400.0, 1.0) << s.label;
    }
    if (s.kind == "move" || s.kind == "set_temperature") {
      EXPECT_EQ(s.samples, 0u) << s.label;
    }
  }
  std::string out;
  ASSERT_EQ(run_command("runs --json --db " + *reference_db_, &out), 0) << out;
  const auto runs = nlohmann::json::parse(out);
  EXPECT_EQ(runs[0]["status"], "completed");
  EXPECT_EQ(runs[0]["steps_done"], runs[0]["steps_total"]);
}

class KilledCampaign : public Campaign, public ::testing::WithParamInterface<int> {};

TEST_P(KilledCampaign, ResumesToTheSameStepsWithNoLostOrDuplicatedSamples) {
  const int kill_after = GetParam();
  const std::string db = db_path("campaign_killed_" + std::to_string(kill_after) + ".db");
  ASSERT_TRUE(run_and_kill(db, kill_after)) << "the run finished before it could be killed";
  std::string out;
  ASSERT_EQ(run_command("runs --json --db " + db, &out), 0) << out;
  // Cut off, not ended: the row says running, but nobody drives it any more.
  EXPECT_EQ(nlohmann::json::parse(out)[0]["status"], "interrupted");
  ASSERT_EQ(run_command("run --quiet --resume 1 --db " + db, &out), 0) << out;
  const auto resumed = check_run(db);
  ASSERT_EQ(resumed.size(), reference_->size());
  for (std::size_t i = 0; i < resumed.size(); ++i) {
    EXPECT_EQ(resumed[i].label, (*reference_)[i].label);
    EXPECT_EQ(resumed[i].status, "completed") << resumed[i].label;
    // Same amount of data per step as the uninterrupted run, to the sample at the window's
    // edges, whatever the clock's phase after the resume.
    EXPECT_NEAR(static_cast<double>(resumed[i].samples),
                static_cast<double>((*reference_)[i].samples), 1.0)
        << resumed[i].label;
  }
}

// Killed after the first soak, in the middle of the static test, and in the rate ladder.
INSTANTIATE_TEST_SUITE_P(AtSeveralPoints, KilledCampaign, ::testing::Values(1, 5, 16));

// A disk that fills mid-run: the database on a small filesystem (tests/support/
// small_fs_preload.cpp under the calstand process), whose capacity the test raises to "free
// space".
class FullDisk : public Campaign {
 protected:
  void SetUp() override {
    const fs::path base = fs::path(::testing::TempDir()) / (std::to_string(getpid()) + "_fulldisk");
    fs::remove_all(base);
    fs::create_directories(base / "disk");
    disk_ = fs::canonical(base / "disk");
    capacity_file_ = base / "capacity";
    db_ = (disk_ / "station.db").string();
    // The built-in station with space rules a small disk can meet.
    nlohmann::json station = calstand::sim::default_station().to_json();
    station["policy"]["min_free_disk_mb"] = 0.5;
    station["policy"]["disk_reserve_mb"] = 2.0;
    station_file_ = (base / "station.json").string();
    std::ofstream(station_file_) << station.dump(2);
  }
  void set_capacity(std::uintmax_t bytes) { std::ofstream(capacity_file_) << bytes << "\n"; }
  std::uintmax_t used_bytes() const {
    std::uintmax_t n = 0;
    for (const auto& e : fs::directory_iterator(disk_)) {
      if (e.is_regular_file()) n += (e.file_size() + 4095) / 4096 * 4096;
    }
    return n;
  }
  // `calstand ARGS` with the database's folder as the small disk.
  int on_small_disk(const std::string& args, std::string* out) {
    const std::string env = std::string("LD_PRELOAD=") + SMALL_FS_PRELOAD +
                            " CALSTAND_SMALL_FS_DIR=" + disk_.string() +
                            " CALSTAND_SMALL_FS_CAPACITY_FILE=" + capacity_file_.string() +
                            // An ASan build wants its runtime first; the preload comes first here.
                            " ASAN_OPTIONS=verify_asan_link_order=0 ";
    return run_command(args, out, env);
  }
  fs::path disk_, capacity_file_;
  std::string db_, station_file_;
};

TEST_F(FullDisk, EndsTheRunInterruptedWithTheReasonAndResumesToTheSameDataOnceSpaceIsBack) {
  // Room for about half of what the whole run stores, plus the write-ahead log's growth to
  // its checkpoint (1000 pages of 4 KiB).
  const auto whole_run_bytes = fs::file_size(*reference_db_);
  set_capacity(whole_run_bytes / 2 + 4 * 1024 * 1024);
  std::string out, run_out;
  const std::string run_args =
      "run thermal-calibration --quiet --station " + station_file_ + " --db " + db_ + kSetArgs;
  EXPECT_NE(on_small_disk(run_args, &run_out), 0) << run_out;
  EXPECT_NE(run_out.find("interrupted"), std::string::npos) << run_out;
  EXPECT_NE(run_out.find("database or disk is full"), std::string::npos) << run_out;

  // Not a `running` lie: interrupted, with the reason and a fault event, and resumable.
  ASSERT_EQ(run_command("show --json --run 1 --db " + db_, &out), 0) << out;
  const auto shown = nlohmann::json::parse(out);
  EXPECT_EQ(shown["status"], "interrupted");
  EXPECT_NE(shown.value("exit_reason", "").find("database or disk is full"), std::string::npos)
      << shown.dump(2) << "\ncalstand run said:\n"
      << run_out;
  bool store_fault = false;
  for (const auto& e : shown["events"]) {
    store_fault |= e["source"] == "store" && e["kind"] == "fault";
  }
  EXPECT_TRUE(store_fault) << shown["events"].dump(2);
  EXPECT_GT(shown["steps_done"].get<int>(), 0) << "what was committed before the disk filled";
  EXPECT_LT(shown["steps_done"].get<int>(), shown["steps_total"].get<int>());

  // Space freed, but less than the station's minimum: refused, saying how much there is.
  set_capacity(used_bytes() + 200 * 1024);
  EXPECT_NE(on_small_disk("run --quiet --resume 1 --db " + db_, &out), 0) << out;
  EXPECT_NE(out.find("disk full: only"), std::string::npos) << out;

  // Enough space: the resumed run ends with the data of an uninterrupted one.
  set_capacity(whole_run_bytes * 4);
  ASSERT_EQ(on_small_disk("run --quiet --resume 1 --db " + db_, &out), 0) << out;
  const auto resumed = check_run(db_);
  ASSERT_EQ(resumed.size(), reference_->size());
  for (std::size_t i = 0; i < resumed.size(); ++i) {
    EXPECT_EQ(resumed[i].status, "completed") << resumed[i].label;
    EXPECT_NEAR(static_cast<double>(resumed[i].samples),
                static_cast<double>((*reference_)[i].samples), 1.0)
        << resumed[i].label;
  }
  EXPECT_FALSE(fs::exists(db_ + "-reserve-1")) << "the reserve is given back when the run ends";
}

}  // namespace

namespace {

// `calstand run static-allan` of 20000 s (minutes of wall time on the simulator) in a child
// process; its pid.
pid_t start_long_static_run(const std::string& db) {
  const pid_t pid = fork();
  if (pid == 0) {
    const std::string cmd = std::string(CALSTAND_BIN) + " run static-allan --quiet --db " + db +
                            " --set duration_s=20000 > /dev/null 2>&1";
    execl("/bin/sh", "sh", "-c", ("exec " + cmd).c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  return pid;
}

// The foreground run obeys the operator's signals: pause at once mid-capture, resume, and the
// interrupted capture is repeated whole.
TEST(CampaignSignals, PauseAtOnceAndResumeRepeatsTheCapture) {
  const std::string db = db_path("campaign_signals.db");
  const pid_t pid = start_long_static_run(db);
  // Wait until the capture is under way, then pause at once.
  auto query = [&](const char* sql) {
    sqlite3* h = nullptr;
    sqlite3_open_v2(db.c_str(), &h, SQLITE_OPEN_READONLY, nullptr);
    sqlite3_busy_timeout(h, 1000);
    sqlite3_stmt* st = nullptr;
    std::string value;
    if (sqlite3_prepare_v2(h, sql, -1, &st, nullptr) == SQLITE_OK &&
        sqlite3_step(st) == SQLITE_ROW && sqlite3_column_text(st, 0)) {
      value = reinterpret_cast<const char*>(sqlite3_column_text(st, 0));
    }
    sqlite3_finalize(st);
    sqlite3_close(h);
    return value;
  };
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (query("SELECT count(*) FROM steps WHERE run_id = 1 AND kind = 'capture' AND "
               "status = 'running'") != "1" &&
         std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  kill(pid, SIGUSR2);
  bool paused = false;
  while (std::chrono::steady_clock::now() < deadline) {
    if (query("SELECT status FROM runs WHERE id = 1") == "paused") {
      paused = true;
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  EXPECT_TRUE(paused) << "the run never reported paused";
  kill(pid, SIGCONT);
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0);
  calstand::store::Database handle(db);
  calstand::store::RunStore runs(handle);
  const auto run = runs.load_run(1);
  EXPECT_EQ(run.summary.status, "completed");
  bool repeated = false;
  for (const auto& s : run.steps) {
    if (s.kind == "capture") {
      repeated |= s.attempts >= 2;
      EXPECT_NEAR(
          static_cast<double>(calstand::store::read_samples(handle, 1, s.index, "imu0").size()),
          20000.0 * 400.0, 1.0);
    }
  }
  EXPECT_TRUE(repeated) << "the interrupted capture was not repeated";
}

// A foreground run whose terminal goes away (SIGHUP: a closed SSH session, a killed tmux) ends
// safe with the reason, like SIGINT and SIGTERM; while it runs, it reads `running` and a second
// process cannot resume it (one process drives a run).
TEST(CampaignSignals, AHangupEndsTheRunWithItsReasonAndALiveRunIsNotResumedTwice) {
  const std::string db = db_path("campaign_hangup.db");
  const pid_t pid = start_long_static_run(db);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (completed_steps(db) < 1 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  std::string out;
  ASSERT_EQ(run_command("runs --json --db " + db, &out), 0) << out;
  EXPECT_EQ(nlohmann::json::parse(out)[0]["status"], "running") << "driven, and so not cut off";
  EXPECT_EQ(run_command("run --quiet --resume 1 --db " + db, &out), 1) << out;
  EXPECT_NE(out.find("run 1 is being run by another process"), std::string::npos) << out;

  kill(pid, SIGHUP);
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status)) << "killed by the hangup instead of ending the run";
  EXPECT_EQ(WEXITSTATUS(status), 1);
  calstand::store::Database handle(db);
  const auto run = calstand::store::RunStore(handle).load_run(1);
  EXPECT_EQ(run.summary.status, "aborted");
  EXPECT_NE(run.summary.exit_reason.find("SIGHUP"), std::string::npos) << run.summary.exit_reason;
}

}  // namespace

namespace {

// Two runs of one station file are two recordings of the same unit: their samples differ (noise,
// a new turn-on bias), while the unit's error model is the same.
TEST(CampaignNoise, TwoRunsOfOneStationRecordTheUnitAnew) {
  const std::string db = db_path("campaign_noise.db");
  for (int i = 0; i < 2; ++i) {
    std::string out;
    ASSERT_EQ(run_command("run two-position --quiet --set capture_s=2 --db " + db, &out), 0) << out;
  }
  calstand::store::Database handle(db);
  const auto first = calstand::store::read_samples(handle, 1, 1, "imu0");
  const auto second = calstand::store::read_samples(handle, 2, 1, "imu0");
  ASSERT_FALSE(first.empty());
  ASSERT_EQ(first.size(), second.size());
  double mean_first = 0.0, mean_second = 0.0;
  std::size_t same = 0;
  for (std::size_t i = 0; i < first.size(); ++i) {
    same += first[i].gyro_dps.x() == second[i].gyro_dps.x() ? 1 : 0;
    mean_first += first[i].accel_mps2.z() / static_cast<double>(first.size());
    mean_second += second[i].accel_mps2.z() / static_cast<double>(first.size());
  }
  EXPECT_EQ(same, 0u) << "the second run replayed the first's noise";
  // Gravity on z in both, the same unit: the means agree to the turn-on bias (500 ug class).
  EXPECT_NEAR(mean_first, mean_second, 0.05);
  EXPECT_NE(mean_first, mean_second);
}

}  // namespace
