// `calstand runs` and `calstand show`: what a database holds, for people and for scripts.
#include <fmt/format.h>

#include <algorithm>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "commands.hpp"
#include "core/error.hpp"
#include "open_database.hpp"
#include "store/database.hpp"
#include "store/run_json.hpp"
#include "store/run_store.hpp"
#include "store/step_data.hpp"
#include "table_free_printer.hpp"

namespace calstand::cli {
namespace {

struct RunsOptions {
  std::string db = "calstand.db";
  std::int64_t run = 0;
  bool as_json = false;
  std::int64_t limit = -1;  ///< runs: the newest this many (-1: not given, every run)
  StaticPoseOptions poses;  ///< show: a run without a table
};

void list_runs(const RunsOptions& opt) {
  store::Database db = open_existing_database(opt.db);
  store::RunStore runs(db);
  if (opt.limit != -1 && opt.limit < 1) {
    throw core::InputError("--limit", fmt::format("must be at least 1, got {}", opt.limit));
  }
  const auto list = runs.list_runs(
      opt.limit > 0 ? std::optional(static_cast<std::size_t>(opt.limit)) : std::nullopt);
  if (opt.as_json) {
    nlohmann::json out = nlohmann::json::array();
    for (const auto& r : list) out.push_back(store::to_json(r));
    fmt::print("{}\n", out.dump(2));
    return;
  }
  fmt::print("{:>5}  {:<22} {:<10} {:>11}  {:<24} {:<24}\n", "id", "procedure", "status", "steps",
             "start", "end");
  for (const auto& r : list) {
    fmt::print("{:>5}  {:<22} {:<10} {:>5}/{:<5}  {:<24} {:<24}{}\n", r.id, r.procedure_name,
               r.status, r.steps_done, r.steps_total, r.started_utc, r.ended_utc,
               r.exit_reason.empty() ? "" : "  " + r.exit_reason);
  }
}

// A run without a table whose steps are not labelled sections: its static poses come from the
// detector (or the operator's intervals), and `show` lists them as a fit would use them.
bool shows_static_poses(store::Database& db, const store::RunRecord& r) {
  if (store::orientation_known(db, r.summary.id) || r.steps.empty()) return false;
  return std::none_of(r.steps.begin(), r.steps.end(),
                      [](const store::StepRecord& s) { return s.commanded.contains("section"); });
}

void show_run(const RunsOptions& opt) {
  store::Database db = open_existing_database(opt.db);
  store::RunStore runs(db);
  const store::RunRecord r = runs.load_run(opt.run);
  if (opt.as_json) {
    nlohmann::json steps = nlohmann::json::array();
    for (const auto& s : r.steps) steps.push_back(store::to_json(s));
    nlohmann::json events = nlohmann::json::array();
    for (const auto& e : r.events) events.push_back(store::to_json(e));
    nlohmann::json out = store::to_json(r.summary);
    out["parameters"] = r.parameters;
    out["procedure_sha256"] = r.procedure_sha256;
    out["units"] = store::units_json(r.units);
    out["steps"] = steps;
    out["events"] = events;
    if (shows_static_poses(db, r)) {
      try {
        out["static_poses"] = analysis::to_json(
            analysis::table_free_poses(db, opt.run, static_pose_request(opt.poses, "")));
      } catch (const core::InputError& e) {
        out["static_poses"] = {{"error", e.what()}};
      }
    }
    fmt::print("{}\n", out.dump(2));
    return;
  }
  const auto& s = r.summary;
  fmt::print("run {}: {} [{}], {}/{} steps, started {}, ended {}{}\n", s.id, s.procedure_name,
             s.status, s.steps_done, s.steps_total, s.started_utc.empty() ? "-" : s.started_utc,
             s.ended_utc.empty() ? "-" : s.ended_utc,
             s.exit_reason.empty() ? "" : "\n  exit reason: " + s.exit_reason);
  fmt::print("parameters: {}\n", r.parameters.dump());
  for (const auto& u : r.units) {
    fmt::print("unit in {}: {} {} ({})\n", u.imu, u.model.empty() ? "-" : u.model,
               u.serial.empty() ? "(no serial)" : u.serial,
               u.source == "device"      ? "read from the device"
               : u.source == "submitted" ? "given with the run"
                                         : "from the station file");
  }
  fmt::print("\n");
  fmt::print("{:>5}  {:<16} {:<11} {:>3}  {:>10} {:>10}  {}\n", "step", "kind", "status", "try",
             "start [s]", "end [s]", "label");
  for (const auto& st : r.steps) {
    fmt::print("{:>5}  {:<16} {:<11} {:>3}  {:>10} {:>10}  {}{}\n", st.index, st.kind,
               store::to_string(st.status), st.attempts,
               st.started_clock_s ? fmt::format("{:.1f}", *st.started_clock_s) : "-",
               st.ended_clock_s ? fmt::format("{:.1f}", *st.ended_clock_s) : "-", st.label,
               st.reason.empty() ? "" : "  (" + st.reason + ")");
  }
  fmt::print("\nevents:\n");
  for (const auto& e : r.events) {
    fmt::print("{:>10.1f}  {:<9} {:<15} {}\n", e.time_s, store::to_string(e.kind), e.source,
               e.message);
  }
  // A recording without a table: the static poses a fit would use (labelled sections are
  // their own steps, listed above).
  if (shows_static_poses(db, r)) {
    fmt::print("\n");
    try {
      print_static_poses(
          analysis::table_free_poses(db, opt.run, static_pose_request(opt.poses, "")));
    } catch (const core::InputError& e) {
      fmt::print("static poses: none found: {}\n", e.what());
    }
  }
}

}  // namespace

void register_runs(CLI::App& app) {
  auto opt = std::make_shared<RunsOptions>();
  CLI::App* runs = app.add_subcommand("runs", "List the runs of a database");
  runs->add_option("--db", opt->db, "SQLite database file")->capture_default_str();
  runs->add_flag("--json", opt->as_json, "Machine-readable output");
  runs->add_option("--limit", opt->limit, "Only the newest N runs");
  runs->callback([opt] { list_runs(*opt); });

  CLI::App* show = app.add_subcommand("show", "Show one run: its steps and events");
  show->add_option("--db", opt->db, "SQLite database file")->capture_default_str();
  show->add_option("--run", opt->run, "Run id")->required();
  show->add_flag("--json", opt->as_json, "Machine-readable output");
  add_static_pose_options(show, opt->poses);
  show->callback([opt] { show_run(*opt); });
}

}  // namespace calstand::cli
