// calstandd as a process: kill -9 mid-run and restart (the run resumes by itself; completed
// steps untouched; no lost or duplicated samples), SIGTERM (checkpoint, exit 0), and the
// refusal to listen beyond loopback without a token.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>

#include "daemon_test_support.hpp"
#include "sim/sim_world.hpp"
#include "sim_station_process.hpp"
#include "store/database.hpp"
#include "store/run_store.hpp"
#include "store/sample_reader.hpp"

namespace {

using namespace calstand;
using calstand::testing::ApiClient;
using calstand::testing::DaemonProcess;
using calstand::testing::wait_until;

std::size_t steps_done(ApiClient& api, std::int64_t run) {
  const auto r = api.get("/runs/" + std::to_string(run));
  return r.status == 200 ? r.body["steps_done"].get<std::size_t>() : 0;
}

struct StepSamples {
  std::string status;
  std::optional<int> good_attempt;
  std::string kind;
  int attempts = 0;  ///< attempts started
  std::size_t count = 0;
  std::uint32_t first_sequence = 0;
  std::uint32_t last_sequence = 0;
};

// Every step of `run` with its good attempt's samples; checks they are contiguous (no sequence
// number missing or repeated) and that no other attempt's samples remain of a completed step.
std::vector<StepSamples> read_steps(const std::string& db_file, std::int64_t run) {
  store::Database db(db_file);
  std::vector<StepSamples> out;
  for (const auto& s : store::RunStore(db).load_steps(run)) {
    StepSamples d{std::string(store::to_string(s.status)), s.good_attempt, s.kind, s.attempts};
    if (s.status == store::StepStatus::kCompleted) {
      const auto samples = store::read_samples(db, run, s.index, "imu0");
      d.count = samples.size();
      if (!samples.empty()) {
        d.first_sequence = samples.front().sequence;
        d.last_sequence = samples.back().sequence;
      }
      for (std::size_t k = 1; k < samples.size(); ++k) {
        EXPECT_EQ(samples[k].sequence, (samples[k - 1].sequence + 1) % 65536) << "step " << s.index;
        if (::testing::Test::HasFailure()) break;
      }
      SQLite::Statement q(
          db.sql(), "SELECT COUNT(*) FROM sample_chunks WHERE step_id = ? AND attempt IS NOT ?");
      q.bind(1, s.id);
      q.bind(2, *s.good_attempt);
      q.executeStep();
      EXPECT_EQ(q.getColumn(0).getInt(), 0)
          << "samples of a discarded attempt remain in step " << s.index;
    }
    out.push_back(d);
  }
  return out;
}

TEST(DaemonProcess, KilledMidRunResumesOnRestartWithNoLostOrDuplicatedSamples) {
  const std::string dir = calstand::testing::fresh_dir("kill9");
  const std::string db = dir + "/station.db";
  std::int64_t run = 0;
  std::vector<StepSamples> before;
  {
    DaemonProcess d(db, dir + "/calstandd.log");
    ASSERT_GT(d.port(), 0) << "calstandd did not start; see " << dir << "/calstandd.log";
    ApiClient api(d.port());
    run = api.submit("six-position", {{"capture_s", 300}});
    ASSERT_GT(run, 0);
    // Mid-run: several steps done, a capture in progress (its cut-off attempt must go).
    ASSERT_TRUE(wait_until([&] {
      const auto r = api.get("/runs/" + std::to_string(run));
      return r.status == 200 && r.body["steps_done"].get<std::size_t>() >= 4 &&
             r.body.contains("live") && r.body["live"]["phase"] == "capturing";
    }));
    EXPECT_EQ(d.signal_and_wait(SIGKILL), -SIGKILL);
  }
  before = read_steps(db, run);
  {
    store::Database database(db);
    // Cut off: the row says running, and nobody drives the run any more.
    EXPECT_EQ(store::RunStore(database).load_run(run).summary.status, "interrupted");
  }
  ASSERT_LT(std::count_if(before.begin(), before.end(),
                          [](const auto& s) { return s.status == "completed"; }),
            12)
      << "the run finished before the kill";
  // The step cut off mid-capture: its first attempt was under way.
  const auto cut = std::find_if(before.begin(), before.end(),
                                [](const auto& s) { return s.status != "completed"; });
  ASSERT_NE(cut, before.end());
  const std::size_t cut_step = static_cast<std::size_t>(cut - before.begin());

  DaemonProcess d(db, dir + "/calstandd.log");
  ASSERT_GT(d.port(), 0);
  ApiClient api(d.port());
  ASSERT_TRUE(wait_until([&] {
    return api.get("/runs/" + std::to_string(run)).body.value("status", "") == "completed";
  }));
  const auto after = read_steps(db, run);
  ASSERT_EQ(after.size(), before.size());
  std::optional<std::size_t> capture_count;
  for (std::size_t i = 0; i < after.size(); ++i) {
    EXPECT_EQ(after[i].status, "completed") << i;
    if (before[i].status == "completed") {
      // Completed steps are never touched again.
      EXPECT_EQ(after[i].good_attempt, before[i].good_attempt) << i;
      EXPECT_EQ(after[i].count, before[i].count) << i;
      EXPECT_EQ(after[i].first_sequence, before[i].first_sequence) << i;
      EXPECT_EQ(after[i].last_sequence, before[i].last_sequence) << i;
    }
    if (after[i].count > 0) {
      // Every capture is 300 s at the same rate: the same count, within a control tick.
      if (!capture_count) capture_count = after[i].count;
      EXPECT_NEAR(static_cast<double>(after[i].count), static_cast<double>(*capture_count), 1.0)
          << i;
    }
  }
  EXPECT_TRUE(capture_count.has_value());
  // The cut-off step was redone as a new attempt; the old attempt's samples are gone (read_steps
  // checked that only the good attempt's chunks remain). The kill normally lands in the capture
  // the check saw; on a loaded machine the run may have moved on to a step it had not yet
  // started, which then runs as its first attempt.
  ASSERT_TRUE(after[cut_step].good_attempt.has_value());
  EXPECT_EQ(*after[cut_step].good_attempt, before[cut_step].attempts + 1)
      << "step " << cut_step << " (" << before[cut_step].kind << ", " << before[cut_step].status
      << ", " << before[cut_step].attempts << " attempts before the kill)";
  if (before[cut_step].kind == "capture" && before[cut_step].attempts > 0) {
    EXPECT_GT(after[cut_step].count, 0u);
  }
}

TEST(DaemonProcess, SigtermCheckpointsTheRunAndExitsCleanly) {
  const std::string dir = calstand::testing::fresh_dir("sigterm");
  const std::string db = dir + "/station.db";
  DaemonProcess d(db, dir + "/calstandd.log");
  ASSERT_GT(d.port(), 0);
  ApiClient api(d.port());
  const std::int64_t run = api.submit("six-position", {{"capture_s", 300}});
  ASSERT_TRUE(wait_until([&] { return steps_done(api, run) >= 1; }));
  EXPECT_EQ(d.signal_and_wait(SIGTERM), 0);
  store::Database database(db);
  const auto record = store::RunStore(database).load_run(run);
  EXPECT_EQ(record.summary.status, "interrupted");
  EXPECT_NE(record.summary.exit_reason.find("SIGTERM"), std::string::npos)
      << record.summary.exit_reason;
}

TEST(DaemonProcess, RefusesToListenBeyondLoopbackWithoutAToken) {
  const std::string dir = calstand::testing::fresh_dir("no-token");
  const std::string command = std::string("env -u CALSTAND_TOKEN ") + CALSTANDD_BIN + " --db " +
                              dir + "/station.db --listen 0.0.0.0:0 2>" + dir + "/err.txt";
  const int status = std::system(command.c_str());
  EXPECT_EQ(WEXITSTATUS(status), 2);
  std::ifstream err(dir + "/err.txt");
  const std::string text((std::istreambuf_iterator<char>(err)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("a token is required"), std::string::npos) << text;
}

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// One process drives a database's station: a second daemon and a foreground `calstand run`
// are refused while a daemon runs (naming it), and the lock dies with the daemon.
TEST(DaemonProcess, OwnsItsDatabaseAlone) {
  const std::string dir = calstand::testing::fresh_dir("lock");
  const std::string db = dir + "/station.db";
  {
    DaemonProcess d(db, dir + "/calstandd.log");
    ASSERT_GT(d.port(), 0);
    const std::string second = std::string("env CALSTAND_TOKEN=") + calstand::testing::kTestToken +
                               " " + CALSTANDD_BIN + " --db " + db +
                               " --listen 127.0.0.1:0 >/dev/null 2>" + dir + "/second.txt";
    EXPECT_EQ(WEXITSTATUS(std::system(second.c_str())), 1);
    EXPECT_NE(read_text(dir + "/second.txt").find("in use by another calstandd"), std::string::npos)
        << read_text(dir + "/second.txt");

    const std::string run = std::string(CALSTAND_BIN) + " run two-position --quiet --db " + db +
                            " >" + dir + "/run.txt 2>&1";
    EXPECT_NE(WEXITSTATUS(std::system(run.c_str())), 0);
    const std::string said = read_text(dir + "/run.txt");
    EXPECT_NE(said.find("a station daemon owns this database (calstandd pid"), std::string::npos)
        << said;
    ApiClient api(d.port());
    EXPECT_EQ(api.get("/runs").body.size(), 0u);  // the refused run wrote nothing

    // Nor can another daemon (of another database) share its port and take half its requests.
    const std::string same_port = std::string("env CALSTAND_TOKEN=") +
                                  calstand::testing::kTestToken + " " + CALSTANDD_BIN + " --db " +
                                  dir + "/other.db --listen 127.0.0.1:" + std::to_string(d.port()) +
                                  " >/dev/null 2>" + dir + "/port.txt";
    EXPECT_EQ(WEXITSTATUS(std::system(same_port.c_str())), 1);
    EXPECT_NE(read_text(dir + "/port.txt").find("cannot listen on 127.0.0.1:"), std::string::npos)
        << read_text(dir + "/port.txt");
    EXPECT_EQ(d.signal_and_wait(SIGKILL), -SIGKILL);
  }
  // Killed: the kernel released the lock, a foreground run may use the database now.
  const std::string run = std::string(CALSTAND_BIN) +
                          " run two-position --quiet --set capture_s=2 --db " + db + " >" + dir +
                          "/run2.txt 2>&1";
  EXPECT_EQ(WEXITSTATUS(std::system(run.c_str())), 0) << read_text(dir + "/run2.txt");
}

// The database on a small filesystem (tests/support/small_fs_preload.cpp in the daemon's
// process) whose capacity the test sets.
class SmallDisk {
 public:
  explicit SmallDisk(const std::string& dir) {
    std::filesystem::create_directories(dir + "/disk");
    disk_ = std::filesystem::canonical(dir + "/disk").string();
    capacity_file_ = dir + "/capacity";
  }
  void set_capacity(std::uintmax_t bytes) { std::ofstream(capacity_file_) << bytes << "\n"; }
  std::uintmax_t used_bytes() const {
    std::uintmax_t n = 0;
    for (const auto& e : std::filesystem::directory_iterator(disk_)) {
      if (e.is_regular_file()) n += (e.file_size() + 4095) / 4096 * 4096;
    }
    return n;
  }
  std::vector<std::pair<std::string, std::string>> env() const {
    return {{"LD_PRELOAD", SMALL_FS_PRELOAD},
            {"CALSTAND_SMALL_FS_DIR", disk_},
            {"CALSTAND_SMALL_FS_CAPACITY_FILE", capacity_file_},
            {"ASAN_OPTIONS", "verify_asan_link_order=0"}};  // the preload comes first
  }
  const std::string& path() const { return disk_; }

 private:
  std::string disk_, capacity_file_;
};

TEST(DaemonProcess, FullDiskInterruptsTheRunRefusesNewRunsAndResumesOnceSpaceIsBack) {
  const std::string dir = calstand::testing::fresh_dir("fulldisk");
  SmallDisk disk(dir);
  disk.set_capacity(std::uintmax_t{1} << 30);
  nlohmann::json station = sim::default_station().to_json();
  station["policy"]["min_free_disk_mb"] = 0.5;
  station["policy"]["disk_reserve_mb"] = 2.0;
  std::ofstream(dir + "/station.json") << station.dump(2);
  const std::string db = disk.path() + "/station.db";
  DaemonProcess d(db, dir + "/calstandd.log", "127.0.0.1:0", {"--station", dir + "/station.json"},
                  disk.env());
  ASSERT_GT(d.port(), 0) << "calstandd did not start; see " << dir << "/calstandd.log";
  ApiClient api(d.port());
  const std::int64_t run = api.submit("six-position", {{"capture_s", 300}});
  ASSERT_GT(run, 0);
  ASSERT_TRUE(wait_until([&] {
    const auto r = api.get("/runs/" + std::to_string(run));
    return r.status == 200 && r.body["steps_done"].get<std::size_t>() >= 1 &&
           r.body.contains("live") && r.body["live"]["phase"] == "capturing";
  }));
  // A reader of the database (a report, the console) is open while the disk fills: the daemon's
  // connections are then not the last, and the write-ahead log stays until the reader closes.
  std::optional<store::Database> reader(std::in_place, db);
  store::RunStore(*reader).load_run(run);
  // Room for about half a capture more.
  disk.set_capacity(disk.used_bytes() + 3 * 1024 * 1024);
  nlohmann::json status;
  ASSERT_TRUE(wait_until([&] {
    status = api.get("/runs/" + std::to_string(run)).body;
    return status.value("status", "") == "interrupted";
  })) << status.dump(2);
  EXPECT_NE(status.value("exit_reason", "").find("database or disk is full"), std::string::npos)
      << status.dump(2);
  // The daemon stays up and says why nothing starts; a new run is refused for lack of space.
  nlohmann::json shown;
  ASSERT_TRUE(wait_until([&] {
    shown = api.get("/station").body;
    return shown["waiting"].is_string() &&
           shown["waiting"].get<std::string>().find("disk full") != std::string::npos;
  })) << shown.dump(2);
  // The reader closes last and its checkpoint drops the log: bytes back that were the run's own,
  // not space an operator freed.
  reader.reset();
  const auto refused =
      api.post_json("/runs", {{"procedure", "six-position"}, {"parameters", {{"capture_s", 2}}}});
  EXPECT_EQ(refused.status, 507) << refused.raw;
  EXPECT_NE(refused.raw.find("disk full"), std::string::npos) << refused.raw;

  // Space back: the run resumes by itself and ends whole.
  disk.set_capacity(std::uintmax_t{1} << 30);
  ASSERT_TRUE(wait_until([&] {
    status = api.get("/runs/" + std::to_string(run)).body;
    return status.value("status", "") == "completed";
  })) << status.dump(2);
  EXPECT_TRUE(api.get("/station").body["waiting"].is_null());
  for (const auto& s : read_steps(db, run)) {
    EXPECT_EQ(s.status, "completed");
    if (s.kind == "capture") {
      EXPECT_NEAR(static_cast<double>(s.count), 300.0 * 400.0, 1.0);
    }
  }
}

TEST(DaemonProcess, LatchedInterlockHoldsQueuedRunsUntilAnOperatorClosesIt) {
  const std::string dir = calstand::testing::fresh_dir("interlock");
  const std::string lab = dir + "/lab.json";
  calstand::testing::SimStationProcess sim({"--time-scale", "20", "--station-out", lab});
  DaemonProcess d(dir + "/station.db", dir + "/calstandd.log", "127.0.0.1:0", {"--station", lab});
  ASSERT_GT(d.port(), 0) << "calstandd did not start; see " << dir << "/calstandd.log";
  ApiClient api(d.port());
  ASSERT_TRUE(sim.command("interlock open outer door opened").value("ok", false));
  const std::int64_t run = api.submit("six-position", {{"capture_s", 2}});
  ASSERT_GT(run, 0);
  nlohmann::json shown;
  ASSERT_TRUE(wait_until([&] {
    shown = api.get("/station").body;
    return shown["waiting"].is_string() &&
           shown["waiting"].get<std::string>().find("interlock") != std::string::npos;
  })) << shown.dump(2);
  EXPECT_NE(shown["waiting"].get<std::string>().find("door opened"), std::string::npos);
  // Refused while the cause is there.
  auto closing = api.post("/station/interlock/close", "");
  EXPECT_EQ(closing.status, 409) << closing.raw;
  // The cause gone, the run still waits: nothing closes the interlock but an operator.
  ASSERT_TRUE(sim.command("interlock clear outer").value("ok", false));
  std::this_thread::sleep_for(std::chrono::seconds(3));
  EXPECT_EQ(api.get("/runs/" + std::to_string(run)).body.value("status", ""), "queued");
  closing = api.post("/station/interlock/close", "");
  ASSERT_EQ(closing.status, 200) << closing.raw;
  ASSERT_EQ(closing.body["closed"].size(), 1u) << closing.raw;
  EXPECT_EQ(closing.body["closed"][0], "outer axis interlock (door opened)");
  nlohmann::json status;
  ASSERT_TRUE(wait_until([&] {
    status = api.get("/runs/" + std::to_string(run)).body;
    return status.value("status", "") == "completed";
  })) << status.dump(2);
  // Who closed it and when, in the station's log.
  bool recorded = false;
  const auto station_now = api.get("/station");
  for (const auto& e : station_now.body["events"]) {
    recorded |= e["message"] == "interlock closed: outer axis interlock (door opened)" &&
                e["source"].get<std::string>().rfind("tester", 0) == 0 &&
                e["source"].get<std::string>().find("(token operator)") != std::string::npos &&
                !e["wall_utc"].get<std::string>().empty();
  }
  EXPECT_TRUE(recorded) << station_now.raw;
}

}  // namespace
