#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "store/database.hpp"

namespace calstand::store {

/// The unit in one IMU slot of a run (table run_units).
struct RunUnit {
  std::string imu;     ///< the slot's name at the station, e.g. imu0
  std::string model;   ///< model or spec sheet name; empty when unknown
  std::string serial;  ///< serial number; empty when nobody knows it
  /// Where the serial came from: "device" (read from the unit), "submitted" (given with the
  /// run, `--unit imu0=SN`), or "station" (fixed in the station file).
  std::string source = "station";
};

/// Stores the units of `run`, replacing what was stored for the same slots (a resume reads the
/// devices again). Throws StoreError on SQL failure.
void record_run_units(Database& db, std::int64_t run, const std::vector<RunUnit>& units);

/// The units of `run` in slot-name order; empty for a run made before units were recorded.
std::vector<RunUnit> units_of_run(Database& db, std::int64_t run);

/// The unit in slot `imu` of `run`, or one with only the slot's name when none was recorded.
RunUnit unit_of_run(Database& db, std::int64_t run, const std::string& imu);

/// The runs that measured the unit `serial`, oldest first.
std::vector<std::int64_t> runs_of_serial(Database& db, const std::string& serial);

}  // namespace calstand::store
