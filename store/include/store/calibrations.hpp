#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "store/database.hpp"

namespace calstand::store {

/// A row of table calibrations.
struct CalibrationRow {
  std::int64_t id = 0;
  std::int64_t run = 0;
  std::string imu;
  std::string model;
  nlohmann::json record;
  std::string created_utc;
  std::string serial;  ///< the unit's serial (the record's device.serial); empty when unknown
  /// The station that made it, when read from the fleet's central database (the name it
  /// registered with); empty for a row of a station's own file.
  std::string station;
};

/// Stores a calibration record (schemas/calibration.schema.json) of `imu` fitted on `run`;
/// returns its id. The unit's serial is the record's `device.serial`. Throws core::InputError
/// for an unknown run, StoreError on SQL failure.
/// `step_residuals`, when not null, are stored with it in the same transaction (table
/// calibration_residuals: what the record's certificate draws, so that it need not refit).
std::int64_t insert_calibration(Database& db, std::int64_t run, const std::string& imu,
                                const std::string& model, const nlohmann::json& record,
                                const nlohmann::json& step_residuals = nullptr);

/// The step residuals stored with calibration `id`; none for a record stored without them (made
/// before schema version 7, or without a table). Throws StoreError on SQL failure.
std::optional<nlohmann::json> load_calibration_residuals(Database& db, std::int64_t id);

/// The calibration `id`; throws core::InputError when there is none.
CalibrationRow load_calibration(Database& db, std::int64_t id);

/// The calibrations fitted on `run`, oldest first.
std::vector<CalibrationRow> calibrations_of_run(Database& db, std::int64_t run);

/// The calibrations of the unit `serial`, newest first.
std::vector<CalibrationRow> calibrations_of_serial(Database& db, const std::string& serial);

/// Every calibration created at or after `since_utc` (ISO 8601, compared as text; empty: all),
/// oldest first.
std::vector<CalibrationRow> calibrations_since(Database& db, const std::string& since_utc);

}  // namespace calstand::store
