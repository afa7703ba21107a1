// `calstand fit`: fit an error model to a recorded (or imported) run and show how well it fits.
#include <fmt/format.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "commands.hpp"
#include "core/error.hpp"
#include "fit_printer.hpp"
#include "open_database.hpp"
#include "solver/fit.hpp"

namespace calstand::cli {
namespace {

struct FitCommandOptions : RunModelOptions {
  bool as_json = false;
};

void run_fit(const FitCommandOptions& opt) {
  const solver::Model model = solver::Model::parse(opt.model, opt.customs);
  store::Database db = open_existing_database(opt.db);
  const solver::RunData data = solver::load_run_data(db, opt.run, opt.device);
  const auto steps = solver::summarize_steps(data, model);
  solver::FitOptions fit_options;
  fit_options.rows = parse_sensor_rows(opt.sensor);
  const solver::FitResult fit =
      solver::fit_model(steps, model, solver::measure_noise_floor(steps), fit_options);
  record_history(db, opt.run, data.setup.device, "fit", model, fit, opt.sensor);
  const auto groups = solver::group_quality(fit, steps);
  const auto worst = solver::worst_steps(fit);
  if (opt.as_json) {
    nlohmann::json j = solver::fit_to_json(fit);
    solver::add_groups_json(j, groups, worst);
    fmt::print("{}\n", j.dump(2));
    return;
  }
  fmt::print("run {} ({}), device {}, {} steps\n", opt.run, data.setup.procedure_name,
             data.setup.device, steps.size());
  print_fit(fit);
  print_groups(groups, worst);
}

}  // namespace

void register_fit(CLI::App& app) {
  auto opt = std::make_shared<FitCommandOptions>();
  auto* cmd = app.add_subcommand(
      "fit", "Fit an error model to a run by weighted least squares on step means");
  add_run_model_options(cmd, *opt);
  cmd->add_flag("--json", opt->as_json, "Print the fit as JSON");
  cmd->callback([opt] { run_fit(*opt); });
}

}  // namespace calstand::cli
