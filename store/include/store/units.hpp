#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "store/database.hpp"
#include "store/records.hpp"

namespace calstand::store {

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
