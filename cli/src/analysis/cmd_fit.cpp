// `calstand fit`: fit an error model to a recorded (or imported) run and show how well it fits.
#include <fmt/format.h>

#include <optional>
#include <string>
#include <vector>

#include "analysis/fit_request.hpp"
#include "analysis/noise_run.hpp"
#include "commands.hpp"
#include "core/error.hpp"
#include "fit_printer.hpp"
#include "open_database.hpp"
#include "solver/thermal_fit.hpp"
#include "table_free_printer.hpp"

namespace calstand::cli {
namespace {

struct FitCommandOptions : RunModelOptions {
  StaticPoseOptions poses;  ///< runs without a table
  bool as_json = false;
  int per_plateau_order = 0;  ///< > 0: thermal calibration by per-plateau fits
  bool white_noise = false;   ///< weights from the white noise alone (no wandering bias)
  std::optional<std::int64_t> noise_run;  ///< the wander from this static run of the unit
};

analysis::FitRequest fit_request_of(const FitCommandOptions& opt, const char* command) {
  analysis::FitRequest request;
  request.model = solver::Model::parse(opt.model, opt.customs);
  request.device = opt.device;
  request.sensor = opt.sensor;
  request.white_noise = opt.white_noise;
  request.noise_run = opt.noise_run;
  request.history_command = command;
  return request;
}

/// The classical thermal calibration: the model fitted on each temperature plateau, then a
/// polynomial of `order` in dT per bias (linear per scale factor).
void print_per_plateau(const FitCommandOptions& opt, const analysis::PlateauFitOutcome& outcome) {
  const solver::ThermalFitResult& r = outcome.result;
  if (opt.as_json) {
    fmt::print("{}\n", solver::thermal_fit_to_json(r).dump(2));
    return;
  }
  fmt::print("run {} ({}), device {}: per-plateau fits of {}\n", opt.run, outcome.procedure,
             outcome.device, r.model);
  for (const auto& p : r.plateaus) {
    fmt::print("  plateau {:>7.2f} degC: {:>3} steps, chi2/dof {:.3g}\n", p.temperature_c, p.steps,
               p.chi2_dof);
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
  const bool per_plateau = opt.per_plateau_order > 0;
  const analysis::FitRequest request = fit_request_of(opt, per_plateau ? "" : "fit");
  store::Database db = open_existing_database(opt.db);
  if (analysis::needs_table_free_fit(db, opt.run)) {
    // No orientation is known: the table-free methods, with the optional terms of the model.
    if (opt.noise_run) analysis::throw_noise_run_on_table_free(opt.run);
    if (per_plateau) {
      throw core::InputError("--per-plateau", fmt::format("run {} was recorded without a table: "
                                                          "there are no temperature plateaus "
                                                          "of known orientation to fit",
                                                          opt.run));
    }
    analysis::TableFreeFitRequest table_free =
        analysis::table_free_request(request.model, static_pose_request(opt.poses, opt.device));
    table_free.history_command = request.history_command;
    const analysis::TableFreeFit fit = analysis::table_free_fit(db, opt.run, table_free);
    if (opt.as_json) {
      fmt::print("{}\n", analysis::to_json(fit).dump(2));
    } else {
      print_table_free_fit(fit);
    }
    return;
  }
  if (per_plateau) {
    print_per_plateau(opt,
                      analysis::plateau_fit_request(db, opt.run, request, opt.per_plateau_order));
    return;
  }
  const analysis::FitOutcome outcome = analysis::fit_request(db, opt.run, request);
  if (opt.as_json) {
    fmt::print("{}\n", analysis::to_json(outcome).dump(2));
    return;
  }
  fmt::print("run {} ({}), device {}, {} steps\n", opt.run, outcome.procedure, outcome.device,
             outcome.steps.size());
  print_fit(outcome.fit);
  print_groups(outcome.groups, outcome.worst);
}

}  // namespace

void register_fit(CLI::App& app) {
  auto opt = std::make_shared<FitCommandOptions>();
  auto* cmd = app.add_subcommand(
      "fit", "Fit an error model to a run by weighted least squares on step means");
  add_run_model_options(cmd, *opt);
  cmd->add_flag("--json", opt->as_json, "Print the fit as JSON");
  add_static_pose_options(cmd, opt->poses);
  cmd->add_flag("--white-noise", opt->white_noise,
                "Weigh the steps by the white noise inside them alone (no wandering bias "
                "between steps): the plain weighted least squares");
  add_noise_run_option(cmd, opt->noise_run);
  cmd->add_option("--per-plateau", opt->per_plateau_order,
                  "Thermal calibration the classical way: fit the model on each temperature "
                  "plateau, then a polynomial of this order in temperature per bias")
      ->check(CLI::Range(1, 9));
  cmd->callback([opt] { run_fit(*opt); });
}

}  // namespace calstand::cli
