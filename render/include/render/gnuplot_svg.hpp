#pragma once
// Plots drawn by gnuplot's svg terminal, made fit to inline in an HTML page.

#include <string>
#include <string_view>
#include <vector>

namespace calstand::analysis {

/// The gnuplot binary on PATH. Throws core::InputError naming gnuplot when there is none.
std::string find_gnuplot();

/// Runs `script` (a whole gnuplot script that sets the svg terminal and plots data blocks, no
/// output file) through gnuplot and returns its SVG ready to inline in HTML: no XML prolog, no
/// namespace declarations (HTML needs none, and they look like external URLs), xlink:href as
/// href, every id and reference prefixed with `id_prefix` so that several plots share a page,
/// and `title` as the SVG's title. Throws core::InputError naming gnuplot when it is missing or
/// fails (its error message is quoted). Not thread safe (temporary files, one gnuplot process).
std::string gnuplot_svg(const std::string& script, const std::string& id_prefix,
                        const std::string& title);

/// `text` as a gnuplot double-quoted string, quotes included (also usable as a data column).
/// Safe for any text: a backquote, which gnuplot would run as a shell command even inside
/// double quotes, is written as an escape.
std::string gnuplot_quote(std::string_view text);

/// `text` as a text column of a data block: double-quoted, its own double quotes made single
/// (gnuplot reads no escapes in data).
std::string data_text(std::string_view text);

/// A gnuplot data block `$name << EOD ... EOD` of pre-formatted rows (columns separated by
/// spaces; text columns through gnuplot_quote()).
std::string data_block(std::string_view name, const std::vector<std::string>& rows);

/// A number for a data block: shortest round-trip form, or "NaN" (gnuplot skips it).
std::string gp_number(double value);

/// The svg terminal of calstand's plots, `width` x `height` pixels, with its borders, grid and
/// tics in the pages' colours (one look on every page).
std::string svg_terminal(int width, int height);

/// A dashed horizontal reference line across the graph at y (dash type `dash`, colour `rgb`).
std::string horizontal_line(double y, const char* rgb, int dash);

}  // namespace calstand::analysis
