#pragma once
// The fit and diagnosis of a run as one request (calstand fit|diagnose, POST /runs/{id}/fits
// and /diagnose): one code path, so the command line and the daemon give the same JSON for the
// same run and model.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "solver/diagnose.hpp"
#include "solver/fit.hpp"
#include "solver/groups.hpp"
#include "solver/model.hpp"
#include "solver/step_summary.hpp"
#include "solver/thermal_fit.hpp"
#include "store/database.hpp"

namespace calstand::analysis {

/// What to fit to a run.
struct FitRequest {
  solver::Model model;          ///< parsed: Model::parse() or model_from_lists()
  std::string device;           ///< "" = the run's only IMU
  std::string sensor = "both";  ///< rows to fit: both, gyro or accel
  bool white_noise = false;     ///< weights from the white noise alone (no wandering bias)
  /// The wander from this static run of the same unit (noise_run.hpp) instead of one
  /// estimated from the run's own step means; white_noise takes precedence.
  std::optional<std::int64_t> noise_run;
  /// The command recorded in the fit history ("fit", "diagnose"); empty: not recorded.
  std::string history_command;
};

/// A whole-run fit with where it fails.
struct FitOutcome {
  std::int64_t run = 0;
  std::string procedure;  ///< the run's procedure name
  std::string device;     ///< the IMU fitted
  solver::FitResult fit;
  std::vector<solver::StepSummary> steps;    ///< in fit order
  std::vector<solver::GroupQuality> groups;  ///< worst first
  std::vector<solver::WorstStep> worst;      ///< worst single residuals
  std::optional<std::int64_t> history_id;    ///< the history row written, if any
};

/// Loads the run (load_fit_data()), fits the model by generalised least squares with the run's
/// noise model, finds the groups of steps where it fails, and records the fit in the run's
/// history when `request.history_command` is set. Throws RunNotFound, NothingToFit, or
/// core::InputError for a bad device or sensor.
FitOutcome fit_request(store::Database& db, std::int64_t run, const FitRequest& request);

/// `calstand fit --json`: the fit (solver::fit_to_json) with its groups and worst steps.
nlohmann::json to_json(const FitOutcome& outcome);

/// A diagnosis: the model's fit, the candidate terms, the signals the residual follows and
/// custom terms suggested.
struct DiagnoseOutcome {
  std::int64_t run = 0;
  std::string procedure;
  std::string device;
  solver::Diagnosis diagnosis;
  std::optional<std::int64_t> history_id;
};

/// As fit_request() with solver::diagnose() (request.white_noise is not used: a diagnosis
/// weighs as the solver's diagnosis does).
DiagnoseOutcome diagnose_request(store::Database& db, std::int64_t run, const FitRequest& request);

/// `calstand diagnose --json` (solver::diagnosis_to_json).
nlohmann::json to_json(const DiagnoseOutcome& outcome);

/// The classical thermal calibration of a run: the model fitted on each temperature plateau,
/// each weighed with the run's own noise model, then a polynomial of `order` in dT per bias.
struct PlateauFitOutcome {
  std::int64_t run = 0;
  std::string procedure;
  std::string device;
  solver::ThermalFitResult result;
};

/// Throws as fit_request(); never records history.
PlateauFitOutcome plateau_fit_request(store::Database& db, std::int64_t run,
                                      const FitRequest& request, int order);

}  // namespace calstand::analysis
