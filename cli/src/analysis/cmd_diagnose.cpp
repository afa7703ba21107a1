// `calstand diagnose` (which effect is the model missing?) and `calstand history` (how the fit
// of a run improved as effects were added).
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "analysis/fit_history.hpp"
#include "analysis/fit_request.hpp"
#include "analysis/noise_run.hpp"
#include "analysis/table_free_diagnose.hpp"
#include "commands.hpp"
#include "fit_printer.hpp"
#include "open_database.hpp"
#include "solver/diagnose.hpp"
#include "store/fit_history.hpp"
#include "table_free_printer.hpp"

namespace calstand::cli {
namespace {

struct DiagnoseOptions : RunModelOptions {
  StaticPoseOptions poses;  ///< runs without a table
  bool as_json = false;
  bool suggest = false;
  std::optional<std::int64_t> noise_run;  ///< the wander from this static run of the unit
};

// The best few custom terms, each ready to paste, with its figures and effect in words.
constexpr std::size_t kSuggestionsShown = 3;

void print_warm_ups(const solver::Diagnosis& d) {
  for (const solver::WarmUpCheck& w : d.warm_ups) {
    if (w.kept) continue;  // shown with the suggestions
    fmt::print("warm-up checked: {}: {}\n", w.custom, w.verdict);
  }
}

void print_suggestions(const solver::Diagnosis& d) {
  if (d.suggestions.empty()) {
    // Searched only as a check on a wander where the catalogue explains: no news to print.
    if (!d.explained) fmt::print("\ncustom terms: {}\n", d.custom_summary);
    if (!d.warm_ups.empty()) fmt::print("\n");
    print_warm_ups(d);
    return;
  }
  fmt::print("\ncustom terms built from the signals ({} forms tried; best first):\n",
             d.custom_forms_tried);
  for (std::size_t i = 0; i < d.suggestions.size() && i < kSuggestionsShown; ++i) {
    const solver::Suggestion& s = d.suggestions[i];
    fmt::print("  --custom '{}'\n", s.custom);
    fmt::print(
        "      delta BIC {:.1f} against the wander, chi2/dof after {:.3g}; held out ({}): "
        "chi2/dof {:.3g} -> "
        "{:.3g}\n",
        s.delta_bic, s.chi2_dof_after, s.held_out, s.held_out_chi2_dof_before,
        s.held_out_chi2_dof_after);
    fmt::print("      {}\n", s.explanation);
  }
  print_warm_ups(d);
}

void run_diagnose(const DiagnoseOptions& opt) {
  analysis::FitRequest request;
  request.model = solver::Model::parse(opt.model, opt.customs);
  request.device = opt.device;
  request.sensor = opt.sensor;
  request.noise_run = opt.noise_run;
  request.history_command = opt.suggest ? "" : "diagnose";
  store::Database db = open_existing_database(opt.db);
  if (analysis::needs_table_free_fit(db, opt.run)) {
    if (opt.noise_run) analysis::throw_noise_run_on_table_free(opt.run);
    analysis::TableFreeFitRequest table_free =
        analysis::table_free_request(request.model, static_pose_request(opt.poses, opt.device));
    table_free.history_command = request.history_command;
    const analysis::TableFreeDiagnosis d = analysis::diagnose_table_free(db, opt.run, table_free);
    if (opt.as_json) {
      fmt::print("{}\n", analysis::to_json(d).dump(2));
    } else if (opt.suggest) {
      if (!d.recommended.empty()) fmt::print("{}\n", d.recommended);
    } else {
      print_table_free_diagnosis(d);
    }
    return;
  }
  const analysis::DiagnoseOutcome outcome = analysis::diagnose_request(db, opt.run, request);
  const solver::Diagnosis& d = outcome.diagnosis;
  if (opt.as_json) {
    fmt::print("{}\n", analysis::to_json(outcome).dump(2));
    return;
  }
  if (opt.suggest) {
    if (!d.recommended.empty()) fmt::print("{}\n", d.recommended);
    return;
  }
  fmt::print("run {} ({}), device {}: model {}\n", opt.run, outcome.procedure, outcome.device,
             d.fit.model);
  fmt::print("chi2/dof {:.3g}; step residual rms gyro {:.3g} deg/s, accel {:.3g} m/s^2\n",
             d.fit.chi2_dof, d.fit.residual_rms_gyro_dps, d.fit.residual_rms_accel_mps2);
  print_groups(d.groups, solver::worst_steps(d.fit), 5);
  fmt::print("\ncandidates (each added in turn, best first):\n");
  fmt::print("  {:<24} {:>11} {:>10} {:>9} {:>14}  {}\n", "term", "delta BIC", "vs wander", "p",
             "chi2/dof after", "what it is");
  for (std::size_t i = 0; i < d.candidates.size(); ++i) {
    const auto& c = d.candidates[i];
    fmt::print("  {:<24} {:>11.1f} {:>10} {:>9.2g} {:>14.3g}  {}\n", c.term, c.delta_bic,
               std::isfinite(c.delta_bic_against_wander)
                   ? fmt::format("{:.1f}", c.delta_bic_against_wander)
                   : std::string("-"),
               c.p_value, c.chi2_dof_after, c.explanation);
  }
  if (!d.untestable.empty()) {
    fmt::print("  not testable on this run: {}\n", fmt::join(d.untestable, ", "));
  }
  fmt::print("\nresiduals follow (strongest first):\n");
  for (std::size_t i = 0; i < d.signals.size() && i < 8; ++i) {
    fmt::print("  {:<24} {:<3} r = {:+.2f}\n", d.signals[i].signal, d.signals[i].channel,
               d.signals[i].correlation);
  }
  if (d.custom_searched) print_suggestions(d);
  fmt::print("\n{}: {}\n", d.explained ? "explained" : "NOT explained", d.advice);
}

struct HistoryOptions {
  std::string db;
  std::int64_t run = 0;
  bool as_json = false;
};

std::string optional_text(const std::optional<double>& v, const char* format) {
  return v ? fmt::format(fmt::runtime(format), *v) : std::string("-");
}

void run_history(const HistoryOptions& opt) {
  store::Database db = open_existing_database(opt.db);
  const auto fits = store::fit_history(db, opt.run);
  if (opt.as_json) {
    fmt::print("{}\n", analysis::history_to_json(fits).dump(2));
    return;
  }
  if (fits.empty()) {
    fmt::print("run {} has no fits yet: try calstand fit --db {} --run {}\n", opt.run, opt.db,
               opt.run);
    return;
  }
  // A run without a table has no rate steps: its gyro figure is the gravity direction after
  // each turn, and its accel figure |f| - g.
  const bool table_free = std::any_of(fits.begin(), fits.end(),
                                      [](const store::FitRecord& f) { return f.rms_turn_deg; });
  fmt::print("{:>4}  {:<24} {:<9} {:>6} {:>10} {:>14} {:>14}  {}\n", "fit", "time", "command",
             "params", "chi2/dof", table_free ? "turns [deg]" : "gyro [deg/s]",
             table_free ? "|f|-g [m/s^2]" : "accel [m/s^2]", "model");
  for (const auto& f : fits) {
    std::string model = f.model;
    for (const auto& c : f.custom_terms) model += " (" + c + ")";
    fmt::print("{:>4}  {:<24} {:<9} {:>6} {:>10} {:>14} {:>14}  {}\n", f.id, f.created_utc,
               f.command, f.parameters, optional_text(f.chi2_dof, "{:.3g}"),
               optional_text(table_free ? f.rms_turn_deg : f.rms_gyro_dps, "{:.3g}"),
               optional_text(f.rms_accel_mps2, "{:.3g}"), model);
  }
}

}  // namespace

void register_diagnose(CLI::App& app) {
  auto opt = std::make_shared<DiagnoseOptions>();
  auto* cmd = app.add_subcommand(
      "diagnose", "Find the effect a model misses: candidate terms ranked, residual signals");
  add_run_model_options(cmd, *opt);
  add_static_pose_options(cmd, opt->poses);
  cmd->add_flag("--json", opt->as_json, "Print the diagnosis as JSON");
  cmd->add_flag("--suggest", opt->suggest,
                "Print only the term to add (nothing when the model fits or no term explains "
                "the residual): for scripts");
  add_noise_run_option(cmd, opt->noise_run);
  cmd->callback([opt] { run_diagnose(*opt); });

  auto hopt = std::make_shared<HistoryOptions>();
  auto* history = app.add_subcommand("history", "Every fit of a run: how the error fell");
  history->add_option("--db", hopt->db, "Database file")->required();
  history->add_option("--run", hopt->run, "Run id")->required();
  history->add_flag("--json", hopt->as_json, "Print the history as JSON");
  history->callback([hopt] { run_history(*hopt); });
}

}  // namespace calstand::cli
