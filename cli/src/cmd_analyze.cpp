// `calstand analyze KIND`: the datasheet analyses of the seed's test catalogue on a stored run.
// Kinds so far: stability (in-run bias stability of a long static capture), repeatability
// (turn-on bias across power cycles).
#include <fmt/format.h>

#include <optional>
#include <string>

#include "analysis/repeatability.hpp"
#include "analysis/stability.hpp"
#include "commands.hpp"
#include "core/error.hpp"
#include "open_database.hpp"

namespace calstand::cli {
namespace {

struct AnalyzeOptions {
  std::string kind;
  std::string db;
  std::int64_t run = 0;
  std::string device;
  std::optional<std::size_t> step;
  bool as_json = false;
};

void print_stability(const analysis::StabilityAnalysis& s) {
  fmt::print("run {} {}, step {} \"{}\": {:.0f} s static\n", s.run, s.device, s.step, s.step_label,
             s.duration_s);
  fmt::print("{:<8} {:>22} {:>24} {:>10}  {:>16} {:>14}\n", "channel", "bias instability",
             fmt::format("{:.0f} % interval", 100.0 * s.confidence), "at tau", "bias variation",
             "correlation");
  for (std::size_t c = 0; c < s.channels.size(); ++c) {
    const auto& ch = s.channels[c];
    const char* unit = c < 3 ? "deg/h" : "ug";
    fmt::print(
        "{:<8} {}{:>15.4g} {:<5} {:>11.4g} .. {:<9.4g} {:>8.0f} s  {:>10.4g} {:<5} {:>10.3g} s{}\n",
        ch.channel, ch.floor_resolved ? " " : "<", ch.bias_instability, unit,
        ch.bias_instability_lo, ch.bias_instability_hi, ch.min_tau_s, ch.variation_sigma, unit,
        ch.correlation_time_s, ch.correlation_resolved ? "" : "  (not resolved)");
  }
  fmt::print(
      "< : no floor inside the record (the deviation still falls at its longest averaging time): "
      "a bound.\nnot resolved: the correlation time is outside what the record shows.\n");
}

void print_repeatability(const analysis::RepeatabilityAnalysis& r) {
  fmt::print("run {} {}: {} power cycles, {} position{} each ({} degrees of freedom)\n", r.run,
             r.device, r.cycles, r.positions, r.positions == 1 ? "" : "s", r.dof);
  fmt::print("{:<8} {:>16} {:>26} {:>14} {:>16}\n", "channel", "repeatability",
             fmt::format("{:.0f} % interval", 100.0 * r.confidence), "spread", "noise of a mean");
  for (std::size_t c = 0; c < r.channels.size(); ++c) {
    const auto& ch = r.channels[c];
    const char* unit = c < 3 ? "deg/h" : "ug";
    fmt::print("{:<8} {:>10.4g} {:<5} {:>11.4g} .. {:<11.4g} {:>14.4g} {:>16.4g}\n", ch.channel,
               ch.repeatability, unit, ch.repeatability_lo, ch.repeatability_hi, ch.spread,
               ch.noise_of_means);
  }
  fmt::print("repeatability = sqrt(spread^2 - noise of a mean^2), 1 sigma across power-ups\n");
}

void run_analyze(const AnalyzeOptions& opt) {
  if (opt.kind != "stability" && opt.kind != "repeatability") {
    throw core::InputError("KIND", "'" + opt.kind +
                                       "' is not an analysis calstand has (stability, "
                                       "repeatability)");
  }
  store::Database db = open_existing_database(opt.db);
  if (opt.kind == "repeatability") {
    const auto r = analysis::analyse_repeatability(db, opt.run, opt.device);
    if (opt.as_json) {
      fmt::print("{}\n", analysis::to_json(r).dump(2));
    } else {
      print_repeatability(r);
    }
    return;
  }
  const analysis::StabilityAnalysis s =
      analysis::analyse_stability(db, opt.run, opt.device, opt.step);
  if (opt.as_json) {
    fmt::print("{}\n", analysis::to_json(s).dump(2));
  } else {
    print_stability(s);
  }
}

}  // namespace

void register_analyze(CLI::App& app) {
  auto opt = std::make_shared<AnalyzeOptions>();
  auto* cmd = app.add_subcommand(
      "analyze",
      "Datasheet analyses of a run: stability (bias instability and bias variation "
      "with its correlation time, from a long static capture)");
  cmd->add_option("kind", opt->kind, "stability | repeatability")->required();
  cmd->add_option("--db", opt->db, "Database file")->required();
  cmd->add_option("--run", opt->run, "Run id")->required();
  cmd->add_option("--device", opt->device, "IMU (default: the run's first)");
  cmd->add_option("--step", opt->step, "Static capture step (default: the longest)");
  cmd->add_flag("--json", opt->as_json, "Print the analysis as JSON");
  cmd->callback([opt] { run_analyze(*opt); });
}

}  // namespace calstand::cli
