#pragma once
// The validation run of acceptance: the unit measured again, corrected with its new record
// (apply_calibration()), and the terms fitted to what remains. A record that holds leaves
// biases and scale factors at zero within their sigmas.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>

#include "factory/acceptance_spec.hpp"
#include "store/calibrations.hpp"
#include "store/database.hpp"

namespace calstand::analysis {

/// What remains after the correction.
struct ValidationFit {
  std::int64_t run = 0;            ///< the validation run
  std::int64_t corrected_run = 0;  ///< its copy corrected with the record (a derived run)
  std::string model;               ///< the terms fitted (Model::text())
  /// The fit in the shape of a calibration record's parameters, unidentifiable and fit blocks,
  /// so that judge_limits() reads it as it reads a record.
  nlohmann::json residual_record;
};

/// Corrects `device`'s samples of `validation_run` with `calibration`'s record as a derived
/// run, and fits `spec.model` (empty: the record's model) to it, recording the fit in that
/// run's history (command "accept"). Throws RunNotFound / NothingToFit for the validation run,
/// core::InputError naming `--validation-run` when that run is the calibrated run itself, has
/// no such device, holds another unit (serials known and different), or was recorded without a
/// table (not supported).
ValidationFit fit_validation_run(store::Database& db, const store::CalibrationRow& calibration,
                                 std::int64_t validation_run, const ValidationSpec& spec);

}  // namespace calstand::analysis
