// `calstand calibrate` (fit a run, store and write a calibration record) and `calstand apply`
// (correct a run's raw samples with a record, as a new run).
#include <fmt/format.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "commands.hpp"
#include "core/error.hpp"
#include "core/json_schema.hpp"
#include "core/schemas.hpp"
#include "fit_printer.hpp"
#include "open_database.hpp"
#include "solver/calibration_record.hpp"
#include "solver/noise_estimate.hpp"
#include "solver/run_noise.hpp"
#include "store/calibrations.hpp"
#include "store/derived_run.hpp"
#include "store/run_store.hpp"

namespace calstand::cli {
namespace {

struct CalibrateOptions : RunModelOptions {
  std::string out;
  bool as_json = false;
};

void write_text(const std::string& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary | std::ios::trunc);
  f << text;
  f.close();
  if (!f) throw std::runtime_error(path + ": cannot write the file");
}

// Noise figures are worth a record only from a static step long enough for the Allan curve to
// reach the bias instability region [s].
constexpr double kMinNoiseStepS = 100.0;

/// The run's noise figures in datasheet units from its longest static capture, or null when the
/// run has none long enough.
nlohmann::json noise_figures(store::Database& db, std::int64_t run, const std::string& device) {
  solver::RunNoiseOptions options;
  options.device = device;
  solver::RunNoise noise;
  try {
    noise = solver::analyse_run_noise(db, run, options);
  } catch (const core::InputError&) {
    return nullptr;  // no static capture
  }
  if (noise.duration_s < kMinNoiseStepS) return nullptr;
  nlohmann::json j = {{"step", noise.step}, {"duration_s", noise.duration_s}, {"channels", nlohmann::json::object()}};
  for (const auto& c : noise.channels) {
    nlohmann::json figures = nlohmann::json::array();
    for (const auto& f : c.figures) {
      figures.push_back({{"name", f.name},
                         {"value", f.value},
                         {"sigma", std::isfinite(f.sigma) ? nlohmann::json(f.sigma) : nlohmann::json()},
                         {"unit", f.unit},
                         {"resolved", f.resolved}});
    }
    j["channels"][std::string(solver::to_string(c.channel))] = figures;
  }
  return j;
}

void run_calibrate(const CalibrateOptions& opt) {
  const solver::Model model = solver::Model::parse(opt.model, opt.customs);
  store::Database db = open_existing_database(opt.db);
  const solver::RunData data = solver::load_run_data(db, opt.run, opt.device);
  std::vector<solver::StepSummary> steps;
  const solver::FitResult fit = solver::fit_run(data, model, {}, {}, &steps);
  record_history(db, opt.run, data.setup.device, "calibrate", model, fit, "both");
  const nlohmann::json record = solver::make_calibration_record(
      data.setup, model, fit, steps, noise_figures(db, opt.run, data.setup.device));
  // Check our own output against the published schema before anything is stored.
  core::validate_or_throw(core::schema("calibration.schema.json"), record, "calibration record");
  const std::string out =
      opt.out.empty() ? fmt::format("calibration-run{}-{}.json", opt.run, data.setup.device) : opt.out;
  write_text(out, record.dump(2) + "\n");
  const std::int64_t id = store::insert_calibration(db, opt.run, data.setup.device, fit.model, record);
  if (opt.as_json) {
    fmt::print("{}\n", nlohmann::json{{"calibration_id", id}, {"file", out}, {"record", record}}.dump(2));
    return;
  }
  fmt::print("run {} ({}), device {}, {} steps\n", opt.run, data.setup.procedure_name,
             data.setup.device, steps.size());
  print_fit(fit);
  fmt::print("\ncalibration {} stored in {} and written to {}\n", id, opt.db, out);
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
  solver::RunData data = solver::load_run_data(db, opt.run, opt.device);
  const solver::Corrector corrector(calibration, data.setup);
  const double run_start_s = data.steps.front().samples.front().receive_time_s;
  double tmin = 1e300, tmax = -1e300;
  for (auto& step : data.steps) {
    for (const auto& s : step.samples) {
      tmin = std::min(tmin, s.temperature_c);
      tmax = std::max(tmax, s.temperature_c);
    }
    corrector.correct(step, run_start_s);
  }
  store::DerivedRun derived;
  derived.source_run = opt.run;
  derived.procedure_name = "corrected " + store::RunStore(db).load_run(opt.run).summary.procedure_name;
  derived.status = "corrected";
  derived.parameters = {{"calibration", opt.record}};
  derived.device = data.setup.device;
  derived.steps = std::move(data.steps);
  const std::int64_t run = store::write_derived_run(db, derived);
  fmt::print("run {}: run {} corrected with {} ({} steps)\n", run, opt.run, opt.record,
             derived.steps.size());
  const double margin_c = 1.0;
  if (tmin < calibration.valid_min_c - margin_c || tmax > calibration.valid_max_c + margin_c) {
    fmt::print("warning: the run spans {:.1f} to {:.1f} degC; the record was fitted on {:.1f} to "
               "{:.1f} degC\n",
               tmin, tmax, calibration.valid_min_c, calibration.valid_max_c);
  }
  fmt::print("check it: calstand fit --db {} --run {} --model earth_rate\n", opt.db, run);
}

}  // namespace

void register_calibrate(CLI::App& app) {
  auto opt = std::make_shared<CalibrateOptions>();
  auto* cmd = app.add_subcommand(
      "calibrate", "Fit a run, store the calibration record in the database and write its JSON");
  add_run_model_options(cmd, *opt, false);
  cmd->add_option("--out", opt->out, "Record file (default calibration-run<ID>-<device>.json)");
  cmd->add_flag("--json", opt->as_json, "Print the record id, file and record as JSON");
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
