#pragma once
// The step residuals of a table fit as a calibration record keeps them beside it (store table
// calibration_residuals, schema version 7): what the record's certificate draws, so that a
// certificate reads the fit that made the record instead of fitting the model again.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "solver/fit.hpp"

namespace calstand::analysis {

/// The format name the stored document carries.
inline constexpr const char* kStepResidualsFormat = "calstand-step-residuals/1";

/// {"format": kStepResidualsFormat, "steps": [{"index", "label", "residual": [gx, gy, gz, ax, ay,
/// az], "sigma": [...]}]}: per fitted step its mean's residual and that mean's noise, in deg/s
/// and m/s^2 (a channel the fit left out: null).
nlohmann::json step_residuals_json(const solver::FitResult& fit);

/// The steps of a document step_residuals_json() wrote: index, label, residual and sigma set
/// (NaN for null), the other fields of StepResidual left at their defaults. Throws
/// core::InputError naming `where` and the field for another format or a malformed step.
std::vector<solver::StepResidual> step_residuals_from_json(const nlohmann::json& doc,
                                                           const std::string& where);

}  // namespace calstand::analysis
