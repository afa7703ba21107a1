#pragma once
// Cells and rows of the report's HTML tables, one definition for report_tables.cpp and
// report_datasheet.cpp (a unity build compiles them as one file).

#include <initializer_list>
#include <string>
#include <string_view>

#include "render/markup_escape.hpp"

namespace calstand::analysis::html_cells {

/// A text cell, its text escaped.
inline std::string td(std::string_view text) { return "<td>" + html_escape(text) + "</td>"; }

/// A row of cells already made.
inline std::string row(std::initializer_list<std::string> cells) {
  std::string out = "<tr>";
  for (const auto& c : cells) out += c;
  return out + "</tr>\n";
}

}  // namespace calstand::analysis::html_cells
