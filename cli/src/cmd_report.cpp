// `calstand report`: one self-contained HTML page of a run's fit: how the error fell over the
// fits of the run, where the model fails, what the residual follows, the parameters, the
// candidate terms, the datasheet figures that apply and, for a static run, the Allan deviation
// with its fitted noise lines. A run without an error model gets its summary and figures.
#include <fmt/format.h>

#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <typeinfo>
#include <vector>

#include "commands.hpp"
#include "core/error.hpp"
#include "fit_printer.hpp"
#include "open_database.hpp"
#include "render/gnuplot_svg.hpp"
#include "report/report_data.hpp"
#include "report/report_html.hpp"
#include "report/table_free_report.hpp"

namespace calstand::cli {
namespace {

struct ReportOptions {
  analysis::ReportRequest request;
  std::string out;
};

void write_page(const std::string& path, const std::string& page) {
  std::ofstream out(path, std::ios::binary);
  if (!out || !(out << page) || !out.flush()) {
    throw core::InputError("--out " + path, "cannot write the report");
  }
}

void run_report(const ReportOptions& opt) {
  analysis::find_gnuplot();  // before the work: a missing plotter is the first thing to say
  store::Database db = open_existing_database(opt.request.db);
  if (analysis::needs_table_free_fit(db, opt.request.run)) {
    std::optional<analysis::TableFreeReportData> gathered;
    try {
      gathered = analysis::gather_table_free_report(db, opt.request);
    } catch (const core::InputError& e) {
      if (typeid(e) != typeid(core::InputError)) throw;  // RunNotFound and the like as they are
      // A static recording (an imported bag at rest) has no poses to calibrate from: say what
      // its record is good for instead of only what the fit lacks.
      throw core::InputError(
          "", fmt::format("{}; the report of a run without a table is its table-free "
                          "calibration. A static record's noise is `calstand noise --run {}` "
                          "(and `calstand analyze stability`)",
                          e.what(), opt.request.run));
    }
    const analysis::TableFreeReportData& data = *gathered;
    const std::string page = analysis::render_table_free_report_html(data);
    write_page(opt.out, page);
    fmt::print(
        "{}: run {} ({}) without a table, method {}, model {}: {}; {} fits in the "
        "history; {} kB\n",
        opt.out, data.request.run, data.procedure, data.diagnosis.fit.method,
        analysis::table_free_model_text(data.diagnosis.fit.terms),
        data.diagnosis.explained ? "explained" : "not explained", data.history.size(),
        (page.size() + 512) / 1024);
    return;
  }
  const analysis::ReportData data = analysis::gather_report(db, opt.request);
  const std::string page = analysis::render_report_html(data);
  write_page(opt.out, page);
  std::string figures;
  for (const auto kind : analysis::kDatasheetKinds) {
    if (data.datasheet.has_result(kind)) {
      figures += fmt::format("{}{}", figures.empty() ? "" : ", ", analysis::to_string(kind));
    } else if (data.datasheet.applicability_of(kind).applies) {
      figures +=
          fmt::format("{}{} missing", figures.empty() ? "" : ", ", analysis::to_string(kind));
    }
  }
  figures = figures.empty() ? "" : "; datasheet figures: " + figures;
  if (!data.fitted()) {
    fmt::print("{}: run {} ({}), no error model fitted: {}{}{}; {} kB\n", opt.out, data.request.run,
               data.procedure, data.no_fit_reason, figures,
               data.noise ? ", Allan deviation of the static step" : "",
               (page.size() + 512) / 1024);
    return;
  }
  fmt::print("{}: run {} ({}), model {}: chi2/dof {:.3g}, {} fits in the history{}{}; {} kB\n",
             opt.out, data.request.run, data.procedure, data.diagnosis.fit.model,
             data.diagnosis.fit.chi2_dof, data.history.size(), figures,
             data.noise ? ", Allan deviation of the static step" : "", (page.size() + 512) / 1024);
}

}  // namespace

void register_report(CLI::App& app) {
  auto opt = std::make_shared<ReportOptions>();
  auto* cmd = app.add_subcommand(
      "report",
      "One self-contained HTML page of a run's fit: history, residuals, signals, "
      "parameters, candidates, datasheet figures, Allan deviation (plots by gnuplot)");
  cmd->add_option("--db", opt->request.db, "Database file")->required();
  cmd->add_option("--run", opt->request.run, "Run id")->required();
  cmd->add_option("--model", opt->request.model, "Comma-separated error terms")
      ->capture_default_str();
  cmd->add_option("--custom", opt->request.customs, "A custom term NAME=SENSOR:EXPR, repeatable");
  cmd->add_option("--device", opt->request.device, "IMU (default: the run's only IMU)");
  cmd->add_option("--sensor", opt->request.sensor, "Rows to fit: both, gyro or accel")
      ->check(CLI::IsMember({"both", "gyro", "accel"}))
      ->capture_default_str();
  cmd->add_option("--out", opt->out, "The HTML file to write")->required();
  cmd->footer(catalogue_help());
  cmd->callback([opt] { run_report(*opt); });
}

}  // namespace calstand::cli
