// `calstand report`: one self-contained HTML page of a run's fit: how the error fell over the
// fits of the run, where the model fails, what the residual follows, the parameters, the
// candidate terms, the datasheet figures that apply and, for a static run, the Allan deviation
// with its fitted noise lines. A run without an error model gets its summary and figures.
#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <memory>
#include <string>

#include "commands.hpp"
#include "core/error.hpp"
#include "core/file_output.hpp"
#include "fit_printer.hpp"
#include "noise/record_length.hpp"
#include "open_database.hpp"
#include "render/gnuplot_svg.hpp"
#include "render/html_to_pdf.hpp"
#include "report/report_data.hpp"
#include "report/report_html.hpp"
#include "report/table_free_report.hpp"

namespace calstand::cli {
namespace {

struct ReportOptions {
  analysis::ReportRequest request;
  std::string out;
};

// The page as HTML, or printed to PDF when `path` ends in .pdf (as `calstand certificate`);
// either file appears whole or not at all.
void write_page(const std::string& path, const std::string& page) {
  if (std::filesystem::path(path).extension() == ".pdf") {
    analysis::html_to_pdf(page, path);
    return;
  }
  core::write_file_whole(path, page);
}

void print_static(const ReportOptions& opt, const analysis::StaticReportData& data,
                  std::size_t bytes) {
  std::string figures;
  if (data.record) {
    const analysis::StaticRecordNoise& r = *data.record;
    figures = fmt::format("; {} of {} at {:.6g} Hz: Allan deviation, noise figures{}{}",
                          solver::format_record_length(r.noise.duration_s), data.record_label,
                          r.noise.sample_rate_hz,
                          std::any_of(r.models.begin(), r.models.end(),
                                      [](const auto& m) { return m.model.has_value(); })
                              ? ", composite noise model"
                              : "",
                          r.stability ? ", stability" : "");
  }
  fmt::print("{}: run {} ({}), a record at rest, no calibration: {}{}; {} kB\n", opt.out,
             data.request.run, data.procedure, data.no_fit_reason, figures, (bytes + 512) / 1024);
}

void print_table_free(const ReportOptions& opt, const analysis::TableFreeReportData& data,
                      std::size_t bytes) {
  fmt::print(
      "{}: run {} ({}) without a table, method {}, model {}: {}; {} fits in the "
      "history; {} kB\n",
      opt.out, data.request.run, data.procedure, data.diagnosis.fit.method,
      analysis::table_free_model_text(data.diagnosis.fit.terms),
      data.diagnosis.explained ? "explained" : "not explained", data.history.size(),
      (bytes + 512) / 1024);
}

void print_table(const ReportOptions& opt, const analysis::ReportData& data, std::size_t bytes) {
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
               data.noise ? ", Allan deviation of the static step" : "", (bytes + 512) / 1024);
    return;
  }
  fmt::print("{}: run {} ({}), model {}: chi2/dof {:.3g}, {} fits in the history{}{}; {} kB\n",
             opt.out, data.request.run, data.procedure, data.diagnosis.fit.model,
             data.diagnosis.fit.chi2_dof, data.history.size(), figures,
             data.noise ? ", Allan deviation of the static step" : "", (bytes + 512) / 1024);
}

void run_report(const ReportOptions& opt) {
  analysis::find_gnuplot();  // before the work: a missing plotter is the first thing to say
  store::Database db = open_existing_database(opt.request.db);
  const analysis::ReportPage gathered = analysis::gather_report_page(db, opt.request);
  const std::string page = analysis::render_report_page(gathered);
  write_page(opt.out, page);
  if (gathered.static_record) {
    print_static(opt, *gathered.static_record, page.size());
  } else if (gathered.table_free) {
    print_table_free(opt, *gathered.table_free, page.size());
  } else {
    print_table(opt, *gathered.table, page.size());
  }
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
  cmd->add_flag("!--no-noise-model", opt->request.noise_model,
                "A record at rest: leave out the composite noise model (calstand noise-id; "
                "minutes on a record of hours)");
  add_noise_run_option(cmd, opt->request.noise_run);
  cmd->add_option("--out", opt->out,
                  "The file to write: HTML, or PDF when it ends in .pdf (headless Chromium)")
      ->required();
  cmd->footer(catalogue_help());
  cmd->callback([opt] { run_report(*opt); });
}

}  // namespace calstand::cli
