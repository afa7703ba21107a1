// `calstand lot`: every unit calibrated (since a date): each parameter's distribution, the units
// far from their siblings, the yield; --html writes the control charts.
#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include "commands.hpp"
#include "core/file_output.hpp"
#include "factory/lot.hpp"
#include "record_source_option.hpp"

namespace calstand::cli {
namespace {

struct LotOptions {
  std::string db;
  CentralOptions central;  ///< --from: the fleet's central database instead of --db
  std::string since;
  std::string html;
  bool as_json = false;
};

void run_lot(const LotOptions& opt) {
  analysis::check_lot_since(opt.since, "--since");
  const analysis::LotStatistics lot = with_record_source(
      opt.db, opt.central, "lot",
      [&](store::RecordSource& records) { return analysis::lot_statistics(records, opt.since); });
  if (!opt.html.empty()) {
    core::write_file_whole(opt.html, analysis::lot_html(lot));
  }
  if (opt.as_json) {
    fmt::print("{}\n", analysis::to_json(lot).dump(2));
    return;
  }
  fmt::print("{} units{}", lot.units.size(), opt.since.empty() ? "" : " since " + opt.since);
  if (lot.records_without_serial > 0) {
    fmt::print(" ({} records without a serial left out)", lot.records_without_serial);
  }
  fmt::print("\nverdicts: {} pass, {} fail, {} indeterminate, {} not judged; yield {}\n\n",
             lot.passed, lot.failed, lot.indeterminate, lot.not_judged,
             lot.yield ? fmt::format("{:.1f} %", 100.0 * *lot.yield) : "-");
  fmt::print("{:<28} {:<9} {:>4} {:>12} {:>12} {:>12}  {}\n", "parameter", "unit", "n", "mean",
             "std", "median", "outliers (robust z > 4)");
  for (const analysis::LotParameter& p : lot.parameters) {
    std::string flagged;
    for (const auto& o : p.outliers) {
      flagged += fmt::format("{}{} z={}{}", flagged.empty() ? "" : ", ", o.serial,
                             std::isfinite(o.robust_z) ? fmt::format("{:.1f}", o.robust_z) : "inf",
                             o.verdict.empty() ? "" : " (" + o.verdict + ")");
    }
    fmt::print("{:<28} {:<9} {:>4} {:>12.5g} {:>12.5g} {:>12.5g}  {}\n", p.name, p.unit,
               p.values.size(), p.mean, p.std_dev, p.median, flagged.empty() ? "-" : flagged);
  }
  if (!opt.html.empty()) fmt::print("\ncontrol charts: {}\n", opt.html);
}

}  // namespace

void register_lot(CLI::App& app) {
  auto opt = std::make_shared<LotOptions>();
  auto* cmd = app.add_subcommand(
      "lot",
      "Every unit calibrated (its newest record): each parameter's distribution, units far from "
      "their siblings, yield, control charts");
  auto* db = cmd->add_option("--db", opt->db, "Database file");
  add_central_options(cmd, opt->central, "--from", "The fleet's central database instead of --db",
                      false);
  cmd->get_option("--from")->excludes(db);
  cmd->add_option(
      "--since", opt->since,
      "Only records made since this UTC date (YYYY-MM-DD) or time (YYYY-MM-DDTHH:MM[:SS])");
  cmd->add_option("--html", opt->html, "Write the statistics and control charts as HTML");
  cmd->add_flag("--json", opt->as_json, "Print the statistics as JSON");
  cmd->callback([opt] { run_lot(*opt); });
}

}  // namespace calstand::cli
