#pragma once
// As found and as left: how far a unit had moved from the record in force before its new
// calibration (drift between calibrations), parameter by parameter in units of the combined
// uncertainty of both records.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "store/calibrations.hpp"
#include "store/database.hpp"

namespace calstand::analysis {

/// The record of unit `calibration.serial` that was in force before `calibration`: the newest
/// record of that serial older than it (by calstand's order, newest first) and from another run,
/// whose latest acceptance is neither fail nor indeterminate (a record never judged counts as
/// in force: the station had nothing against it). None for a unit without a serial or without
/// an earlier record in force.
std::optional<store::CalibrationRow> record_in_force_before(
    store::Database& db, const store::CalibrationRow& calibration);

/// One parameter in both records.
struct ParameterDrift {
  std::string parameter;
  std::string unit;
  double old_value = 0.0;       ///< in the record in force (what the unit was corrected with)
  double new_value = 0.0;       ///< in the new record (what the unit is now)
  double difference = 0.0;      ///< new_value - old_value [unit]
  double combined_sigma = 0.0;  ///< sqrt(sigma_found^2 + sigma_left^2) [unit]
  /// difference / combined_sigma: beyond about 3 the unit has moved more than both
  /// calibrations' uncertainties explain; NaN when both sigmas are 0.
  double difference_sigmas = 0.0;
};

/// The drift of a unit: the record it was found with and every parameter both records hold
/// (in the new record's order). Parameters only one record holds are listed by name.
struct AsFound {
  std::int64_t calibration = 0;  ///< the record in force
  std::int64_t run = 0;
  std::string created_utc;
  std::string verdict;  ///< its latest acceptance ("pass"), or "" when never judged
  std::vector<ParameterDrift> parameters;
  std::vector<std::string> only_old;  ///< in the record in force only
  std::vector<std::string> only_new;  ///< in the new record only
};

/// The drift from `found` (the record in force) to `left` (the new record).
AsFound compare_records(const store::CalibrationRow& found, const store::CalibrationRow& left);

/// record_in_force_before() and compare_records(), or none.
std::optional<AsFound> as_found(store::Database& db, const store::CalibrationRow& calibration);

/// {"calibration", "run", "created_utc", "verdict" (null when never judged), "parameters":
/// [{"parameter", "unit", "old_value", "new_value", "difference", "combined_sigma",
/// "difference_sigmas"}], "only_old", "only_new"}.
nlohmann::json to_json(const AsFound& drift);

}  // namespace calstand::analysis
