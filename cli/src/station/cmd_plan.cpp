// `calstand plan PROCEDURE`: expands a procedure (library name or file) with its parameters,
// estimates each step's start and duration on a station, shows the envelope and checks the
// station's limits. Nothing moves; exit 2 with every violation when the procedure is invalid.
#include <fmt/format.h>

#include <cmath>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "analysis/run_model.hpp"
#include "commands.hpp"
#include "core/station_config.hpp"
#include "factory/plan_coverage.hpp"
#include "procedures/plan.hpp"
#include "procedures/procedure.hpp"
#include "sim/sim_world.hpp"

namespace calstand::cli {
namespace {

struct PlanOptions {
  std::string procedure;
  std::string station_file;
  std::vector<std::string> set_args;
  std::string model = analysis::kDefaultModel;  ///< the terms coverage is checked for
  bool as_json = false;
};

// h:mm:ss, with `decimals` digits of the seconds.
std::string hms(double seconds, int decimals = 0) {
  const double scale = std::pow(10.0, decimals);
  const double rounded = std::round(seconds * scale) / scale;
  const auto whole = static_cast<long long>(std::floor(rounded));
  const double frac_s = rounded - static_cast<double>(whole) + static_cast<double>(whole % 60);
  return decimals == 0 ? fmt::format("{}:{:02}:{:02}", whole / 3600, whole / 60 % 60, whole % 60)
                       : fmt::format("{}:{:02}:{:0{}.{}f}", whole / 3600, whole / 60 % 60, frac_s,
                                     decimals + 3, decimals);
}

std::string format_number(double v) { return fmt::format("{:g}", v); }

// The commanded values of a step, in the file's terms.
std::string commanded(const procedures::Step& s) {
  using procedures::StepKind;
  switch (s.kind) {
    case StepKind::kSetTemperature: {
      std::string text = fmt::format("target {} degC", format_number(s.target_c));
      if (s.ramp_c_per_min)
        text += fmt::format(", ramp {} degC/min", format_number(*s.ramp_c_per_min));
      if (s.wait_for_soak) {
        text += fmt::format(", soak +-{} degC for {} s (timeout {} s)",
                            format_number(s.soak.tolerance_c), format_number(s.soak.stable_s),
                            format_number(s.soak.timeout_s));
      } else {
        text += ", no soak (ramps on)";
      }
      return text;
    }
    case StepKind::kMove:
      return fmt::format("{}outer {} deg, inner {} deg",
                         s.up.empty() ? "" : fmt::format("{} up: ", s.up),
                         format_number(s.outer_deg), format_number(s.inner_deg));
    case StepKind::kRate: {
      std::string text = fmt::format("{} {:+g} deg/s, settle {} s, record {} s", s.axis, s.rate_dps,
                                     format_number(s.settle_s), format_number(s.duration_s));
      if (s.revolutions) text += fmt::format(" ({} rev)", format_number(*s.revolutions));
      if (!s.rest_after) text += ", stays at rate";
      return text;
    }
    case StepKind::kCapture:
      return fmt::format("record {} s", format_number(s.duration_s));
    case StepKind::kWait:
      return fmt::format("{} s", format_number(s.duration_s));
    case StepKind::kPower:
      return fmt::format("supply of {} {}, settle {} s", s.imu.empty() ? "every IMU" : s.imu,
                         s.power_on ? "on" : "off", format_number(s.settle_s));
    case StepKind::kOscillate:
      return fmt::format(
          "{} sine {} deg at {} Hz (peak {} deg/s, {} deg/s^2), settle {} cycles, "
          "record {} cycles ({} s)",
          s.axis, format_number(s.amplitude_deg), format_number(s.frequency_hz),
          format_number(s.peak_rate_dps()), format_number(s.peak_accel_dps2()),
          format_number(s.settle_cycles), format_number(s.cycles), format_number(s.duration_s));
  }
  return "";
}

std::string parameter_line(const procedures::Plan& plan) {
  std::string text;
  for (const auto& [name, value] : plan.parameters) {
    text += (text.empty() ? "" : " ") + name + "=" + value.dump();
  }
  return text.empty() ? "(none)" : text;
}

void print_axis(const char* name, const procedures::AxisEnvelope& a, const core::AxisConfig& cfg) {
  if (a.max_accel_dps2 == 0.0) {
    fmt::print("  {} axis    does not move\n", name);
    return;
  }
  fmt::print(
      "  {} axis    rate steps up to {} deg/s, moves up to {} deg/s, accel {} deg/s^2 "
      "(limits {} deg/s, {} deg/s^2)\n",
      name, format_number(a.max_rate_dps), format_number(a.max_move_rate_dps),
      format_number(a.max_accel_dps2), format_number(cfg.max_rate_dps),
      format_number(cfg.max_accel_dps2));
}

void print_text(const procedures::Plan& plan, const core::StationConfig& station) {
  fmt::print("procedure {} ({}) on station {}\n", plan.procedure, plan.file_name, station.name);
  fmt::print("parameters {}\n\n", parameter_line(plan));
  fmt::print("{:>5}  {:>11}  {:>11}  {:<15}  {:<40}  {}\n", "step", "start", "duration", "kind",
             "label", "commanded");
  for (std::size_t i = 0; i < plan.steps.size(); ++i) {
    const auto& s = plan.steps[i];
    fmt::print("{:>5}  {:>11}  {:>11}  {:<15}  {:<40}  {}\n", s.index, hms(plan.step_start_s[i]),
               hms(plan.step_duration_s[i], 1), procedures::to_string(s.kind), s.label,
               commanded(s));
  }
  const auto& e = plan.envelope;
  fmt::print(
      "\ntotal {} ({} steps; estimate: no chamber or IMU thermal lag, soaks at their "
      "stable time)\n",
      hms(plan.total_s), plan.steps.size());
  fmt::print("envelope\n");
  print_axis("outer", e.outer, station.table.outer);
  print_axis("inner", e.inner, station.table.inner);
  if (e.min_temperature_c) {
    fmt::print(
        "  temperature  {} to {} degC, ramps up to {} degC/min (chamber {} to {} degC, "
        "{} degC/min)\n",
        format_number(*e.min_temperature_c), format_number(*e.max_temperature_c),
        format_number(e.max_ramp_c_per_min), format_number(station.chamber.min_c),
        format_number(station.chamber.max_c), format_number(station.chamber.max_ramp_c_per_min));
  } else {
    fmt::print("  temperature  chamber not used\n");
  }
  fmt::print("  recording    {} captures, {} in total\n", e.captures, hms(e.capture_s));
  if (plan.ok()) {
    fmt::print("check: ok (procedure rules and station limits)\n");
  } else {
    fmt::print("check: FAILED, {} violation{} (listed on stderr)\n", plan.violations.size(),
               plan.violations.size() == 1 ? "" : "s");
  }
}

// Per unit, what the procedure leaves undetermined of the model; on a fixture this is where a
// unit whose mount the pointing was not resolved for shows an axis the procedure never excites.
void print_coverage(const analysis::PlanCoverage& coverage) {
  fmt::print("\nwhat each unit's data determine of {}:\n", coverage.model);
  for (const analysis::UnitCoverage& u : coverage.units) {
    if (u.undetermined.empty()) {
      fmt::print("  {:<8} every parameter\n", u.imu);
      continue;
    }
    fmt::print("  {:<8} NOT {} parameter{}:\n", u.imu, u.undetermined.size(),
               u.undetermined.size() == 1 ? "" : "s");
    for (const auto& p : u.undetermined) fmt::print("             {:<28} {}\n", p.name, p.reason);
  }
}

void run_plan(const PlanOptions& opt) {
  const core::StationConfig station = sim::load_station_or_default(opt.station_file);
  const procedures::Overrides overrides = procedures::parse_overrides(opt.set_args);
  const procedures::Procedure procedure = procedures::load_procedure(opt.procedure);
  const procedures::Plan plan = procedures::make_plan(procedure, station, overrides);
  const analysis::PlanCoverage coverage =
      analysis::plan_coverage(plan, station, solver::Model::parse(opt.model));
  if (opt.as_json) {
    nlohmann::json out = plan.to_json();
    out["coverage"] = analysis::to_json(coverage);
    fmt::print("{}\n", out.dump(2));
  } else {
    print_text(plan, station);
    print_coverage(coverage);
  }
  procedures::require_valid(plan);  // exit 2 through main, every violation on stderr
}

}  // namespace

void register_plan(CLI::App& app) {
  auto opt = std::make_shared<PlanOptions>();
  CLI::App* cmd = app.add_subcommand(
      "plan",
      "Expand a procedure and preview it on a station: steps, durations, envelope, "
      "limit check (nothing moves)");
  cmd->add_option("procedure", opt->procedure, "Library procedure name or procedure file")
      ->required();
  cmd->add_option("--station", opt->station_file, "Station file (default: built-in simulator)");
  cmd->add_option("--model", opt->model,
                  "Terms whose determination per unit is checked (default: the fit's default)")
      ->capture_default_str();
  cmd->add_option("--set", opt->set_args,
                  "Parameter override NAME=VALUE, VALUE as JSON (e.g. temperatures=[-40,25,85])")
      ->allow_extra_args(false);
  cmd->add_flag("--json", opt->as_json, "The plan as JSON");
  cmd->callback([opt] { run_plan(*opt); });
}

}  // namespace calstand::cli
