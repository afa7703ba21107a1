#pragma once
// The style sheet of calstand's HTML reports (inlined in each page: a report is one file).

namespace calstand::analysis {

/// The CSS of a report page (header, sections, tables, advice boxes, badges).
const char* report_css();

}  // namespace calstand::analysis
