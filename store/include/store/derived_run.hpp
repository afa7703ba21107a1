#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "store/database.hpp"
#include "store/step_data.hpp"

namespace calstand::store {

/// A run computed from another one (e.g. its samples corrected with a calibration record):
/// the same station snapshot and steps, new samples.
struct DerivedRun {
  std::int64_t source_run = 0;
  std::string procedure_name;                            ///< e.g. "corrected six-position"
  std::string status = "derived";                        ///< runs.status of the new run
  nlohmann::json parameters = nlohmann::json::object();  ///< what it was derived with
  std::string device = "imu0";
  std::vector<StepData> steps;  ///< completed steps with their samples and table state
};

/// Writes `derived` as a new run in one transaction: the source run's procedure and station
/// snapshot, one completed step per entry (index, kind, label, commanded state and origin kept),
/// exact (float64) sample chunks, the table state of every sample and the step means. Returns
/// the new run id. Throws core::InputError for an unknown source run, StoreError when writing
/// fails (nothing is written then).
std::int64_t write_derived_run(Database& db, const DerivedRun& derived);

}  // namespace calstand::store
