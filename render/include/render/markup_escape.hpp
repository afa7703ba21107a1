#pragma once
// Escaping text for HTML and inline SVG (the report's page and its gnuplot plots).

#include <string>
#include <string_view>

namespace calstand::analysis {

/// `text` with & < > " replaced by their entities: safe in element content and in attribute
/// values of HTML and XML alike.
std::string html_escape(std::string_view text);

}  // namespace calstand::analysis
