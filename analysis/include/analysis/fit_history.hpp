#pragma once
// A run's fit history (calstand history, GET /runs/{id}/history): what a fit leaves in it, and
// the history as JSON.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "solver/fit.hpp"
#include "solver/model.hpp"
#include "store/database.hpp"
#include "store/fit_history.hpp"

namespace calstand::analysis {

/// The history row of a fit: run, device, the command that made it ("fit", "diagnose",
/// "calibrate", "report", "api"...), the model text and custom terms, the rows fitted
/// (`sensors`: both, gyro or accel), parameter count, chi2/dof and the residual rms of the
/// fitted rows only (the others stay empty).
store::FitRecord history_record(std::int64_t run, const std::string& device,
                                const std::string& command, const solver::Model& model,
                                const solver::FitResult& fit, const std::string& sensors);

/// Appends history_record(...) to the run's history; returns the new row's id. The caller has
/// checked the run (store::record_fit does not refuse an unknown run).
std::int64_t record_history(store::Database& db, std::int64_t run, const std::string& device,
                            const std::string& command, const solver::Model& model,
                            const solver::FitResult& fit, const std::string& sensors);

/// `calstand history --json`: an array of the fits, oldest first (id, command, model,
/// custom_terms, sensors, parameters, chi2_dof, rms_gyro_dps, rms_accel_mps2, time; missing
/// figures null).
nlohmann::json history_to_json(const std::vector<store::FitRecord>& fits);

}  // namespace calstand::analysis
