#pragma once
// The page of `calstand report` (and GET /runs/{id}/report) for a run without a table: the
// table-free fit of the model, how the error fell over the run's fits, where the model fails
// (|f| - g per static pose, the gravity direction after each turn, each against its noise), the
// parameters, the candidate terms with the advice, and the static poses found.

#include <string>
#include <vector>

#include "analysis/table_free_diagnose.hpp"
#include "report/report_data.hpp"
#include "store/database.hpp"
#include "store/fit_history.hpp"

namespace calstand::analysis {

struct TableFreeReportData {
  ReportRequest request;
  std::string procedure;
  TableFreeDiagnosis diagnosis;  ///< of the model asked for (recorded as "report")
  std::vector<store::FitRecord> history;
};

/// Diagnoses the request's model on `run` (the static poses by the detector), records the fit in
/// the history (command "report") and reads the history. Throws as diagnose_table_free(), and
/// core::InputError (where "model") for terms such a run cannot fit.
TableFreeReportData gather_table_free_report(store::Database& db, const ReportRequest& request);

/// The whole page (inline CSS and SVG). Draws its plots with gnuplot: throws core::InputError
/// naming gnuplot when it is missing or fails.
std::string render_table_free_report_html(const TableFreeReportData& r);

}  // namespace calstand::analysis
