#pragma once
// A unit's calibration records across runs, and which one is in force: what a factory looks up
// by serial number (`calstand calibrations`); acceptance's as-found (as_found.hpp) uses the same
// rule for the record in force before a recalibration.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "store/acceptances.hpp"
#include "store/calibrations.hpp"
#include "store/database.hpp"
#include "store/record_source.hpp"

namespace calstand::analysis {

/// One calibration record with its latest acceptance verdict.
struct UnitRecord {
  store::CalibrationRow calibration;
  std::optional<store::AcceptanceRow> acceptance;  ///< none when never judged
  bool in_force = false;  ///< the record the unit's correction should use now
};

/// Whether a record may be in force: it passed its latest acceptance, or was never judged (a
/// lab without a specification). A failed or indeterminate record is never put in force.
bool may_be_in_force(const std::optional<store::AcceptanceRow>& acceptance);

/// The records of unit `serial`, newest first; the newest that may be in force is marked.
/// Empty `serial`: every record in the database, newest first, one in force per serial (none
/// for records without a serial: nobody knows which unit they belong to).
std::vector<UnitRecord> unit_records(store::RecordSource& records, const std::string& serial);
/// The same on a station's own file.
std::vector<UnitRecord> unit_records(store::Database& db, const std::string& serial);

/// `{"id", "run", "imu", "serial", "model", "created_utc", "verdict" (or null), "spec" (or null),
///   "in_force", "station" (central database only)}`, the record itself left out (GET
///   /calibrations/{id} has it).
nlohmann::json to_json(const UnitRecord& record);

/// `{"serial", "calibrations": [to_json(record), ...]}`: the lookup of unit `serial` (empty:
/// every record) as `calstand calibrations --json` prints it and GET /units/{serial}/calibrations
/// answers it.
nlohmann::json unit_records_json(const std::string& serial, const std::vector<UnitRecord>& records);

}  // namespace calstand::analysis
