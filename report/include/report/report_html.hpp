#pragma once
// The page of `calstand report`: one self-contained HTML document (inline CSS and SVG, no
// script, no external resource).

#include <optional>
#include <string>
#include <string_view>

#include "render/markup_escape.hpp"
#include "report/report_data.hpp"
#include "report/static_report.hpp"
#include "report/table_free_report.hpp"

namespace calstand::analysis {

/// The whole page. Draws its plots with gnuplot: throws core::InputError naming gnuplot when it
/// is missing or fails.
std::string render_report_html(const ReportData& r);

/// The page a run gets, with its data: exactly one member is set.
struct ReportPage {
  std::optional<ReportData> table;                ///< a run on a table (gather_report())
  std::optional<TableFreeReportData> table_free;  ///< a run without a table, calibrated
  std::optional<StaticReportData> static_record;  ///< a record at rest (static_report.hpp)
};

/// Gathers the page of `calstand report` for a run: a run on a table gets gather_report(); a
/// run without a table that lies at rest throughout the static page at once (no fit tried); any
/// other run without a table its table-free report, or, when that fit is refused for what the
/// run lacks (too few static poses, no initial rest: a core::InputError of its own type, not
/// about the model), the static page saying why, with the noise of its longest record at rest.
/// Throws as the gatherers; the refusal itself when the run has no record at rest either.
ReportPage gather_report_page(store::Database& db, const ReportRequest& request);

/// The HTML of the page gathered.
std::string render_report_page(const ReportPage& page);

/// gather_report_page() and render_report_page() in one: the page of `calstand report` and of
/// GET /runs/{id}/report. Checks for gnuplot first (before any fit is recorded). Throws as both.
std::string run_report_html(store::Database& db, const ReportRequest& request);
}  // namespace calstand::analysis
