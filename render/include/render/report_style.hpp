#pragma once
// The style sheet of calstand's HTML reports (inlined in each page: a report is one file).

#include <cstdint>
#include <string>

namespace calstand::analysis {

/// The CSS of a report page (header, sections, tables, advice boxes, badges).
const char* report_css();

/// The opening of the "Which effect is missing" section: its heading and the advice in a box
/// coloured by whether the model explains the measurements.
std::string advice_section_start(bool explained, const std::string& advice);

/// A whole report page around `body` (its sections): the document head with the title
/// "calstand report: run RUN (PROCEDURE)" and the style sheet, then a footer naming the run and
/// `stamp` (the time of the fit it shows). Text is escaped here.
std::string report_page(std::int64_t run, const std::string& procedure, const std::string& body,
                        const std::string& stamp);

}  // namespace calstand::analysis
