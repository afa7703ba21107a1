#pragma once
// The page of `calstand report`: one self-contained HTML document (inline CSS and SVG, no
// script, no external resource).

#include <string>
#include <string_view>

#include "render/markup_escape.hpp"
#include "report/report_data.hpp"

namespace calstand::analysis {

/// The whole page. Draws its plots with gnuplot: throws core::InputError naming gnuplot when it
/// is missing or fails.
std::string render_report_html(const ReportData& r);

/// gather_report() and render_report_html() in one: the page of `calstand report` for a run
/// (for a run without a table, table_free_report.hpp's page). Checks for gnuplot first (before
/// any fit is recorded). Throws as both.
std::string run_report_html(store::Database& db, const ReportRequest& request);
}  // namespace calstand::analysis
