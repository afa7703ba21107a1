#pragma once
// The tables of `calstand report` as HTML fragments.

#include <string>
#include <string_view>

#include "report/report_data.hpp"

namespace calstand::analysis {

/// Every fit of the run: time, command, parameters, chi2/dof, residual rms, model.
std::string history_table(const ReportData& r);

/// The groups of steps where the model fails, worst first, and the worst single residuals.
std::string groups_table(const ReportData& r);

/// The signals the residuals follow, strongest first.
std::string signals_table(const ReportData& r);

/// Fit quality against the noise floor, per channel.
std::string quality_table(const ReportData& r);

/// Fitted parameters with sigmas and units, then those the run cannot determine and why.
std::string parameter_tables(const ReportData& r);

/// The candidate terms, best first, with what each is.
std::string candidates_table(const ReportData& r);

/// Which estimator gives the noise figure `name` (solver::DatasheetFigure::name), in words: read
/// off the Allan curve (its minimum) or the IEEE Std 952 model fitted to it.
std::string noise_figure_estimator(std::string_view name);

/// The noise figures of the static step's gyros (or accelerometers) in datasheet units, per
/// channel.
std::string noise_figures_table(const ReportData& r, bool gyro);
/// The same of a noise analysis held apart from a ReportData (the page of a static record).
std::string noise_figures_table(const solver::RunNoise& noise, bool gyro);

}  // namespace calstand::analysis
