#pragma once
// The report's datasheet figures as HTML: which analyses of the test catalogue the run supports
// (run_analyses.hpp), then each one's figures in datasheet units with their intervals, and its
// plot.

#include <string>

#include "report/report_data.hpp"

namespace calstand::analysis {

/// A value in a fitted parameter's unit as a datasheet states it: deg/s as deg/h, m/s^2 as ug;
/// other units as they are.
struct ParameterScale {
  double factor = 1.0;  ///< datasheet value = factor * value
  std::string unit;
};
ParameterScale parameter_scale(const std::string& unit);

/// A figure as the datasheet sections write it: `digits` significant digits, in plain notation
/// from 0.001 to below 1e6 ("1460", "0.0123"), else in exponent notation ("1.23e-05").
std::string datasheet_number(double value, int digits = 3);

/// Section "datasheet": one row per analysis of the catalogue: shown below (and what in the run
/// it comes from), missing (the run looks like it should have it, and why the analysis refused
/// it) or not applicable (what the run lacks).
std::string datasheet_overview_section(const DatasheetAnalyses& a);

/// One section per analysis with a result, in kDatasheetKinds order ("datasheet-KIND"): its
/// figures (datasheet_number(); intervals as "lo &ndash; hi") and its plot. Draws
/// with gnuplot: throws core::InputError naming gnuplot when it is missing or fails.
std::string datasheet_sections(const ReportData& r);

/// Section "datasheet-stability" alone: the Allan floor and the bias model of each channel
/// (also on the page of a static record).
std::string stability_section(const StabilityAnalysis& s);

}  // namespace calstand::analysis
