#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/imu_sample.hpp"
#include "store/database.hpp"
#include "store/records.hpp"

namespace calstand::store {

/// The table state at one sample instant, as the encoders report it. NaN throughout for a
/// step whose orientation is not known (see orientation_known()): no encoder read anything.
struct TableSample {
  double outer_deg = 0.0;
  double inner_deg = 0.0;
  double outer_rate_dps = 0.0;
  double inner_rate_dps = 0.0;
};

/// False for a step whose orientation is not known: one imported from a calstand-import/2
/// folder without table, whose commanded state holds `"orientation": "unknown"` (and `"mode"`
/// "recording", "static" or "turn"; store/import_export.hpp). Such a step has no table rows;
/// its StepData::table reads NaN. True for every recorded step and every /1 import.
bool orientation_known(const StepRecord& step);

/// False when any step of `run` has no known orientation (orientation_known() of the step):
/// the run cannot be fitted by the methods that need the table (their regressors need the
/// reference rate and specific force in the body frame), only by those that need none. Throws
/// core::InputError for an unknown run, StoreError when reading fails.
bool orientation_known(Database& db, std::int64_t run);

/// One completed step's data: its record, the samples of its data attempt, and the table
/// state at each sample (table[i] belongs to samples[i]).
struct StepData {
  StepRecord step;
  std::vector<core::ImuSample> samples;
  std::vector<TableSample> table;
};

/// Every completed step of `run` with samples of `device`, by step index. The table state per
/// sample is NaN when the step's orientation is not known, the stored one when the step holds
/// one table row per sample (imported runs), else
/// interpolated in the table telemetry recorded while the step ran, at the sample's receive
/// time (linear, the turn between rows resolved with the recorded rates; before the first and
/// after the last row, that
/// row advanced at its rates), else the step's commanded state. Throws core::InputError for an
/// unknown run, StoreError when reading fails.
std::vector<StepData> read_step_data(Database& db, std::int64_t run, const std::string& device);

/// As read_step_data(), one step at a time: `use` gets each step's data in turn, and only one
/// step's samples are in memory at once (an export of a long run).
void for_each_step_data(Database& db, std::int64_t run, const std::string& device,
                        const std::function<void(const StepData&)>& use);

/// The device of `run` to analyse: `device` when given (an error when it has no samples), else
/// the run's only IMU with samples (an error when it has none or several). Throws
/// core::InputError naming the run.
std::string choose_device(Database& db, std::int64_t run, const std::string& device);

}  // namespace calstand::store
