// `calstand calibrate` (fit a run, store and write a calibration record) and `calstand apply`
// (correct a run's raw samples with a record, as a new run).
#include <fmt/format.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "analysis/calibrate.hpp"
#include "commands.hpp"
#include "core/error.hpp"
#include "core/file_output.hpp"
#include "core/json_schema.hpp"
#include "fit_printer.hpp"
#include "open_database.hpp"
#include "solver/calibration_record.hpp"
#include "table_free_printer.hpp"

namespace calstand::cli {
namespace {

struct CalibrateOptions : RunModelOptions {
  StaticPoseOptions poses;                ///< runs without a table
  std::optional<std::int64_t> noise_run;  ///< the wander from this static run of the unit
  std::string out;
  std::string out_dir = ".";
  bool as_json = false;
};

// Every unit of the run (or the one named) is fitted before anything is written: a unit that
// cannot be calibrated stops the command with no record of the others half-stored.
void run_calibrate(const CalibrateOptions& opt) {
  const solver::Model model = solver::Model::parse(opt.model, opt.customs);
  store::Database db = open_existing_database(opt.db);
  const std::vector<std::string> devices = analysis::units_to_calibrate(db, opt.run, opt.device);
  if (!opt.out.empty() && devices.size() > 1) {
    throw core::InputError("--out", fmt::format("run {} has {} units: give --out-dir, or --device "
                                                "with --out",
                                                opt.run, devices.size()));
  }
  std::vector<analysis::CalibrationOutcome> outcomes;
  for (const std::string& device : devices) {
    outcomes.push_back(analysis::calibrate_run(
        db, opt.run, model, device, static_pose_request(opt.poses, device), opt.noise_run));
  }
  nlohmann::json listed = nlohmann::json::array();
  for (const analysis::CalibrationOutcome& c : outcomes) {
    const std::string out = !opt.out.empty()
                                ? opt.out
                                : (std::filesystem::path(opt.out_dir) /
                                   analysis::default_calibration_file(opt.run, c.device))
                                      .string();
    // The file first: a record that cannot be written is not stored either.
    core::write_file_whole(out, c.record.dump(2) + "\n");
    const std::int64_t id = analysis::store_calibration(db, c);
    listed.push_back({{"calibration_id", id}, {"file", out}, {"record", c.record}});
    if (opt.as_json) continue;
    if (outcomes.size() > 1) fmt::print("== {} ==\n", c.device);
    if (c.table_free) {
      print_table_free_fit(*c.table_free);
    } else {
      const std::string serial = c.record["device"].value("serial", "");
      fmt::print("run {} ({}), device {}{}, {} steps\n", opt.run, c.procedure, c.device,
                 serial.empty() ? "" : " (unit " + serial + ")", c.steps);
      print_fit(c.fit);
    }
    fmt::print("\ncalibration {} stored in {} and written to {}\n\n", id, opt.db, out);
  }
  if (opt.as_json) fmt::print("{}\n", nlohmann::json{{"calibrations", listed}}.dump(2));
}

struct ApplyOptions {
  std::string record;
  std::string db;
  std::int64_t run = 0;
  std::string device;
};

void run_apply(const ApplyOptions& opt) {
  const nlohmann::json doc = core::read_json_file(opt.record);
  const solver::Calibration calibration = solver::read_calibration(doc, opt.record);
  store::Database db = open_existing_database(opt.db);
  const analysis::ApplyOutcome a =
      analysis::apply_calibration(db, opt.run, opt.device, calibration, opt.record);
  fmt::print("run {}: run {} corrected with {} ({} steps)\n", a.run, opt.run, opt.record, a.steps);
  if (a.outside_valid_range) {
    fmt::print(
        "warning: the run spans {:.1f} to {:.1f} degC; the record was fitted on {:.1f} to "
        "{:.1f} degC\n",
        a.min_temperature_c, a.max_temperature_c, calibration.valid_min_c, calibration.valid_max_c);
  }
  fmt::print("check it: calstand fit --db {} --run {} --model earth_rate\n", opt.db, a.run);
}

}  // namespace

void register_calibrate(CLI::App& app) {
  auto opt = std::make_shared<CalibrateOptions>();
  auto* cmd = app.add_subcommand(
      "calibrate",
      "Fit every unit of a run (or --device), store each unit's calibration record in the "
      "database and write its JSON");
  add_run_model_options(cmd, *opt, false);
  add_static_pose_options(cmd, opt->poses);
  add_noise_run_option(cmd, opt->noise_run);
  cmd->add_option("--out", opt->out,
                  "Record file, for one unit (default calibration-run<ID>-<device>.json)");
  cmd->add_option("--out-dir", opt->out_dir, "Folder of the record files (one per unit)")
      ->capture_default_str();
  cmd->add_flag("--json", opt->as_json,
                "Print {\"calibrations\": [{calibration_id, file, record}]}, one per unit");
  cmd->callback([opt] { run_calibrate(*opt); });

  auto aopt = std::make_shared<ApplyOptions>();
  auto* apply = app.add_subcommand(
      "apply", "Correct a run's raw samples with a calibration record, as a new run");
  apply->add_option("--record", aopt->record, "Calibration record (JSON)")->required();
  apply->add_option("--db", aopt->db, "Database file")->required();
  apply->add_option("--run", aopt->run, "Run id")->required();
  apply->add_option("--device", aopt->device, "IMU (default: the run's only IMU)");
  apply->callback([aopt] { run_apply(*aopt); });
}

}  // namespace calstand::cli
