// `calstand accept`: the newest calibration record of each unit of a run judged against a
// product specification (analysis/accept_run.hpp), the verdicts stored with their records.
#include <fmt/format.h>

#include <algorithm>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "commands.hpp"
#include "core/file_output.hpp"
#include "factory/accept_run.hpp"
#include "factory/acceptance_spec.hpp"
#include "factory/junit.hpp"
#include "open_database.hpp"

namespace calstand::cli {
namespace {

struct AcceptOptions {
  std::string db;
  std::int64_t run = 0;
  std::string spec;
  std::string device;
  std::int64_t validation_run = 0;
  std::string junit;
  bool as_json = false;
};

std::string number(const std::optional<double>& v) {
  return v ? fmt::format("{:.6g}", *v) : std::string("-");
}

std::string upper(std::string_view verdict) {
  std::string s(verdict);
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::toupper(c); });
  return s;
}

void print_unit(const analysis::UnitAcceptance& u) {
  fmt::print("\n{}{} (calibration {} of run {}): {}\n", u.device,
             u.serial.empty() ? std::string(", no serial") : ", serial " + u.serial, u.calibration,
             u.run, upper(analysis::to_string(u.verdict)));
  std::size_t width = 5;
  for (const auto& c : u.checks) width = std::max(width, c.check.size());
  fmt::print("  {:<{}}  {:>13}  {:>11}  {:<28}  {}\n", "check", width, "value", "sigma", "limit",
             "verdict");
  for (const auto& c : u.checks) {
    // A verdict other than pass is written in capitals with the reason, so it stands out.
    const bool pass = c.verdict == analysis::Verdict::kPass;
    fmt::print("  {:<{}}  {:>13}  {:>11}  {:<28}  {}{}\n", c.check, width, number(c.value),
               number(c.sigma), analysis::describe(c.limit, c.unit),
               pass ? std::string("pass") : upper(analysis::to_string(c.verdict)),
               pass ? std::string() : "  " + c.reason);
  }
  if (u.validation) {
    fmt::print("  validation: run {} corrected with the record as run {}, fitted with {}\n",
               u.validation->run, u.validation->corrected_run, u.validation->model);
  }
  if (!u.as_found) {
    fmt::print("  as found: no earlier record of this unit in force{}\n",
               u.serial.empty() ? " (the unit has no serial)" : "");
    return;
  }
  const analysis::AsFound& d = *u.as_found;
  fmt::print("  as found: calibration {} of run {} ({}, {}), drift to this calibration:\n",
             d.calibration, d.run, d.created_utc,
             d.verdict.empty() ? std::string("never judged") : "accepted: " + d.verdict);
  std::size_t pw = 9;
  for (const auto& p : d.parameters) pw = std::max(pw, p.parameter.size());
  fmt::print("    {:<{}}  {:>13}  {:>13}  {:>13}  {:>9}  {}\n", "parameter", pw, "old", "new",
             "difference", "in sigma", "unit");
  for (const auto& p : d.parameters) {
    fmt::print("    {:<{}}  {:>13.6g}  {:>13.6g}  {:>13.6g}  {:>9.2f}  {}\n", p.parameter, pw,
               p.old_value, p.new_value, p.difference, p.difference_sigmas, p.unit);
  }
}

void print_text(const analysis::AcceptanceOutcome& o) {
  fmt::print("run {} against \"{}\" ({}, sha256 {}), k = {}\n", o.run, o.spec.name, o.spec.file,
             o.spec.sha256.substr(0, 12), o.spec.k);
  fmt::print("decision rule: {}\n", analysis::decision_rule_text(o.spec.k));
  std::size_t counts[3] = {0, 0, 0};
  for (const auto& u : o.units) {
    print_unit(u);
    ++counts[static_cast<int>(u.verdict)];
  }
  fmt::print(
      "\nverdict: {} ({} unit{}: {} pass, {} indeterminate, {} fail); stored with the "
      "records\n",
      analysis::to_string(o.verdict), o.units.size(), o.units.size() == 1 ? "" : "s", counts[0],
      counts[1], counts[2]);
}

int run_accept(const AcceptOptions& opt, bool validation_given) {
  // The specification first: a bad one stores nothing.
  const analysis::AcceptanceSpec spec = analysis::read_acceptance_spec(opt.spec);
  store::Database db = open_existing_database(opt.db);
  analysis::AcceptRequest request;
  request.run = opt.run;
  request.device = opt.device;
  if (validation_given) request.validation_run = opt.validation_run;
  analysis::AcceptanceOutcome outcome = analysis::accept_run(db, spec, request);
  // The XML before the verdicts are stored: a CI job that gets no file sees no stored verdict.
  if (!opt.junit.empty()) core::write_file_whole(opt.junit, analysis::junit_xml(outcome));
  analysis::store_acceptances(db, outcome);
  if (opt.as_json) {
    fmt::print("{}\n", analysis::to_json(outcome).dump(2));
  } else {
    print_text(outcome);
  }
  return outcome.verdict == analysis::Verdict::kPass ? 0 : 1;
}

}  // namespace

void register_accept(CLI::App& app) {
  auto opt = std::make_shared<AcceptOptions>();
  auto* cmd = app.add_subcommand(
      "accept",
      "Judge the newest calibration record of each unit of a run against a specification "
      "(pass, fail, indeterminate); exit 0 when every unit passes, 1 when any fails or is "
      "indeterminate, 2 for bad input");
  cmd->add_option("--db", opt->db, "Database file")->required();
  cmd->add_option("--run", opt->run, "Run whose records to judge")->required();
  cmd->add_option("--spec", opt->spec, "Specification (calstand-acceptance/1 JSON)")->required();
  cmd->add_option("--device", opt->device, "Only this IMU (default: every unit with a record)");
  auto* validation = cmd->add_option(
      "--validation-run", opt->validation_run,
      "Run measuring the units again: corrected with their records and judged by the "
      "specification's validation limits");
  cmd->add_option("--junit", opt->junit, "Also write the checks as JUnit XML to this file");
  cmd->add_flag("--json", opt->as_json, "Print the outcome as JSON");
  cmd->callback([opt, validation] {
    if (const int code = run_accept(*opt, validation->count() > 0); code != 0) {
      throw CLI::RuntimeError(code);
    }
  });
}

}  // namespace calstand::cli
