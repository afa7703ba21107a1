#pragma once
// What `calstand fleet` asks the central database: runs, units and calibration records of
// every station, filtered by station, unit and date.

#include <nlohmann/json.hpp>
#include <pqxx/connection>
#include <string>

namespace calstand::fleet {

/// Filters of a fleet query; empty fields do not filter.
struct FleetFilter {
  std::string station;    ///< a station's registered name or its uuid
  std::string serial;     ///< a unit's serial
  std::string since_utc;  ///< created at or after: YYYY-MM-DD or YYYY-MM-DDTHH:MM[:SS] (UTC)
  /// Throws core::InputError naming `--since` for a malformed date (analysis::check_lot_since).
  void validate() const;
};

/// The stations registered, by name: `{"stations": [{"name", "uuid", "registered_utc", "runs",
/// "last_run_utc" (null), "last_run_status" (null), "calibrations", "units"}]}`. `station`
/// keeps one. Throws CentralError.
nlohmann::json fleet_stations(pqxx::connection& connection, const FleetFilter& filter);

/// Runs of the fleet, newest first: `{"runs": [{"station", "station_uuid", "run" (local id),
/// "central_id", "procedure", "status", "created_utc", "started_utc", "ended_utc" (null when
/// none), "exit_reason" (null), "steps_done", "steps_total", "units": [{"imu", "model",
/// "serial"}]}]}`. `serial` keeps the runs that measured that unit. Throws CentralError.
nlohmann::json fleet_runs(pqxx::connection& connection, const FleetFilter& filter);

/// Units of the fleet by serial: `{"units": [{"serial", "model", "stations": [name...],
/// "runs", "calibrations", "last_run_utc", "latest_verdict" (of its newest record; null when
/// never judged)}]}`, by serial. Units without a serial are left out. `since`: units with a run
/// created since then. Throws CentralError.
nlohmann::json fleet_units(pqxx::connection& connection, const FleetFilter& filter);

/// The distribution of each calibration parameter across the stations: every unit's newest
/// record (as `calstand lot` counts a unit once), grouped by the station that made it:
/// `{"parameters": [{"name", "unit", "stations": [{"station", "n", "mean", "std" (null for one
/// unit), "min", "max"}]}]}`, parameters and stations by name. `since`: records made since
/// then; `station`, `serial` narrow the records. Throws CentralError.
nlohmann::json fleet_parameters(pqxx::connection& connection, const FleetFilter& filter);

/// Calibration records of the fleet, newest first, the one in force per unit marked across
/// every station (analysis::unit_records on the central database), then filtered by station
/// and date: analysis::unit_records_json's shape, each record with its "station".
/// Throws CentralError.
nlohmann::json fleet_calibrations(pqxx::connection& connection, const FleetFilter& filter);

}  // namespace calstand::fleet
