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
#include "solver/noise_estimate.hpp"
#include "solver/thermal_fit.hpp"

namespace calstand::cli {
namespace {

struct FitCommandOptions : RunModelOptions {
  bool as_json = false;
  int per_plateau_order = 0;  ///< > 0: thermal calibration by per-plateau fits
  bool white_noise = false;   ///< weights from the white noise alone (no wandering bias)
};

/// The classical thermal calibration: the model fitted on each temperature plateau, then a
/// polynomial of `order` in dT per bias (linear per scale factor).
void run_per_plateau(const FitCommandOptions& opt, const solver::Model& model,
                     const solver::RunData& data, const std::vector<solver::StepSummary>& steps) {
  solver::ThermalFitOptions options;
  options.temperature_ref_c = data.setup.temperature_ref_c;
  options.fit.rows = parse_sensor_rows(opt.sensor);
  solver::NoiseEstimateOptions noise_options;
  noise_options.estimate_wander = !opt.white_noise;
  // Each plateau's fit is weighed with the run's own noise model, like the whole-run fit.
  const solver::ThermalFitResult r = solver::fit_per_plateau(
      steps, model, opt.per_plateau_order,
      solver::estimate_run_noise(data, model, options.fit.rows, noise_options), options);
  if (opt.as_json) {
    fmt::print("{}\n", solver::thermal_fit_to_json(r).dump(2));
    return;
  }
  fmt::print("run {} ({}), device {}: per-plateau fits of {}\n", opt.run,
             data.setup.procedure_name, data.setup.device, r.model);
  for (const auto& p : r.plateaus) {
    fmt::print("  plateau {:>7.2f} degC: {:>3} steps, chi2/dof {:.3g}\n", p.temperature_c,
               p.steps, p.chi2_dof);
  }
  fmt::print("\npolynomial of order {} in T - {:g} degC:\n", r.order, r.temperature_ref_c);
  fmt::print("{:<28} {:>15} {:>12}  {}\n", "parameter", "value", "sigma", "unit");
  for (const auto& c : r.coefficients) {
    fmt::print("{:<28} {:>15.6g} {:>12.3g}  {}\n", c.name, c.value, c.sigma, c.unit);
  }
  for (const auto& c : r.constants) {
    fmt::print("{:<28} {:>15.6g} {:>12.3g}  {}  (mean over plateaus)\n", c.name, c.value, c.sigma,
               c.unit);
  }
  for (const auto& k : r.skipped) fmt::print("  not fitted: {} ({})\n", k.name, k.reason);
}

void run_fit(const FitCommandOptions& opt) {
  const solver::Model model = solver::Model::parse(opt.model, opt.customs);
  store::Database db = open_existing_database(opt.db);
  const solver::RunData data = solver::load_run_data(db, opt.run, opt.device);
  if (opt.per_plateau_order > 0) {
    run_per_plateau(opt, model, data, solver::summarize_steps(data, model));
    return;
  }
  solver::FitOptions fit_options;
  fit_options.rows = parse_sensor_rows(opt.sensor);
  solver::NoiseEstimateOptions noise_options;
  noise_options.estimate_wander = !opt.white_noise;
  std::vector<solver::StepSummary> steps;
  const solver::FitResult fit = solver::fit_run(data, model, fit_options, noise_options, &steps);
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
  cmd->add_flag("--white-noise", opt->white_noise,
                "Weigh the steps by the white noise inside them alone (no wandering bias "
                "between steps): the plain weighted least squares");
  cmd->add_option("--per-plateau", opt->per_plateau_order,
                  "Thermal calibration the classical way: fit the model on each temperature "
                  "plateau, then a polynomial of this order in temperature per bias")
      ->check(CLI::Range(1, 9));
  cmd->callback([opt] { run_fit(*opt); });
}

}  // namespace calstand::cli
