#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "store/acceptances.hpp"
#include "store/calibrations.hpp"
#include "store/database.hpp"

namespace calstand::store {

/// Where the factory line's analyses (lot, trend, a unit's records) read calibration records
/// and their verdicts: a station's SQLite file (DatabaseRecords) or the fleet's central
/// PostgreSQL database (fleet::CentralRecords). One interface, so the analyses are written
/// once and give the same answer on either.
///
/// Calibration ids are the source's own: local ids on a station file, central ids on the
/// central database (where each row also names its station, and its run is that station's
/// own run id). Errors as the implementation says
/// (StoreError from SQLite, fleet::CentralError from PostgreSQL).
class RecordSource {
 public:
  virtual ~RecordSource() = default;
  /// Every calibration created at or after `since_utc` (ISO 8601, compared as text; empty:
  /// all), oldest first.
  virtual std::vector<CalibrationRow> calibrations_since(const std::string& since_utc) = 0;
  /// The calibrations of the unit `serial`, newest first.
  virtual std::vector<CalibrationRow> calibrations_of_serial(const std::string& serial) = 0;
  /// The latest judgement of calibration `calibration` (an id of this source), if any.
  virtual std::optional<AcceptanceRow> latest_acceptance(std::int64_t calibration) = 0;
};

/// The records of a station's SQLite database. `db` must outlive it; not thread safe.
class DatabaseRecords : public RecordSource {
 public:
  explicit DatabaseRecords(Database& db) : db_(db) {}
  std::vector<CalibrationRow> calibrations_since(const std::string& since_utc) override {
    return store::calibrations_since(db_, since_utc);
  }
  std::vector<CalibrationRow> calibrations_of_serial(const std::string& serial) override {
    return store::calibrations_of_serial(db_, serial);
  }
  std::optional<AcceptanceRow> latest_acceptance(std::int64_t calibration) override {
    return store::latest_acceptance(db_, calibration);
  }

 private:
  Database& db_;
};

}  // namespace calstand::store
