#pragma once
// The page of `calstand report`: one self-contained HTML document (inline CSS and SVG, no
// script, no external resource).

#include <string>
#include <string_view>

#include "markup_escape.hpp"
#include "report_data.hpp"

namespace calstand::cli {

/// The whole page. Draws its plots with gnuplot: throws core::InputError naming gnuplot when it
/// is missing or fails.
std::string render_report_html(const ReportData& r);


}  // namespace calstand::cli
