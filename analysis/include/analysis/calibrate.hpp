#pragma once
// The calibration pipeline: a run fitted into a calibration record (calstand calibrate), and a
// record applied to a run's raw samples as a new run (calstand apply). Files are the caller's.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "analysis/table_free_fit.hpp"
#include "solver/calibration_record.hpp"
#include "solver/fit.hpp"
#include "solver/model.hpp"
#include "store/database.hpp"

namespace calstand::analysis {

/// A fitted calibration, not yet stored.
struct CalibrationOutcome {
  std::int64_t run = 0;
  std::string procedure;
  std::string device;
  solver::FitResult fit;  ///< the fit of a run on a table
  /// The fit of a run without a table (table_free_fit.hpp), instead of `fit`.
  std::optional<TableFreeFit> table_free;
  std::size_t steps = 0;        ///< steps fitted
  nlohmann::json record;        ///< schemas/calibration.schema.json, checked against it
  std::int64_t history_id = 0;  ///< the fit's row in the run's history (command "calibrate")
};

/// Fits `model` to both sensors of `run` (device "" = its only IMU), records the fit in the
/// history, and builds the record with the run's noise figures (calibration_noise_figures()).
/// A run without a table is fitted by table_free_fit() instead (`model` read by
/// table_free_model(), the static poses as `poses` says) and recorded by
/// table_free_calibration_record(). With `noise_run`, a table run's steps are weighed by the
/// wander of that static run of the same unit (noise_run.hpp) instead of one estimated from the
/// run itself, and the record's fit says so (its "noise_model"). Throws as fit_request() or
/// table_free_fit(); core::InputError naming --noise-run for a run without a table;
/// std::runtime_error if the record breaks its own schema (a bug).
CalibrationOutcome calibrate_run(store::Database& db, std::int64_t run, const solver::Model& model,
                                 const std::string& device, const TableFreeFitRequest& poses = {},
                                 std::optional<std::int64_t> noise_run = std::nullopt);

/// The units of `run` that `calstand calibrate` calibrates: `device` alone when given, else
/// every IMU with samples (every unit on the fixture), in name order. Throws core::InputError
/// naming the run when it has no samples or `device` has none.
std::vector<std::string> units_to_calibrate(store::Database& db, std::int64_t run,
                                            const std::string& device);

/// Stores the record in the database's calibrations (with the model text of whichever fit) and,
/// for a table fit, its step residuals (step_residuals.hpp) for the certificate; returns its id.
std::int64_t store_calibration(store::Database& db, const CalibrationOutcome& calibration);

/// The record file `calstand calibrate` writes when not told: calibration-run<ID>-<device>.json.
std::string default_calibration_file(std::int64_t run, const std::string& device);

/// A run corrected with a calibration, written as a new run.
struct ApplyOutcome {
  std::int64_t run = 0;  ///< the new run
  std::int64_t source_run = 0;
  std::size_t steps = 0;
  double min_temperature_c = 0.0;  ///< of the source run's samples [degC]
  double max_temperature_c = 0.0;
  /// The samples span more than 1 degC beyond the record's valid range.
  bool outside_valid_range = false;
};

/// Corrects every sample of `run` (device "" = its only IMU) with `calibration` and writes the
/// result as a derived run "corrected <procedure>" (status "corrected", parameters
/// {"calibration": record_name}). Throws as fit_request() for the run.
ApplyOutcome apply_calibration(store::Database& db, std::int64_t run, const std::string& device,
                               const solver::Calibration& calibration,
                               const std::string& record_name);

}  // namespace calstand::analysis
