// `calstand run`: runs a procedure in the foreground on a station (the embedded simulated one
// by default), recording everything in a SQLite file; `--resume RUN_ID` continues a run that
// was cut off (power loss, kill -9) at its first unfinished step. Ctrl-C aborts to the safe
// state; `kill -USR1` pauses at the next step boundary, `kill -USR2` at once, `kill -CONT`
// resumes.
#include <fmt/format.h>

#include <atomic>
#include <csignal>
#include <memory>
#include <string>
#include <vector>

#include "commands.hpp"
#include "core/error.hpp"
#include "core/station_config.hpp"
#include "daemon/campaign.hpp"
#include "daemon/run_engine.hpp"
#include "daemon/stored_run.hpp"
#include "procedures/plan.hpp"
#include "procedures/procedure.hpp"
#include "progress_bar.hpp"
#include "sim/sim_world.hpp"
#include "store/database.hpp"
#include "store/database_lock.hpp"
#include "store/disk_space.hpp"
#include "store/run_lock.hpp"
#include "store/run_store.hpp"
#include "unit_option.hpp"

namespace calstand::cli {
namespace {

struct RunOptions {
  std::string procedure;
  std::string station_file;
  std::string db = "calstand.db";
  std::vector<std::string> set_args;
  std::vector<std::string> unit_args;  ///< NAME=SERIAL
  std::int64_t resume_run = 0;
  bool quiet = false;
};

// Operator signals, seen by the engine thread at its next tick (a handler may only set flags):
// SIGINT/SIGTERM/SIGHUP abort to the safe state (SIGHUP: the terminal went away, a closed SSH
// session or a killed tmux; the progress bar falls silent, nobody reads it), SIGUSR1 pauses at
// the next step boundary, SIGUSR2 pauses at once (the capture in progress is repeated), SIGCONT
// resumes.
std::atomic<int> g_stop_signal{0};
std::atomic<int> g_pause_signal{0};
std::atomic<bool> g_resume_signal{false};
extern "C" void on_stop_signal(int sig) { g_stop_signal = sig; }
extern "C" void on_pause_signal(int sig) { g_pause_signal = sig; }
extern "C" void on_resume_signal(int) { g_resume_signal = true; }

// Runs `plan` as run `run_id` from `start`; returns the process exit code.
int execute_plan(const core::StationConfig& station_config, const procedures::Plan& plan,
                 const std::string& db_path, std::int64_t run_id,
                 const daemon::CampaignStart& start, bool quiet) {
  ProgressBar bar;
  bool hung_up = false;  // engine thread only, until the run ends
  std::signal(SIGINT, on_stop_signal);
  std::signal(SIGTERM, on_stop_signal);
  std::signal(SIGHUP, on_stop_signal);
  std::signal(SIGUSR1, on_pause_signal);
  std::signal(SIGUSR2, on_pause_signal);
  std::signal(SIGCONT, on_resume_signal);
  const auto result = daemon::run_campaign(
      station_config, plan, db_path, run_id, start,
      [&](daemon::RunEngine& engine, const daemon::Progress& p) {
        if (const int sig = g_stop_signal.exchange(0); sig != 0) {
          if (sig == SIGHUP) hung_up = true;
          engine.abort(sig == SIGINT   ? "interrupted (SIGINT)"
                       : sig == SIGHUP ? "hangup (SIGHUP: the terminal went away)"
                                       : "terminated (SIGTERM)",
                       "signal");
        }
        if (const int sig = g_pause_signal.exchange(0); sig != 0) {
          engine.pause(sig == SIGUSR2, sig == SIGUSR2 ? "signal SIGUSR2" : "signal SIGUSR1");
        }
        if (g_resume_signal.exchange(false) && p.state == daemon::RunState::kPaused) {
          engine.resume("signal SIGCONT");
        }
        if (!quiet && !hung_up) bar.update(p);
      });
  for (int sig : {SIGINT, SIGTERM, SIGHUP, SIGUSR1, SIGUSR2, SIGCONT}) std::signal(sig, SIG_DFL);
  if (!hung_up) bar.finish();

  const int exit_code = result.state == daemon::RunState::kCompleted ? 0 : 1;
  if (hung_up) return exit_code;  // no terminal to tell: the run and its reason are stored
  store::Database db(db_path);
  store::RunStore run_store(db);
  const auto summary = run_store.load_run(run_id).summary;
  fmt::print("run {} {}: {}/{} steps, station time {}{}\n", run_id, to_string(result.state),
             summary.steps_done, summary.steps_total, format_duration(result.station_time_s),
             result.exit_reason.empty() ? "" : " (" + result.exit_reason + ")");
  return exit_code;
}

int run_new(const RunOptions& opt) {
  const core::StationConfig station = sim::load_station_or_default(opt.station_file);
  const procedures::Procedure procedure = procedures::load_procedure(opt.procedure);
  const procedures::Plan plan =
      procedures::make_plan(procedure, station, procedures::parse_overrides(opt.set_args));
  procedures::require_valid(plan);  // every violation, before anything is written or moves
  const daemon::UnitSerials units = parse_unit_options(opt.unit_args);
  daemon::units_for_run(station, units);  // a unit unknown or without its serial, likewise
  const store::DatabaseLock lock(opt.db, store::DatabaseLock::Mode::kShared, "calstand run");
  if (const auto why = store::disk_space_shortfall(opt.db, station.policy.min_free_disk_mb)) {
    throw core::InputError(opt.db, *why);  // before the run is recorded or anything moves
  }

  std::int64_t run_id = 0;
  {
    store::Database db(opt.db);
    store::RunStore run_store(db);
    run_id = daemon::create_run_record(run_store, station, procedure, plan, units);
  }
  fmt::print("run {}: {} ({} steps, estimated {}) into {}\n", run_id, procedure.name,
             plan.steps.size(), format_duration(plan.total_s), opt.db);
  std::fflush(stdout);
  return execute_plan(station, plan, opt.db, run_id, {}, opt.quiet);
}

int run_resume(const RunOptions& opt) {
  const store::DatabaseLock lock(opt.db, store::DatabaseLock::Mode::kShared,
                                 "calstand run --resume");
  store::Database db(opt.db);
  store::RunStore run_store(db);
  // The run's own procedure, parameters and station; cut-off attempts discarded.
  if (const std::string status = run_store.load_run(opt.resume_run).summary.status;
      status == "queued") {
    // Never started; it waits in calstandd's queue (the daemon is not running, or the lock
    // above would have refused this): start the daemon, or abort it there.
    throw core::InputError("--resume",
                           fmt::format("run {} is queued for calstandd and never started; "
                                       "start the daemon or abort the run",
                                       opt.resume_run));
  }
  if (store::RunLock::held(opt.db, opt.resume_run)) {
    throw store::DatabaseBusy(fmt::format(
        "{}: run {} is being run by another process (a foreground `calstand run`); it needs no "
        "resume",
        opt.db, opt.resume_run));
  }
  const daemon::StoredRun stored = daemon::prepare_stored_run(run_store, opt.resume_run);
  if (const auto why =
          store::disk_space_shortfall(opt.db, stored.station.policy.min_free_disk_mb)) {
    throw core::InputError(opt.db, *why);
  }
  store::EventRecord e;
  e.run_id = opt.resume_run;
  e.time_s = stored.start.start_time_s;
  e.kind = store::EventKind::kOperator;
  e.source = "operator";
  e.message = fmt::format("resume requested at step {}", stored.start.first_step);
  run_store.add_event(e);
  fmt::print("run {}: resuming {} at step {}/{}\n", opt.resume_run, stored.procedure_name,
             stored.start.first_step + 1, stored.plan.steps.size());
  std::fflush(stdout);
  return execute_plan(stored.station, stored.plan, opt.db, opt.resume_run, stored.start, opt.quiet);
}

}  // namespace

void register_run(CLI::App& app) {
  auto opt = std::make_shared<RunOptions>();
  CLI::App* cmd = app.add_subcommand(
      "run", "Run a procedure (library name or file) on the station, recording into SQLite");
  cmd->add_option("procedure", opt->procedure, "Library name or procedure file");
  cmd->add_option("--station", opt->station_file, "Station file (default: built-in simulator)");
  cmd->add_option("--db", opt->db, "SQLite database file")->capture_default_str();
  cmd->add_option("--set", opt->set_args, "Override a parameter: NAME=VALUE (JSON)");
  cmd->add_option("--unit", opt->unit_args,
                  "The unit in an IMU slot: NAME=SERIAL (repeat per unit; checked against the "
                  "serial the device reports)");
  cmd->add_option("--resume", opt->resume_run, "Resume the interrupted run RUN_ID");
  cmd->add_flag("--quiet", opt->quiet, "No progress bar");
  cmd->callback([opt] {
    int code = 0;
    if (opt->resume_run > 0) {
      code = run_resume(*opt);
    } else {
      if (opt->procedure.empty())
        throw core::InputError("run", "a PROCEDURE or --resume RUN_ID is needed");
      code = run_new(*opt);
    }
    if (code != 0) throw CLI::RuntimeError(code);
  });
}

}  // namespace calstand::cli
