#pragma once
// The plots of `calstand report`, each one gnuplot script rendered to inline SVG (gnuplot_svg()).
// Every function throws core::InputError naming gnuplot when it is missing or fails.

#include <string>
#include <vector>

#include "report/report_data.hpp"

namespace calstand::analysis {

/// chi2/dof of every fit of the run on a log axis, labelled by what each fit added, with the
/// noise floor (chi2/dof = 1) marked.
std::string history_plot(const ReportData& r);

/// Step-mean residual z-scores of each fitted sensor (one panel per sensor, axes by point
/// shape), coloured by the step grouping.
std::string residual_plot(const ReportData& r);

/// z of the signal's channel against the step mean of the signal, coloured by the step
/// grouping, with the least-squares line. `rank` numbers the plot (ids on the page).
/// Returns "" when the signal has no step series.
std::string signal_plot(const ReportData& r, const solver::SignalCorrelation& signal, int rank);

/// chi2/dof after adding each of the best candidates, against the model's.
std::string candidate_plot(const ReportData& r);

/// Allan deviation of the gyro (or accelerometer) channels with their confidence intervals, the
/// fitted IEEE 952 model and its terms. Requires r.noise.
std::string allan_plot(const ReportData& r, bool gyro);
/// The same of a noise analysis held apart from a ReportData (the page of a static record).
std::string allan_plot(const solver::RunNoise& noise, bool gyro);

}  // namespace calstand::analysis
