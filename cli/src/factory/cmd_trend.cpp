// `calstand trend`: how a unit's calibration parameters moved across its records (aging,
// storage), each change beside the uncertainty of the two records it compares.
#include <fmt/format.h>

#include <string>

#include "commands.hpp"
#include "factory/unit_trend.hpp"
#include "record_source_option.hpp"

namespace calstand::cli {
namespace {

struct TrendOptions {
  std::string db;
  CentralOptions central;  ///< --from: the fleet's central database instead of --db
  std::string serial;
  bool as_json = false;
};

void run_trend(const TrendOptions& opt) {
  const analysis::UnitTrend trend = with_record_source(
      opt.db, opt.central, "trend",
      [&](store::RecordSource& records) { return analysis::unit_trend(records, opt.serial); });
  if (opt.as_json) {
    fmt::print("{}\n", analysis::to_json(trend).dump(2));
    return;
  }
  fmt::print("unit {}: {} records\n", trend.serial, trend.records.size());
  for (std::size_t r = 0; r < trend.records.size(); ++r) {
    const auto& rec = trend.records[r];
    fmt::print("  [{}] calibration {} of run {}{}, {}{}\n", r + 1, rec.calibration, rec.run,
               rec.station.empty() ? "" : " at " + rec.station, rec.created_utc,
               rec.verdict.empty() ? "" : " (" + rec.verdict + ")");
  }
  fmt::print("\n{:<28} {:<9}", "parameter", "unit");
  for (std::size_t r = 0; r < trend.records.size(); ++r)
    fmt::print(" {:>22}", fmt::format("[{}]", r + 1));
  fmt::print(" {:>12} {:>8}\n", "change", "z");
  for (const analysis::TrendParameter& p : trend.parameters) {
    fmt::print("{:<28} {:<9}", p.name, p.unit);
    for (std::size_t r = 0; r < p.values.size(); ++r) {
      fmt::print(" {:>22}", p.values[r]
                                ? fmt::format("{:.5g} +- {:.2g}", *p.values[r], *p.sigmas[r])
                                : std::string("-"));
    }
    fmt::print(" {:>12.4g} {:>8}\n", p.change,
               p.change_z ? fmt::format("{:.1f}", *p.change_z) : std::string("-"));
  }
}

}  // namespace

void register_trend(CLI::App& app) {
  auto opt = std::make_shared<TrendOptions>();
  auto* cmd = app.add_subcommand(
      "trend", "How a unit's calibration parameters moved across its records, with their sigmas");
  auto* db = cmd->add_option("--db", opt->db, "Database file");
  add_central_options(cmd, opt->central, "--from", "The fleet's central database instead of --db",
                      false);
  cmd->get_option("--from")->excludes(db);
  cmd->add_option("--serial", opt->serial, "The unit's serial")->required();
  cmd->add_flag("--json", opt->as_json, "Print the trend as JSON");
  cmd->callback([opt] { run_trend(*opt); });
}

}  // namespace calstand::cli
