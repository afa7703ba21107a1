#pragma once
// Copying a station's SQLite file to the fleet's central database (`calstand sync`, the
// daemon's --publish): idempotent and resumable by cursors kept in the central database.

#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <pqxx/connection>
#include <string>
#include <vector>

#include "store/database.hpp"

namespace calstand::fleet {

/// The SQLite schema version this sync reads (store/schema.sql). A station file at another
/// version is refused by name rather than copied half understood: a new store migration is
/// mapped to the central schema (a new central migration) before stations sync it. Version 7
/// added only `calibration_residuals` (the step residuals a certificate is printed from), which
/// stays at the station: certificates are printed where the unit was calibrated, and the
/// central database answers lots and trends from the records themselves.
inline constexpr int kSyncedStoreSchemaVersion = 7;

struct SyncOptions {
  /// The name the station registers with on its first sync (later syncs keep the registered
  /// one); what `calstand fleet --station` matches besides the uuid.
  std::string station_name;
  /// Copy the sample chunks of the copied runs too (as stored: a central analysis can refit).
  bool samples = false;
  /// Rows (runs with their steps, events and units; records; fits) per central transaction.
  std::size_t batch_rows = 2000;
  /// Sample chunks per central transaction.
  std::size_t batch_chunks = 64;
  /// Asked between transactions: true stops the sync there (the daemon shutting down).
  std::function<bool()> stop_requested;
  /// Throws core::InputError naming the field: empty station_name, zero batch sizes.
  void validate() const;
};

/// What one sync copied.
struct SyncCounts {
  std::int64_t runs = 0;
  std::int64_t steps = 0;
  std::int64_t events = 0;
  std::int64_t run_units = 0;
  std::int64_t calibrations = 0;
  std::int64_t acceptances = 0;
  std::int64_t fits = 0;
  std::int64_t step_means = 0;
  std::int64_t table_telemetry = 0;
  std::int64_t chamber_telemetry = 0;
  std::int64_t station_events = 0;  ///< events of no run (a run's go with it: `events`)
  std::int64_t sample_chunks = 0;
  std::int64_t samples = 0;  ///< IMU samples in the chunks copied
  std::int64_t sample_bytes = 0;
  std::int64_t transactions = 0;  ///< central transactions committed
  /// Rows of every table but samples.
  std::int64_t rows() const {
    return runs + steps + events + run_units + calibrations + acceptances + fits + step_means +
           table_telemetry + chamber_telemetry + station_events;
  }
};

struct SyncReport {
  std::string station_uuid;
  std::string station_name;  ///< as registered centrally
  SyncCounts copied;
  /// Local runs not copied because they have not ended (running, paused, interrupted, queued):
  /// they, their records and fits follow once they end.
  std::vector<std::int64_t> waiting_runs;
  double seconds = 0.0;
  bool stopped = false;  ///< SyncOptions::stop_requested ended it early
};

/// Copies what the central database lacks of station file `station` (runs that have ended,
/// with steps, events, units, parameters and procedure text; their step means and table and
/// chamber telemetry; station-wide events; calibration records; acceptance verdicts; fit
/// history; sample chunks when asked, by binary COPY through a staging table), registering the
/// station on its first sync. Each batch is one central transaction together with the move of its
/// cursor, so a sync cut anywhere (server gone, process killed) loses nothing and the next one
/// resumes there; rows already central are never copied twice (a second sync copies nothing).
/// Concurrent syncs of one station serialise on an advisory lock; of different stations, run side
/// by side.
///
/// Throws core::InputError for bad options, store::StoreError when the station file fails or
/// is at another schema version than kSyncedStoreSchemaVersion, CentralError when the central
/// database does (unreachable, at another central schema version, the station id registered to
/// another role).
SyncReport sync_station(store::Database& station, pqxx::connection& central,
                        const SyncOptions& options);

/// `{"station": {"uuid", "name"}, "copied": {"runs", "steps", "events", "run_units",
///   "calibrations", "acceptances", "fits", "step_means", "table_telemetry",
///   "chamber_telemetry", "station_events", "sample_chunks", "samples", "sample_bytes",
///   "transactions"}, "waiting_runs": [local id...], "seconds", "stopped"}`
nlohmann::json to_json(const SyncReport& report);

}  // namespace calstand::fleet
