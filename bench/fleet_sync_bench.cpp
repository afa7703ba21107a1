// The fleet's sync (issue 19): how fast a station's database reaches the central PostgreSQL
// database, and how long a station that was offline for a day of captures takes to catch up.
// A plain program printing figures, not a Google Benchmark:
//
//   calstand_fleet_sync_bench [--hours H] [--keep DIR] [--station DB]
//
// `--station DB` syncs a station database made before (e.g. by an earlier --keep DIR, as
// DIR/station.db) instead of making one: before-and-after figures on the same station.
// It starts a throw-away PostgreSQL server (tests/support/postgres_server.hpp), makes a station
// database with H hours (default 24) of station time of six-position runs on the simulator
// through the calstand command (each run calibrated: records and fit history), then syncs it
// three times into fresh central databases: rows only (rows/s), samples after the rows
// (samples/s, MB/s), and everything at once (the catch-up time). Ends with one JSON line.
#include <fmt/format.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <pqxx/pqxx>
#include <string>

#include "fleet/central_address.hpp"
#include "fleet/central_schema.hpp"
#include "fleet/sync.hpp"
#include "postgres_server.hpp"
#include "store/database.hpp"

namespace {

using calstand::testing::PostgresServer;

int sh(const std::string& command) { return std::system(command.c_str()); }

/// A fresh central database `name`, migrated, with a station role that syncs into it.
std::unique_ptr<pqxx::connection> fresh_central(PostgresServer& server, const std::string& name) {
  {
    pqxx::connection admin(server.conninfo(PostgresServer::kOwner, "postgres"));
    pqxx::nontransaction tx(admin);
    tx.exec("CREATE DATABASE " + name);
  }
  pqxx::connection owner(server.conninfo(PostgresServer::kOwner, name));
  calstand::fleet::migrate_central(owner);
  return std::make_unique<pqxx::connection>(server.conninfo("bench_station", name));
}

calstand::fleet::SyncReport timed_sync(const std::string& db_path, pqxx::connection& central,
                                       bool samples) {
  calstand::store::Database db(db_path);
  calstand::fleet::SyncOptions options;
  options.station_name = "bench";
  options.samples = samples;
  return calstand::fleet::sync_station(db, central, options);
}

}  // namespace

int main(int argc, char** argv) {
  double hours = 24.0;
  std::string keep;
  std::string given_station;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--hours") {
      hours = std::atof(argv[i + 1]);
    } else if (flag == "--keep") {
      keep = argv[i + 1];
    } else if (flag == "--station") {
      given_station = argv[i + 1];
    } else {
      fmt::print(stderr,
                 "usage: calstand_fleet_sync_bench [--hours H] [--keep DIR] [--station DB]\n");
      return 2;
    }
  }
  const std::string bin_dir = calstand::testing::find_postgres_bin_dir();
  if (bin_dir.empty()) {
    fmt::print(stderr, "no PostgreSQL server (initdb, pg_ctl): apt-get install postgresql\n");
    return 1;
  }
  const std::string dir = keep.empty() ? std::filesystem::temp_directory_path().string() +
                                             "/calstand-fleet-bench-" + std::to_string(::getpid())
                                       : keep;
  std::filesystem::create_directories(dir);
  const std::string db = given_station.empty() ? dir + "/station.db" : given_station;

  // A day at the station: six-position runs back to back, each calibrated.
  const auto made = std::chrono::steady_clock::now();
  double station_s = 0.0;
  int runs = 0;
  if (!given_station.empty()) {
    calstand::store::Database station(db);
    runs = station.sql().execAndGet("SELECT count(*) FROM runs").getInt();
    station_s = station.sql()
                    .execAndGet("SELECT TOTAL(ended_clock_s - started_clock_s) FROM runs")
                    .getDouble();
  }
  while (given_station.empty() && station_s < hours * 3600.0) {
    const std::string run_id = std::to_string(runs + 1);
    if (sh(fmt::format("{} run six-position --quiet --db {} --unit imu0=B-{:04d} > /dev/null",
                       CALSTAND_BIN, db, runs + 1)) != 0 ||
        sh(fmt::format("{} calibrate --db {} --run {} --out-dir {} > /dev/null", CALSTAND_BIN, db,
                       run_id, dir)) != 0) {
      fmt::print(stderr, "making run {} failed\n", run_id);
      return 1;
    }
    ++runs;
    calstand::store::Database station(db);
    station_s +=
        station.sql()
            .execAndGet("SELECT ended_clock_s - started_clock_s FROM runs WHERE id = " + run_id)
            .getDouble();
  }
  const double make_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - made).count();
  fmt::print("station: {} runs, {:.1f} h of station time, {:.0f} MB, made in {:.0f} s\n", runs,
             station_s / 3600.0, static_cast<double>(std::filesystem::file_size(db)) / 1e6, make_s);

  PostgresServer server(bin_dir, dir + "/pg");
  if (!server.error().empty()) {
    fmt::print(stderr, "{}\n", server.error());
    return 1;
  }
  {
    pqxx::connection admin(server.conninfo(PostgresServer::kOwner, "postgres"));
    pqxx::nontransaction tx(admin);
    tx.exec("CREATE DATABASE fleet");
  }
  {
    pqxx::connection owner(server.conninfo(PostgresServer::kOwner, "fleet"));
    calstand::fleet::migrate_central(owner);
    pqxx::nontransaction tx(owner);
    tx.exec("CREATE ROLE bench_station LOGIN PASSWORD 'bench' IN ROLE calstand_station");
    server.add_password("bench_station", "bench");
  }

  // 1. Rows only; 2. then the samples; 3. a station a day behind: everything in one sync.
  auto rows_central = fresh_central(server, "fleet_rows");
  const auto rows = timed_sync(db, *rows_central, false);
  const auto samples = timed_sync(db, *rows_central, true);
  auto catch_up_central = fresh_central(server, "fleet_catch_up");
  const auto catch_up = timed_sync(db, *catch_up_central, true);
  const auto again = timed_sync(db, *catch_up_central, true);

  const double rows_per_s = static_cast<double>(rows.copied.rows()) / rows.seconds;
  const double samples_per_s = static_cast<double>(samples.copied.samples) / samples.seconds;
  const double mb_per_s = static_cast<double>(samples.copied.sample_bytes) / 1e6 / samples.seconds;
  fmt::print(
      "rows: {} (runs {}, steps {}, events {}, units {}, calibrations {}, fits {}) in "
      "{:.2f} s: {:.0f} rows/s\n",
      rows.copied.rows(), rows.copied.runs, rows.copied.steps, rows.copied.events,
      rows.copied.run_units, rows.copied.calibrations, rows.copied.fits, rows.seconds, rows_per_s);
  fmt::print("samples: {} in {} chunks ({:.0f} MB) in {:.2f} s: {:.0f} samples/s, {:.1f} MB/s\n",
             samples.copied.samples, samples.copied.sample_chunks,
             static_cast<double>(samples.copied.sample_bytes) / 1e6, samples.seconds, samples_per_s,
             mb_per_s);
  fmt::print(
      "catch-up after {:.1f} h offline: {:.1f} s ({} transactions); a second sync: "
      "{:.3f} s, {} rows\n",
      station_s / 3600.0, catch_up.seconds, catch_up.copied.transactions, again.seconds,
      again.copied.rows() + again.copied.sample_chunks);
  nlohmann::json line = {{"runs", runs},
                         {"station_hours", station_s / 3600.0},
                         {"rows", rows.copied.rows()},
                         {"rows_per_s", rows_per_s},
                         {"samples", samples.copied.samples},
                         {"samples_per_s", samples_per_s},
                         {"sample_mb_per_s", mb_per_s},
                         {"catch_up_s", catch_up.seconds},
                         {"second_sync_s", again.seconds}};
  fmt::print("{}\n", line.dump());
  if (keep.empty()) std::filesystem::remove_all(dir);
  return again.copied.rows() + again.copied.sample_chunks == 0 ? 0 : 1;
}
