// `calstand calibrations`: a unit's calibration records across runs, newest first, with the one
// in force (analysis/unit_records.hpp says which).
#include <fmt/format.h>

#include <nlohmann/json.hpp>
#include <string>

#include "commands.hpp"
#include "factory/unit_records.hpp"
#include "open_database.hpp"

namespace calstand::cli {
namespace {

struct CalibrationsOptions {
  std::string db;
  std::string serial;
  bool as_json = false;
};

void run_calibrations(const CalibrationsOptions& opt) {
  store::Database db = open_existing_database(opt.db);
  const std::vector<analysis::UnitRecord> records = analysis::unit_records(db, opt.serial);
  if (opt.as_json) {
    fmt::print("{}\n", analysis::unit_records_json(opt.serial, records).dump(2));
    return;
  }
  if (records.empty()) {
    fmt::print("no calibration{}\n", opt.serial.empty() ? "" : " of unit " + opt.serial);
    return;
  }
  fmt::print("{:>5}  {:<14} {:>5}  {:<8} {:<24} {:<14} {}\n", "id", "serial", "run", "imu",
             "created (UTC)", "verdict", "model");
  for (const auto& r : records) {
    const store::CalibrationRow& c = r.calibration;
    fmt::print("{:>5}  {:<14} {:>5}  {:<8} {:<24} {:<14} {}{}\n", c.id,
               c.serial.empty() ? "-" : c.serial, c.run, c.imu, c.created_utc,
               r.acceptance ? r.acceptance->verdict : "not judged", c.model,
               r.in_force ? "   <- in force" : "");
  }
}

}  // namespace

void register_calibrations(CLI::App& app) {
  auto opt = std::make_shared<CalibrationsOptions>();
  auto* cmd = app.add_subcommand(
      "calibrations",
      "A unit's calibration records, newest first, with the one in force (the newest that "
      "passed its acceptance, or was never judged)");
  cmd->add_option("--db", opt->db, "Database file")->required();
  cmd->add_option("--serial", opt->serial, "The unit's serial (default: every record)");
  cmd->add_flag("--json", opt->as_json, "Print {\"serial\", \"calibrations\": [...]} as JSON");
  cmd->callback([opt] { run_calibrations(*opt); });
}

}  // namespace calstand::cli
