// The fleet end to end against a real PostgreSQL server started for this test (a temporary
// cluster on a unix socket, tests/support/postgres_server.hpp): stations made by the
// simulator through the calstand command (six-position runs of known units, calibrations,
// acceptance verdicts, fit history, samples) sync to the central database at once, cut by a
// server stop and by kill -9 and resumed, and the fleet queries read the union. Row-level
// security, schema versions and the password rules are checked on the same server.
//
// Skipped when no PostgreSQL server binaries are found; CALSTAND_REQUIRE_POSTGRES=1 (set by
// scripts/run-tests.sh, whose setup installs `postgresql`) makes that a failure.
#include <SQLiteCpp/Statement.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <future>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <pqxx/pqxx>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "cli_runner.hpp"
#include "daemon_test_support.hpp"
#include "postgres_server.hpp"
#include "store/database.hpp"
#include "store/hash.hpp"
#include "store/migration_blocks.hpp"
#include "store/run_store.hpp"
#include "store/station_identity.hpp"

extern char** environ;

namespace {

using calstand::testing::PostgresServer;
using calstand::testing::Result;
using calstand::testing::run;
using calstand::testing::write_text;

constexpr const char* kModel = "accel_bias,accel_scale,accel_misalignment,gyro_bias,earth_rate";
constexpr const char* kDbName = "fleet";
constexpr const char* kReader = "fleet_reader";

/// Tables a sync copies, each counted on the station (SQLite) and centrally for that station.
const std::vector<std::string> kTables = {
    "runs", "steps",         "events",     "run_units",       "calibrations",     "acceptances",
    "fits", "sample_chunks", "step_means", "table_telemetry", "chamber_telemetry"};

/// A simulated station: its database file and the login role it syncs as.
struct Station {
  std::string name;
  std::string db;
  std::string role;
  std::string uuid;
};

class FleetSync : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const std::string bin = calstand::testing::find_postgres_bin_dir();
    if (bin.empty()) {
      missing_ = "no PostgreSQL server (initdb, pg_ctl) on PATH or in /usr/lib/postgresql/*/bin";
      return;
    }
    dir_ = ::testing::TempDir() + "calstand-fleet-" + std::to_string(::getpid()) + "/";
    std::filesystem::create_directories(dir_);
    server_ = std::make_unique<PostgresServer>(bin, dir_ + "pg");
    if (!server_->error().empty()) {
      missing_ = server_->error();
      return;
    }
    {
      pqxx::connection admin(server_->conninfo(PostgresServer::kOwner, "postgres"));
      pqxx::nontransaction tx(admin);
      tx.exec(std::string("CREATE DATABASE ") + kDbName);
    }
    const Result migrated =
        run("fleet migrate --to " + owner_url() + " --password-file " + server_->passfile());
    ASSERT_EQ(migrated.exit_code, 0) << migrated.out;
    add_role(kReader, "calstand_reader");
    spec_ = dir_ + "spec.json";
    write_text(spec_, R"js({"format": "calstand-acceptance/1", "name": "LN200 line rev A", "k": 2,
      "limits": [{"parameter": "gyro_bias.*", "max_abs": 0.005, "unit": "deg/s"},
                 {"parameter": "accel_bias.*", "max_abs": 0.049, "unit": "m/s^2"}]})js");
  }
  static void TearDownTestSuite() {
    server_.reset();
    if (!dir_.empty()) std::filesystem::remove_all(dir_);
  }
  void SetUp() override {
    if (missing_.empty()) return;
    if (std::getenv("CALSTAND_REQUIRE_POSTGRES") != nullptr &&
        std::string(std::getenv("CALSTAND_REQUIRE_POSTGRES")) == "1") {
      FAIL() << missing_ << " (CALSTAND_REQUIRE_POSTGRES=1: scripts/setup-deps.sh installs "
             << "`postgresql`)";
    }
    GTEST_SKIP() << missing_;
  }

  static std::string owner_url() { return server_->url(PostgresServer::kOwner, kDbName); }

  /// A login role in `group` (calstand_station or calstand_reader) with its password in the
  /// test's password file.
  static void add_role(const std::string& role, const std::string& group) {
    const std::string password = "pw-" + role;
    pqxx::connection owner(server_->conninfo(PostgresServer::kOwner, kDbName));
    pqxx::nontransaction tx(owner);
    tx.exec("CREATE ROLE " + role + " LOGIN PASSWORD " + tx.quote(password) + " IN ROLE " + group);
    server_->add_password(role, password);
  }

  /// A station with one six-position run per unit (the IMU slot imu0 holds each in turn), each
  /// run calibrated; the first run's record judged against the specification.
  static Station make_station(const std::string& name, const std::vector<std::string>& serials) {
    std::string role = "station_" + name;
    std::replace(role.begin(), role.end(), '-', '_');  // a role name is an identifier
    Station s{name, dir_ + name + ".db", role, ""};
    add_role(s.role, "calstand_station");
    for (std::size_t i = 0; i < serials.size(); ++i) {
      Result r = run("run six-position --quiet --db " + s.db + " --unit imu0=" + serials[i]);
      EXPECT_EQ(r.exit_code, 0) << r.out;
      const std::string run_id = std::to_string(i + 1);
      r = run("calibrate --db " + s.db + " --run " + run_id + " --model " + kModel + " --out-dir " +
              dir_);
      EXPECT_EQ(r.exit_code, 0) << r.out;
      if (i == 0) {
        r = run("accept --db " + s.db + " --run 1 --spec " + spec_);
        EXPECT_TRUE(r.exit_code == 0 || r.exit_code == 1) << r.out;  // 1: a unit failed
      }
    }
    calstand::store::Database db(s.db);
    s.uuid = calstand::store::station_uuid(db);
    // A station-wide event (no run), as a daemon records an interlock between runs.
    calstand::store::EventRecord interlock;
    interlock.time_s = 12.5;
    interlock.kind = calstand::store::EventKind::kInterlock;
    interlock.source = "chamber";
    interlock.message = "door opened between runs";
    interlock.detail = {{"air_c", 24.5}};
    calstand::store::RunStore(db).add_event(interlock);
    return s;
  }

  static std::string sync_args(const Station& s, const std::string& extra = "") {
    return "sync --samples --db " + s.db + " --to " + server_->url(s.role, kDbName) +
           " --password-file " + server_->passfile() + " --name " + s.name + " " + extra;
  }

  /// Row counts of every synced table on the station, and its samples and their bytes.
  static std::map<std::string, long long> local_counts(const Station& s) {
    calstand::store::Database db(s.db);
    std::map<std::string, long long> n;
    for (const std::string& t : kTables) {
      n[t] = db.sql().execAndGet("SELECT COUNT(*) FROM " + t).getInt64();
    }
    n["samples"] = db.sql().execAndGet("SELECT TOTAL(count) FROM sample_chunks").getInt64();
    n["sample_bytes"] =
        db.sql().execAndGet("SELECT TOTAL(length(data)) FROM sample_chunks").getInt64();
    return n;
  }

  /// The same counts in the central database for the station's rows (read as the owner).
  static std::map<std::string, long long> central_counts(const Station& s) {
    pqxx::connection owner(server_->conninfo(PostgresServer::kOwner, kDbName));
    pqxx::read_transaction tx(owner);
    std::map<std::string, long long> n;
    for (const std::string& t : kTables) {
      n[t] = tx.exec_params("SELECT count(*) FROM " + t + " WHERE station = $1", s.uuid)[0][0]
                 .as<long long>();
    }
    n["samples"] = tx.exec_params(
                         "SELECT coalesce(sum(count), 0) FROM sample_chunks "
                         "WHERE station = $1",
                         s.uuid)[0][0]
                       .as<long long>();
    n["sample_bytes"] = tx.exec_params(
                              "SELECT coalesce(sum(octet_length(data)), 0) FROM "
                              "sample_chunks WHERE station = $1",
                              s.uuid)[0][0]
                            .as<long long>();
    return n;
  }

  /// Waits until a session of `role` waits on a lock (the sync blocked where the test wants to
  /// cut it); false after 30 s.
  static bool wait_until_blocked(const std::string& role) {
    pqxx::connection owner(server_->conninfo(PostgresServer::kOwner, kDbName));
    for (int i = 0; i < 3000; ++i) {
      pqxx::nontransaction tx(owner);
      if (tx.exec_params("SELECT count(*) FROM pg_stat_activity WHERE usename = $1 AND "
                         "wait_event_type = 'Lock'",
                         role)[0][0]
              .as<int>() > 0) {
        return true;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return false;
  }

  static inline std::string missing_;
  static inline std::string dir_;
  static inline std::string spec_;
  static inline std::unique_ptr<PostgresServer> server_;
  static inline std::vector<Station> stations_;  ///< the three that sync at once
};

TEST_F(FleetSync, ThreeStationsSyncingAtOnceCopyEveryRowOnceAndASecondSyncChangesNothing) {
  // U-SHARED is calibrated at line-1 and again at line-3: a unit that moved between stations.
  stations_ = {make_station("line-1", {"U-101", "U-SHARED"}), make_station("line-2", {"U-201"}),
               make_station("line-3", {"U-301", "U-SHARED"})};
  std::vector<std::future<Result>> syncs;
  for (const Station& s : stations_) {
    syncs.push_back(std::async(std::launch::async, [&s] { return run(sync_args(s, "--json")); }));
  }
  for (std::size_t i = 0; i < syncs.size(); ++i) {
    const Result r = syncs[i].get();
    ASSERT_EQ(r.exit_code, 0) << r.out;
    const nlohmann::json report = nlohmann::json::parse(r.out);
    EXPECT_EQ(report["station"]["uuid"], stations_[i].uuid);
    EXPECT_EQ(report["copied"]["runs"], local_counts(stations_[i])["runs"]);
  }
  for (const Station& s : stations_) {
    const auto local = local_counts(s);
    EXPECT_GT(local.at("sample_chunks"), 0);
    EXPECT_GT(local.at("acceptances"), 0);
    EXPECT_GT(local.at("fits"), 0);
    EXPECT_EQ(central_counts(s), local) << s.name;
  }
  // Central migration 3: chunks are stored as they are, without a compression attempt.
  {
    pqxx::connection owner(server_->conninfo(PostgresServer::kOwner, kDbName));
    pqxx::read_transaction tx(owner);
    EXPECT_EQ(tx.exec("SELECT attstorage FROM pg_attribute WHERE attrelid = "
                      "'sample_chunks'::regclass AND attname = 'data'")[0][0]
                  .as<std::string>(),
              "e");
  }
  // Every station-wide event arrived without a run; telemetry arrived value for value (binary
  // COPY sends a double's eight bytes).
  for (const Station& s : stations_) {
    pqxx::connection owner(server_->conninfo(PostgresServer::kOwner, kDbName));
    pqxx::read_transaction tx(owner);
    EXPECT_EQ(tx.exec_params("SELECT count(*) FROM events WHERE station = $1 AND run_id IS NULL "
                             "AND kind = 'interlock' AND detail->>'air_c' = '24.5'",
                             s.uuid)[0][0]
                  .as<int>(),
              1)
        << s.name;
    std::vector<std::tuple<long long, double, double, double>> local_rows;
    std::vector<std::tuple<long long, double, double, double>> central_rows;
    calstand::store::Database db(s.db);
    SQLite::Statement q(db.sql(),
                        "SELECT id, time_s, outer_deg, inner_rate_dps FROM table_telemetry "
                        "ORDER BY id");
    while (q.executeStep()) {
      local_rows.emplace_back(q.getColumn(0).getInt64(), q.getColumn(1).getDouble(),
                              q.getColumn(2).getDouble(), q.getColumn(3).getDouble());
    }
    for (const auto& row : tx.exec_params("SELECT local_id, time_s, outer_deg, inner_rate_dps "
                                          "FROM table_telemetry WHERE station = $1 ORDER BY "
                                          "local_id",
                                          s.uuid)) {
      central_rows.emplace_back(row[0].as<long long>(), row[1].as<double>(), row[2].as<double>(),
                                row[3].as<double>());
    }
    EXPECT_GT(local_rows.size(), 0u) << s.name;
    EXPECT_EQ(central_rows, local_rows) << s.name;
    // Step means as the station has them, by step and device.
    const double local_gz = db.sql()
                                .execAndGet(
                                    "SELECT gz_dps FROM step_means ORDER BY step_id, "
                                    "attempt, device LIMIT 1")
                                .getDouble();
    EXPECT_EQ(tx.exec_params("SELECT gz_dps FROM step_means WHERE station = $1 ORDER BY "
                             "step_local_id, attempt, device LIMIT 1",
                             s.uuid)[0][0]
                  .as<double>(),
              local_gz);
  }
  // A second sync: nothing copied, nothing changed.
  for (const Station& s : stations_) {
    const Result r = run(sync_args(s, "--json"));
    ASSERT_EQ(r.exit_code, 0) << r.out;
    const nlohmann::json copied = nlohmann::json::parse(r.out)["copied"];
    for (const std::string& t : kTables) EXPECT_EQ(copied[t], 0) << s.name << " " << t;
    EXPECT_EQ(central_counts(s), local_counts(s)) << s.name;
  }
  // The text form says so too.
  const Result again = run(sync_args(stations_[0]));
  EXPECT_NE(again.out.find("nothing new"), std::string::npos) << again.out;
}

TEST_F(FleetSync, FleetQueriesLotAndTrendReturnTheUnionOfTheStations) {
  ASSERT_EQ(stations_.size(), 3u) << "needs the stations of the first test";
  const std::string from =
      " --from " + server_->url(kReader, kDbName) + " --password-file " + server_->passfile();
  long long runs_total = 0;
  std::set<std::string> uuids;
  for (const Station& s : stations_) {
    runs_total += local_counts(s)["runs"];
    uuids.insert(s.uuid);
  }
  Result r = run("fleet runs --json" + from);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  nlohmann::json runs = nlohmann::json::parse(r.out)["runs"];
  long long of_these = 0;
  for (const auto& run_row : runs) of_these += uuids.count(run_row["station_uuid"]) ? 1 : 0;
  EXPECT_EQ(of_these, runs_total);

  // By station (name or uuid) and by unit.
  r = run("fleet runs --json --station line-3" + from);
  runs = nlohmann::json::parse(r.out)["runs"];
  ASSERT_EQ(runs.size(), 2u) << r.out;
  for (const auto& run_row : runs) EXPECT_EQ(run_row["station"], "line-3");
  r = run("fleet runs --json --station " + stations_[1].uuid + from);
  EXPECT_EQ(nlohmann::json::parse(r.out)["runs"].size(), 1u) << r.out;
  r = run("fleet runs --json --serial U-SHARED" + from);
  runs = nlohmann::json::parse(r.out)["runs"];
  ASSERT_EQ(runs.size(), 2u) << r.out;
  EXPECT_NE(runs[0]["station"], runs[1]["station"]);

  r = run("fleet units --json" + from);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  std::map<std::string, nlohmann::json> units;
  const nlohmann::json units_json = nlohmann::json::parse(r.out);
  for (const auto& u : units_json["units"]) {
    units[u["serial"].get<std::string>()] = u;
  }
  for (const char* serial : {"U-101", "U-201", "U-301", "U-SHARED"}) {
    EXPECT_EQ(units.count(serial), 1u) << serial << " in " << r.out;
  }
  EXPECT_EQ(units["U-SHARED"]["stations"], nlohmann::json({"line-1", "line-3"}));
  EXPECT_EQ(units["U-SHARED"]["calibrations"], 2);

  // The unit's records across both stations: the newest in force.
  r = run("fleet calibrations --json --serial U-SHARED" + from);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const nlohmann::json records = nlohmann::json::parse(r.out)["calibrations"];
  ASSERT_EQ(records.size(), 2u) << r.out;
  EXPECT_EQ(records[0]["station"], "line-3");
  EXPECT_TRUE(records[0]["in_force"].get<bool>());
  EXPECT_FALSE(records[1]["in_force"].get<bool>());
  r = run("fleet calibrations --json --station line-2" + from);
  EXPECT_EQ(nlohmann::json::parse(r.out)["calibrations"].size(), 1u) << r.out;

  // lot and trend read the central database through the same analysis as a station file.
  r = run("lot --json" + from);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const nlohmann::json lot = nlohmann::json::parse(r.out);
  std::set<std::string> lot_serials;
  for (const auto& u : lot["units"]) lot_serials.insert(u["serial"]);
  EXPECT_EQ(lot_serials, (std::set<std::string>{"U-101", "U-201", "U-301", "U-SHARED"}));
  r = run("trend --json --serial U-SHARED" + from);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  const nlohmann::json trend = nlohmann::json::parse(r.out);
  ASSERT_EQ(trend["records"].size(), 2u) << r.out;
  EXPECT_EQ(trend["records"][0]["station"], "line-1");
  EXPECT_EQ(trend["records"][1]["station"], "line-3");
  EXPECT_FALSE(trend["parameters"].empty());

  // A station's role sees its own rows only.
  r = run("fleet runs --json --from " + server_->url(stations_[1].role, kDbName) +
          " --password-file " + server_->passfile());
  ASSERT_EQ(r.exit_code, 0) << r.out;
  runs = nlohmann::json::parse(r.out)["runs"];
  ASSERT_EQ(runs.size(), 1u) << r.out;
  EXPECT_EQ(runs[0]["station"], "line-2");
}

TEST_F(FleetSync, ASyncCutByStoppingTheServerResumesWithNothingLostOrDoubled) {
  const Station s = make_station("line-4", {"U-401", "U-402"});
  std::future<Result> sync;
  {
    // Hold the sync at its first calibration: the runs are committed, the records in flight.
    pqxx::connection owner(server_->conninfo(PostgresServer::kOwner, kDbName));
    pqxx::work lock(owner);
    lock.exec("LOCK TABLE calibrations IN EXCLUSIVE MODE");
    sync = std::async(std::launch::async, [&s] { return run(sync_args(s)); });
    ASSERT_TRUE(wait_until_blocked(s.role));
    ASSERT_TRUE(server_->stop("fast"));
  }
  const Result cut = sync.get();
  EXPECT_EQ(cut.exit_code, 1) << cut.out;
  EXPECT_NE(cut.out.find("central: copy calibrations"), std::string::npos) << cut.out;
  ASSERT_TRUE(server_->start());
  auto central = central_counts(s);
  const auto local = local_counts(s);
  EXPECT_EQ(central["runs"], local.at("runs"));
  EXPECT_EQ(central["steps"], local.at("steps"));
  EXPECT_EQ(central["calibrations"], 0) << "the batch in flight was rolled back";
  EXPECT_EQ(central["sample_chunks"], 0);

  const Result resumed = run(sync_args(s, "--json"));
  ASSERT_EQ(resumed.exit_code, 0) << resumed.out;
  const nlohmann::json copied = nlohmann::json::parse(resumed.out)["copied"];
  EXPECT_EQ(copied["runs"], 0) << "the runs were already there";
  EXPECT_EQ(copied["calibrations"], local.at("calibrations"));
  EXPECT_EQ(central_counts(s), local);
}

TEST_F(FleetSync, ASyncKilledMidWayResumesWithNothingLostOrDoubled) {
  const Station s = make_station("line-5", {"U-501", "U-502"});
  const std::string out = dir_ + "killed-sync.out";
  pid_t pid = 0;
  {
    // Hold the sync at its first sample batch's cursor: runs, records and fits are committed,
    // the batch's chunks are written but not committed when the process dies.
    pqxx::connection owner(server_->conninfo(PostgresServer::kOwner, kDbName));
    pqxx::work lock(owner);
    lock.exec("LOCK TABLE sample_cursors IN EXCLUSIVE MODE");
    const std::string command = std::string("exec ") + CALSTAND_BIN + " " +
                                sync_args(s, "--batch-chunks 8") + " > " + out + " 2>&1";
    const char* argv[] = {"/bin/sh", "-c", command.c_str(), nullptr};
    ASSERT_EQ(::posix_spawn(&pid, "/bin/sh", nullptr, nullptr, const_cast<char**>(argv), environ),
              0);
    ASSERT_TRUE(wait_until_blocked(s.role));
    ASSERT_EQ(::kill(pid, SIGKILL), 0);
    int status = 0;
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    EXPECT_TRUE(WIFSIGNALED(status));
  }  // the lock is released: the dead client's transaction is rolled back, never committed
  const auto local = local_counts(s);
  auto central = central_counts(s);
  EXPECT_EQ(central["runs"], local.at("runs"));
  EXPECT_EQ(central["calibrations"], local.at("calibrations"));
  EXPECT_EQ(central["fits"], local.at("fits"));
  EXPECT_EQ(central["sample_chunks"], 0);

  const Result resumed = run(sync_args(s, "--json --batch-chunks 8"));
  ASSERT_EQ(resumed.exit_code, 0) << resumed.out;
  const nlohmann::json copied = nlohmann::json::parse(resumed.out)["copied"];
  EXPECT_EQ(copied["runs"], 0);
  EXPECT_EQ(copied["sample_chunks"], local.at("sample_chunks"));
  EXPECT_EQ(central_counts(s), local);
  // Byte for byte: the central chunks are the station's, in the same order.
  pqxx::connection owner(server_->conninfo(PostgresServer::kOwner, kDbName));
  pqxx::read_transaction tx(owner);
  const std::string central_sha256 =
      tx.exec_params(
            "SELECT encode(sha256(string_agg(data, ''::bytea ORDER BY local_id)), "
            "'hex') FROM sample_chunks WHERE station = $1",
            s.uuid)[0][0]
          .as<std::string>();
  calstand::store::Database db(s.db);
  SQLite::Statement q(db.sql(), "SELECT data FROM sample_chunks ORDER BY id");
  std::string bytes;
  while (q.executeStep()) {
    bytes.append(static_cast<const char*>(q.getColumn(0).getBlob()),
                 static_cast<std::size_t>(q.getColumn(0).getBytes()));
  }
  EXPECT_EQ(calstand::store::sha256_hex(bytes), central_sha256);
}

TEST_F(FleetSync, ARunCutOffWaitsWhileLaterRunsSyncAndFollowsOnceResumedToItsEnd) {
  Station s = make_station("line-7", {"U-701"});
  // Run 2 killed mid-way (a power cut): its row says running, nobody drives it (interrupted).
  const std::string thermal =
      " --set 'temperatures=[15,35]' --set soak_s=600 --set capture_s=4"
      " --set 'outer_angles=[0,90,180]' --set 'inner_angles=[0,90]' --set 'rates=[20,90]'"
      " --set revolutions=1 --set ramp_c_per_min=2";
  const std::string command = std::string("exec ") + CALSTAND_BIN +
                              " run thermal-calibration --quiet --unit imu0=U-702 --db " + s.db +
                              thermal + " > /dev/null 2>&1";
  const char* argv[] = {"/bin/sh", "-c", command.c_str(), nullptr};
  pid_t pid = 0;
  ASSERT_EQ(::posix_spawn(&pid, "/bin/sh", nullptr, nullptr, const_cast<char**>(argv), environ), 0);
  bool killed = false;
  for (int i = 0; i < 30000 && !killed; ++i) {
    int status = 0;
    if (::waitpid(pid, &status, WNOHANG) == pid) break;  // ended before the cut: a failure
    if (std::filesystem::exists(s.db)) {
      calstand::store::Database db(s.db);
      if (db.sql()
              .execAndGet("SELECT count(*) FROM steps WHERE run_id = 2 AND status = 'completed'")
              .getInt() >= 3) {
        ::kill(pid, SIGKILL);
        ::waitpid(pid, &status, 0);
        killed = true;
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  ASSERT_TRUE(killed) << "run 2 ended before it could be cut";
  // Run 3 after it, calibrated.
  Result r = run("run six-position --quiet --db " + s.db + " --unit imu0=U-703");
  ASSERT_EQ(r.exit_code, 0) << r.out;
  r = run("calibrate --db " + s.db + " --run 3 --model " + std::string(kModel) + " --out-dir " +
          dir_);
  ASSERT_EQ(r.exit_code, 0) << r.out;

  r = run(sync_args(s, "--json"));
  ASSERT_EQ(r.exit_code, 0) << r.out;
  nlohmann::json report = nlohmann::json::parse(r.out);
  EXPECT_EQ(report["copied"]["runs"], 2);
  EXPECT_EQ(report["waiting_runs"], nlohmann::json({2}));
  auto central = central_counts(s);
  EXPECT_EQ(central["runs"], 2);
  EXPECT_EQ(central["calibrations"], 2) << "run 3's record does not wait for run 2";
  const auto cursor = [&] {
    pqxx::connection owner(server_->conninfo(PostgresServer::kOwner, kDbName));
    pqxx::read_transaction tx(owner);
    return tx
        .exec_params(
            "SELECT last_local_id FROM sync_cursors WHERE station = $1 AND "
            "stream = 'runs'",
            s.uuid)[0][0]
        .as<long long>();
  };
  EXPECT_EQ(cursor(), 1) << "the cursor stops before the run that has not ended";

  // Resumed to its end, the run follows; the cursor passes it.
  r = run("run --quiet --resume 2 --db " + s.db);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  r = run(sync_args(s, "--json"));
  ASSERT_EQ(r.exit_code, 0) << r.out;
  report = nlohmann::json::parse(r.out);
  EXPECT_EQ(report["copied"]["runs"], 1);
  EXPECT_TRUE(report["waiting_runs"].empty()) << r.out;
  EXPECT_EQ(cursor(), 3);
  EXPECT_EQ(central_counts(s), local_counts(s));
}

TEST_F(FleetSync, AStationRoleInsertsAndReadsOnlyItsOwnRows) {
  ASSERT_EQ(stations_.size(), 3u) << "needs the stations of the first test";
  pqxx::connection as_line2(server_->conninfo(stations_[1].role, kDbName));
  {
    pqxx::read_transaction tx(as_line2);
    EXPECT_EQ(tx.exec("SELECT count(DISTINCT station) FROM runs")[0][0].as<int>(), 1);
    EXPECT_EQ(tx.exec_params("SELECT count(*) FROM calibrations WHERE station = $1",
                             stations_[0].uuid)[0][0]
                  .as<int>(),
              0);
  }
  // Writing a row of another station is refused by row-level security.
  try {
    pqxx::work tx(as_line2);
    tx.exec_params(
        "INSERT INTO runs (station, local_id, procedure_name, procedure_text, procedure_sha256, "
        "parameters, station_snapshot, status, created_utc) VALUES ($1, 999, 'x', 'x', 'x', "
        "'{}', '{}', 'completed', '2026-01-01')",
        stations_[0].uuid);
    tx.commit();
    ADD_FAILURE() << "a station wrote another station's run";
  } catch (const pqxx::sql_error& e) {
    EXPECT_NE(std::string(e.what()).find("row-level security"), std::string::npos) << e.what();
  }
  // ... and deleting is not granted at all.
  try {
    pqxx::work tx(as_line2);
    tx.exec("DELETE FROM fits");
    tx.commit();
    ADD_FAILURE() << "a station deleted rows";
  } catch (const pqxx::sql_error& e) {
    EXPECT_NE(std::string(e.what()).find("permission denied"), std::string::npos) << e.what();
  }
  // A copy of line-1's file synced by line-2's role: the station id belongs to another role.
  const std::string copy = dir_ + "copied.db";
  std::filesystem::copy_file(stations_[0].db, copy);
  Station impostor{"impostor", copy, stations_[1].role, stations_[0].uuid};
  const Result r = run(sync_args(impostor));
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_NE(r.out.find("registered to another database role"), std::string::npos) << r.out;
}

TEST_F(FleetSync, ACentralSchemaOfAnotherVersionIsRefusedByName) {
  ASSERT_EQ(stations_.size(), 3u) << "needs the stations of the first test";
  pqxx::connection owner(server_->conninfo(PostgresServer::kOwner, kDbName));
  {
    pqxx::work tx(owner);
    tx.exec("INSERT INTO calstand_schema (version, title) VALUES (99, 'from the future')");
    tx.commit();
  }
  Result r = run(sync_args(stations_[0]));
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_NE(r.out.find("schema version 99 ('from the future'), newer than station line-1's"),
            std::string::npos)
      << r.out;
  EXPECT_NE(r.out.find("update calstand on station line-1"), std::string::npos) << r.out;
  r = run("fleet migrate --to " + owner_url() + " --password-file " + server_->passfile());
  EXPECT_EQ(r.exit_code, 1) << r.out;
  {
    pqxx::work tx(owner);
    tx.exec("DELETE FROM calstand_schema WHERE version = 99");
    tx.commit();
  }
  // A database without the calstand schema: its owner is told how to make it.
  {
    pqxx::nontransaction tx(owner);
    tx.exec("CREATE DATABASE empty_fleet");
  }
  r = run("sync --db " + stations_[0].db + " --to " +
          server_->url(stations_[0].role, "empty_fleet") + " --password-file " +
          server_->passfile() + " --name line-1");
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_NE(r.out.find("no calstand schema there"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("calstand fleet migrate"), std::string::npos) << r.out;
}

TEST_F(FleetSync, AStationNameIsUniqueInTheFleet) {
  ASSERT_EQ(stations_.size(), 3u) << "needs the stations of the first test";
  // Another station (its own file, its own role) asking for line-2's name is refused by name,
  // though row-level security hides line-2's row from it; nothing of it is registered.
  Station s = make_station("line-2b", {"U-221"});
  const Result r = run("sync --db " + s.db + " --to " + server_->url(s.role, kDbName) +
                       " --password-file " + server_->passfile() + " --name line-2");
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_NE(r.out.find("the name 'line-2' is another station's in this fleet"), std::string::npos)
      << r.out;
  pqxx::connection owner(server_->conninfo(PostgresServer::kOwner, kDbName));
  pqxx::read_transaction tx(owner);
  EXPECT_EQ(tx.exec_params("SELECT count(*) FROM stations WHERE uuid = $1", s.uuid)[0][0].as<int>(),
            0);
  EXPECT_EQ(tx.exec("SELECT count(*) FROM stations WHERE name = 'line-2'")[0][0].as<int>(), 1);
}

TEST_F(FleetSync, MigratingAVersion1DatabaseKeepsItsRowsAndTellsRepeatedNamesApart) {
  // A central database at version 1 (before names were unique, telemetry synced): two stations
  // registered as "bench", one run of the first.
  {
    pqxx::connection admin(server_->conninfo(PostgresServer::kOwner, "postgres"));
    pqxx::nontransaction tx(admin);
    tx.exec("CREATE DATABASE fleet_v1");
  }
  pqxx::connection owner(server_->conninfo(PostgresServer::kOwner, "fleet_v1"));
  const std::string schema =
      calstand::testing::read_text(std::string(CALSTAND_SOURCE_DIR) + "/fleet/central_schema.sql");
  const auto blocks = calstand::store::parse_migrations(schema);
  ASSERT_GE(blocks.size(), 2u);
  const char* first = "11111111-1111-4111-8111-111111111111";
  const char* second = "22222222-2222-4222-8222-222222222222";
  {
    pqxx::work tx(owner);
    tx.exec(
        "CREATE TABLE calstand_schema (version integer PRIMARY KEY, title text NOT NULL, "
        "applied_utc timestamptz NOT NULL DEFAULT now())");
    tx.exec(blocks[0].sql);
    tx.exec_params("INSERT INTO calstand_schema (version, title) VALUES (1, $1)", blocks[0].title);
    tx.exec_params(
        "INSERT INTO stations (uuid, name, store_schema, registered_utc) VALUES "
        "($1, 'bench', 6, '2026-01-02T00:00:00Z'), ($2, 'bench', 6, '2026-03-04T00:00:00Z')",
        first, second);
    tx.exec_params(
        "INSERT INTO runs (station, local_id, procedure_name, procedure_text, procedure_sha256, "
        "parameters, station_snapshot, status, created_utc) VALUES ($1, 1, 'six-position', "
        "'{}', 'x', '{}', '{}', 'completed', '2026-01-02T01:00:00Z')",
        first);
    tx.commit();
  }
  const Result r = run("fleet migrate --to " + server_->url(PostgresServer::kOwner, "fleet_v1") +
                       " --password-file " + server_->passfile());
  ASSERT_EQ(r.exit_code, 0) << r.out;
  pqxx::read_transaction tx(owner);
  EXPECT_EQ(tx.exec("SELECT max(version) FROM calstand_schema")[0][0].as<int>(),
            static_cast<int>(blocks.size()));
  const auto name_of = [&](const char* uuid) {
    return tx.exec_params("SELECT name FROM stations WHERE uuid = $1", uuid)[0][0]
        .as<std::string>();
  };
  EXPECT_EQ(name_of(first), "bench") << "the first registration keeps its name";
  EXPECT_EQ(name_of(second), "bench #22222222");
  EXPECT_EQ(tx.exec("SELECT count(*) FROM runs")[0][0].as<int>(), 1);
}

TEST_F(FleetSync, TheDaemonPublishesInTheBackgroundAndRetriesWhileTheServerIsDown) {
  Station s{"line-6", dir_ + "line-6.db", "station_line_6", ""};
  add_role(s.role, "calstand_station");
  const std::string log = dir_ + "calstandd-line-6.log";
  calstand::testing::DaemonProcess daemon(
      s.db, log, "127.0.0.1:0",
      {"--publish", server_->url(s.role, kDbName), "--publish-password-file", server_->passfile(),
       "--publish-name", s.name, "--publish-interval-s", "1", "--publish-samples"});
  ASSERT_GT(daemon.port(), 0) << calstand::testing::read_text(log);
  {
    calstand::store::Database db(s.db);
    s.uuid = calstand::store::station_uuid(db);
  }
  // The server goes away; the station captures on regardless.
  ASSERT_TRUE(server_->stop("fast"));
  setenv("CALSTAND_TOKEN", calstand::testing::kTestToken, 1);
  const std::string at = " --daemon 127.0.0.1:" + std::to_string(daemon.port());
  Result r = run("submit six-position --unit imu0=U-601" + at);
  ASSERT_EQ(r.exit_code, 0) << r.out;
  r = run("watch 1" + at);
  EXPECT_EQ(r.exit_code, 0) << r.out;
  unsetenv("CALSTAND_TOKEN");
  const auto waited_for = [&](const std::function<bool()>& done) {
    for (int i = 0; i < 300; ++i) {
      if (done()) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    return false;
  };
  EXPECT_TRUE(waited_for([&] {
    return calstand::testing::read_text(log).find("failed (2 in a row), retried later") !=
           std::string::npos;
  })) << calstand::testing::read_text(log);
  calstand::testing::ApiClient api(daemon.port());
  nlohmann::json publish = api.get("/station/publish").body;
  EXPECT_GE(publish["failures_in_a_row"].get<int>(), 2) << publish.dump();
  EXPECT_NE(publish["last_error"].get<std::string>().find("central: connect to"), std::string::npos)
      << publish.dump();
  ASSERT_TRUE(server_->start());
  // Back: the next pass copies the run, its events and its samples.
  const auto local = local_counts(s);
  EXPECT_EQ(local.at("runs"), 1);
  EXPECT_TRUE(waited_for([&] { return central_counts(s) == local; }))
      << calstand::testing::read_text(log);
  EXPECT_TRUE(waited_for([&] {
    publish = api.get("/station/publish").body;
    return publish["failures_in_a_row"] == 0;
  })) << publish.dump();
  EXPECT_TRUE(publish["last_error"].is_null()) << publish.dump();
  EXPECT_TRUE(publish["last_success_utc"].is_string()) << publish.dump();
  EXPECT_EQ(daemon.signal_and_wait(SIGTERM), 0);
}

TEST_F(FleetSync, TheDaemonShowsTheFleetReadOnlyAsTheCommandLineDoes) {
  ASSERT_EQ(stations_.size(), 3u) << "needs the stations of the first test";
  const std::string log = dir_ + "calstandd-fleet-view.log";
  calstand::testing::DaemonProcess daemon(
      dir_ + "fleet-view.db", log, "127.0.0.1:0",
      {"--fleet", server_->url(kReader, kDbName), "--fleet-password-file", server_->passfile()});
  ASSERT_GT(daemon.port(), 0) << calstand::testing::read_text(log);
  calstand::testing::ApiClient api(daemon.port());
  const std::string from =
      " --from " + server_->url(kReader, kDbName) + " --password-file " + server_->passfile();
  for (const auto& [path, command] : std::vector<std::pair<std::string, std::string>>{
           {"/fleet", "fleet stations --json"},
           {"/fleet/runs?station=line-1", "fleet runs --json --station line-1"},
           {"/fleet/units?serial=U-SHARED", "fleet units --json --serial U-SHARED"},
           {"/fleet/calibrations", "fleet calibrations --json"},
           {"/fleet/parameters", "fleet parameters --json"}}) {
    const auto reply = api.get(path);
    ASSERT_EQ(reply.status, 200) << path << ": " << reply.body.dump();
    const Result cli = run(command + from);
    ASSERT_EQ(cli.exit_code, 0) << cli.out;
    EXPECT_EQ(reply.body, nlohmann::json::parse(cli.out)) << path;
  }
  // The spread of a parameter per station: U-SHARED's newest record is line-3's, so line-1
  // counts one unit (U-101) and line-3 two.
  const nlohmann::json parameters = api.get("/fleet/parameters").body["parameters"];
  ASSERT_FALSE(parameters.empty());
  std::map<std::string, long long> units_per_station;
  for (const auto& s : parameters[0]["stations"]) {
    units_per_station[s["station"].get<std::string>()] = s["n"].get<long long>();
  }
  EXPECT_EQ(units_per_station["line-1"], 1);
  EXPECT_EQ(units_per_station["line-2"], 1);
  EXPECT_EQ(units_per_station["line-3"], 2);
  EXPECT_EQ(api.get("/fleet/runs?since=2026/01/01").status, 400);
  // Read-only: nothing under /fleet takes a write.
  EXPECT_EQ(api.post("/fleet/runs", "{}").status, 404);
}

TEST_F(FleetSync, APasswordOnTheCommandLineIsRefusedBeforeAnythingIsOpened) {
  const std::string url = "postgresql://station_x:secret@localhost/" + std::string(kDbName);
  const Result r = run("sync --db " + dir_ + "never.db --to " + url);
  EXPECT_EQ(r.exit_code, 2) << r.out;
  EXPECT_NE(r.out.find("--to: the address holds a password"), std::string::npos) << r.out;
  EXPECT_FALSE(std::filesystem::exists(dir_ + "never.db"));
}

}  // namespace
