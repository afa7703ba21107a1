#include "daemon/service/run_service.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <set>

#include "core/error.hpp"
#include "core/state_json.hpp"
#include "daemon/campaign.hpp"
#include "daemon/run_engine.hpp"
#include "daemon/run_state.hpp"
#include "daemon/service/log_fields.hpp"
#include "daemon/service/observed_journal.hpp"
#include "daemon/service/station_watch.hpp"
#include "daemon/station_run.hpp"
#include "daemon/stored_run.hpp"
#include "drivers/station.hpp"
#include "procedures/plan.hpp"
#include "store/capture_writer.hpp"
#include "store/database.hpp"
#include "store/disk_space.hpp"
#include "store/error.hpp"
#include "store/run_queue.hpp"
#include "store/run_store.hpp"

namespace calstand::daemon::service {
namespace {

// Device states and fault counters are read this often while a run goes (wall time): cheap,
// but a simulated station ticks thousands of times a second.
constexpr auto kDeviceReadPeriod = std::chrono::milliseconds(250);
// Between runs the table and the chamber are read this often (and the queue looked at).
constexpr auto kIdleReadPeriod = std::chrono::seconds(1);

constexpr double kBytesPerMb = 1024.0 * 1024.0;

// The latest station time a run recorded [s] (where a stopped run's clock stands).
double last_station_time_s(const store::RunRecord& record) {
  double t = record.started_clock_s.value_or(0.0);
  for (const auto& s : record.steps) {
    t = std::max({t, s.started_clock_s.value_or(0.0), s.ended_clock_s.value_or(0.0)});
  }
  for (const auto& e : record.events) t = std::max(t, e.time_s);
  return t;
}

// The names a run's events give as their source when a device speaks.
std::set<std::string> device_names(const core::StationConfig& station) {
  std::set<std::string> names;
  for (const auto& d : offline_devices(station)) names.insert(d.name);
  for (const auto& s : station.power_supplies) names.insert(s.name);
  return names;
}

}  // namespace

RecoveryPolicy parse_recovery_policy(const std::string& name, const std::string& where) {
  if (name == "auto") return RecoveryPolicy::kAuto;
  if (name == "hold") return RecoveryPolicy::kHold;
  throw core::InputError(where, fmt::format("'{}' is not a recovery policy (auto or hold)", name));
}

RunService::RunService(ServiceOptions options, EventHub& hub)
    : options_(std::move(options)), hub_(hub), idle_watch_(options_.station) {
  live_.update([&](LiveSnapshot& s) { s.devices = offline_devices(options_.station); });
}

RunService::~RunService() { stop("service destroyed"); }

void RunService::start() {
  std::lock_guard lock(mutex_);
  if (thread_.joinable() || stopping_) return;
  thread_ = std::thread([this] { run_thread(); });
}

void RunService::stop(const std::string& why) {
  {
    std::lock_guard lock(mutex_);
    if (!stopping_) {
      stopping_ = true;
      if (current_) {
        commands_->push({EngineCommand::Kind::kInterrupt, false, std::nullopt,
                         "checkpoint: daemon stopping (" + why + ")", "daemon"});
      }
    }
    ++generation_;
  }
  wake_.notify_all();
  if (thread_.joinable() && thread_.get_id() != std::this_thread::get_id()) thread_.join();
}

void RunService::set_heartbeat(std::function<void()> beat, std::chrono::milliseconds period) {
  std::lock_guard lock(mutex_);
  if (thread_.joinable()) throw std::logic_error("RunService::set_heartbeat after start()");
  heartbeat_ = std::move(beat);
  heartbeat_period_ = period;
}

void RunService::run_thread() {
  while (true) {
    if (heartbeat_) heartbeat_();
    std::uint64_t seen = 0;
    {
      std::lock_guard lock(mutex_);
      if (stopping_) break;
      seen = generation_;
    }
    bool failed = false;
    try {
      serve_interlock_request();
      if (const auto next = next_run()) {
        execute(next->first, next->second);
        continue;
      }
    } catch (const std::exception& e) {
      // A storage failure: logged, and retried after the wait below rather than in a loop.
      spdlog::error("run queue: {}", e.what());
      failed = true;
    } catch (...) {
      // Nothing else may end the run thread (the daemon would serve a station nobody drives).
      spdlog::error("run queue: unknown exception");
      failed = true;
    }
    if (!failed) watch_idle();
    std::unique_lock lock(mutex_);
    // Back round the loop at least every heartbeat period (the beat comes from there). After
    // a storage failure the retry still waits its 5 s, beating meanwhile.
    const auto until = std::chrono::steady_clock::now() +
                       (failed ? std::chrono::milliseconds(5000) : kIdleReadPeriod);
    while (!stopping_ && (failed || generation_ == seen)) {
      const auto now = std::chrono::steady_clock::now();
      if (now >= until) break;
      wake_.wait_for(lock,
                     std::min<std::chrono::steady_clock::duration>(until - now, heartbeat_period_));
      if (heartbeat_ && !stopping_ && std::chrono::steady_clock::now() < until) {
        lock.unlock();
        heartbeat_();
        lock.lock();
      }
    }
  }
  idle_watch_.release();
}

void RunService::watch_idle() {
  IdleStationWatch::Reading reading;
  try {
    reading = idle_watch_.read();
  } catch (const std::exception& e) {
    spdlog::warn("station between runs: {}", e.what());
    return;
  }
  live_.update([&](LiveSnapshot& s) {
    s.devices = reading.devices;
    if (reading.table) s.table = reading.table;
    if (reading.chamber) s.chamber = reading.chamber;
  });
  if (!reading.table && !reading.chamber) return;
  nlohmann::json data = {{"run", nullptr}};
  if (reading.table) data["table"] = core::to_json(*reading.table);
  if (reading.chamber) data["chamber"] = core::to_json(*reading.chamber);
  hub_.publish("telemetry", std::move(data));
}

std::optional<std::pair<std::int64_t, bool>> RunService::next_run() {
  {
    std::lock_guard lock(mutex_);
    if (stopping_) return std::nullopt;
    if (held_) {
      if (!resume_held_) return std::nullopt;
      const std::int64_t run = *held_;
      held_.reset();
      resume_held_ = false;
      live_.update([](LiveSnapshot& s) { s.held.reset(); });
      return std::make_pair(run, true);
    }
  }
  std::optional<std::pair<std::int64_t, bool>> candidate;
  {
    store::Database db(options_.db_path);
    const auto interrupted = store::interrupted_runs(db);
    if (!interrupted.empty()) {
      // A run already held (paused by an operator when the daemon stopped, or held before a
      // crash) waits for an operator whatever the policy.
      const bool held = store::RunStore(db).run_status(interrupted.front()) == store::kHeldStatus;
      if (options_.recovery != RecoveryPolicy::kAuto || held) {
        hold(interrupted.front());
        return std::nullopt;
      }
      candidate = std::make_pair(interrupted.front(), true);
    } else if (const auto queued = store::queued_runs(db); !queued.empty()) {
      candidate = std::make_pair(queued.front().run, false);
    }
  }
  if (!candidate) {
    note_waiting(0, std::nullopt);
    return std::nullopt;
  }
  // A run that cannot start now waits, with the reason shown, and starts by itself once the
  // cause is gone: nobody has to submit it again.
  const auto why = start_blocker();
  note_waiting(candidate->first, why);
  if (why) return std::nullopt;
  return candidate;
}

std::optional<std::string> RunService::disk_shortfall() {
  if (auto why =
          store::disk_space_shortfall(options_.db_path, options_.station.policy.min_free_disk_mb)) {
    return why;
  }
  if (measure_after_full_.exchange(false)) {
    // A new run needs its disk reserve too. The write-ahead log is counted as free: it goes
    // when the last connection closes, which may be a reader's after this reading, and its
    // bytes are the stopped run's own, not space an operator freed.
    const auto policy = options_.station.policy;
    free_bytes_needed_after_full_ =
        store::free_bytes_counting_wal(options_.db_path) +
        static_cast<std::uint64_t>((policy.min_free_disk_mb + policy.disk_reserve_mb) *
                                   kBytesPerMb);
  }
  if (const std::uint64_t needed = free_bytes_needed_after_full_; needed > 0) {
    const std::uint64_t free = store::free_bytes_counting_wal(options_.db_path);
    if (free < needed) {
      return fmt::format(
          "disk full: the last run stopped on a full disk; {:.1f} MB free now, waiting for "
          "{:.1f} MB (what was free then plus the station policy's min_free_disk_mb and "
          "disk_reserve_mb)",
          static_cast<double>(free) / kBytesPerMb, static_cast<double>(needed) / kBytesPerMb);
    }
    free_bytes_needed_after_full_ = 0;
  }
  return std::nullopt;
}

std::optional<std::string> RunService::start_blocker() {
  if (auto why = disk_shortfall()) return why;
  // Read now, not the last idle reading: an interlock may have opened a moment ago.
  const auto reading = idle_watch_.read();
  if (!reading.table) return std::nullopt;  // a link that is down fails the run's bring-up
  for (const auto* axis : {&reading.table->outer, &reading.table->inner}) {
    if (axis->fault && axis->fault_text.rfind("interlock open", 0) == 0) {
      return fmt::format(
          "table {} axis {} (latched): an operator must close it (calstand device table "
          "close-interlock, or POST /station/interlock/close)",
          axis == &reading.table->outer ? "outer" : "inner", axis->fault_text);
    }
  }
  return std::nullopt;
}

void RunService::note_waiting(std::int64_t run, const std::optional<std::string>& why) {
  if (why == waiting_reason_) return;
  waiting_reason_ = why;
  live_.update([&](LiveSnapshot& s) { s.waiting = why; });
  if (!why) return;
  spdlog::warn("run {}: waiting to start: {}", run, *why);
  try {
    record_event(run, "daemon", "waiting to start: " + *why, false);
  } catch (const std::exception& e) {
    // A full disk may refuse even this line; the live status still says why.
    spdlog::error("run {}: recording the wait: {}", run, e.what());
  }
}

void RunService::serve_interlock_request() {
  std::shared_ptr<InterlockRequest> request;
  {
    std::lock_guard lock(mutex_);
    request = std::move(interlock_request_);
  }
  if (!request) return;
  try {
    const drivers::InterlockClosure closure = idle_watch_.close_interlocks();
    store::EventRecord e;  // station-wide: no run
    e.kind = store::EventKind::kOperator;
    e.source = request->who;
    e.message = !closure.result ? "interlock close refused: " + closure.result.message
                : closure.closed.empty()
                    ? std::string("interlock close: none was latched")
                    : "interlock closed: " + fmt::format("{}", fmt::join(closure.closed, ", "));
    {
      store::Database db(options_.db_path);
      store::RunStore(db).add_event(e);
    }
    spdlog::info("{} ({})", e.message, request->who);
    hub_.publish("event", {{"run", nullptr},
                           {"kind", std::string(to_string(e.kind))},
                           {"source", e.source},
                           {"message", e.message}});
    request->done.set_value(closure);
  } catch (...) {
    request->done.set_exception(std::current_exception());
  }
}

drivers::InterlockClosure RunService::close_interlocks(const std::string& who) {
  auto request = std::make_shared<InterlockRequest>();
  request->who = who;
  auto done = request->done.get_future();
  {
    std::lock_guard lock(mutex_);
    if (stopping_) throw ActionRefused("the daemon is stopping");
    if (current_) {
      throw ActionRefused(fmt::format(
          "run {} is on the station: interlocks are closed between runs (pause and abort it, "
          "or wait for its end)",
          *current_));
    }
    if (interlock_request_) throw ActionRefused("another interlock close is under way");
    interlock_request_ = request;
    ++generation_;
  }
  wake_.notify_all();
  // The run thread serves it at the top of its loop: within a second or two of idle reading.
  if (done.wait_for(std::chrono::seconds(60)) != std::future_status::ready) {
    std::lock_guard lock(mutex_);
    if (interlock_request_ == request) interlock_request_.reset();
    throw ActionRefused("the station did not take the interlock close within 60 s");
  }
  return done.get();
}

void RunService::hold(std::int64_t run) {
  spdlog::warn(
      "run {}: interrupted; held with the station safe until an operator resumes or aborts it",
      run);
  {
    std::lock_guard lock(mutex_);
    held_ = run;
    resume_held_ = false;
  }
  store::Database db(options_.db_path);
  const bool was_held = store::RunStore(db).run_status(run) == store::kHeldStatus;
  store::mark_run_resumable(db, run, store::kHeldStatus,
                            was_held ? "interrupted while paused; held for an operator"
                                     : "interrupted; held for an operator (recovery policy hold)");
  // The devices may be wherever the interruption left them: bring them up and make them safe.
  idle_watch_.release();
  std::string safe_outcome = "station made safe";
  try {
    auto station = drivers::make_station(options_.station);
    if (auto r = station->bring_up(); !r) {
      safe_outcome = "station bring-up failed: " + r.message;
    } else if (auto s = station->make_safe(); !s) {
      safe_outcome = "making the station safe failed: " + s.message;
    }
  } catch (const std::exception& e) {
    safe_outcome = std::string("station unavailable: ") + e.what();
  }
  record_event(run, "daemon",
               fmt::format("held after an interruption ({}): {}; waiting for resume or abort",
                           was_held ? "it was paused" : "recovery policy hold", safe_outcome),
               false);
  live_.update([&](LiveSnapshot& s) { s.held = run; });
  hub_.publish("run", {{"run", run}, {"state", store::kHeldStatus}, {"reason", safe_outcome}});
}

void RunService::fail_before_start(std::int64_t run, const std::string& why) {
  spdlog::error("run {}: cannot start: {}", run, why);
  store::Database db(options_.db_path);
  store::RunStore runs(db);
  runs.set_run_status(run, "failed", std::nullopt, store::Stamp::now(0.0), "cannot start: " + why);
  store::dequeue_run(db, run);
  record_event(run, "daemon", "cannot start: " + why, false);
  hub_.publish("run", {{"run", run}, {"state", "failed"}, {"reason", why}});
}

void RunService::execute(std::int64_t run, bool resuming) {
  {
    std::lock_guard lock(mutex_);
    if (stopping_) return;  // a queued run stays queued; an interrupted one stays interrupted
    // Claimed under the lock abort() holds while it ends a queued run: a run aborted while it
    // was being picked from the queue does not start.
    if (has_ended(status_of(run))) return;
    current_ = run;
    commands_->clear();
    if (interlock_request_) {
      // Asked for while this run was being picked: the devices are the run's now.
      drivers::InterlockClosure refused;
      refused.result = drivers::Result::failure(
          fmt::format("run {} started on the station first; close interlocks between runs", run));
      interlock_request_->done.set_value(refused);
      interlock_request_.reset();
    }
  }
  // However execute() ends (a storage error included), the station is free afterwards.
  struct ClearCurrent {
    RunService& s;
    ~ClearCurrent() {
      s.live_.update([](LiveSnapshot& live) {
        live.run.reset();
        live.progress = {};
        for (auto& d : live.devices) d.state = "offline";
      });
      std::lock_guard lock(s.mutex_);
      s.current_.reset();
      s.commands_->clear();
    }
  } clear_current{*this};

  // The run's log lines carry its id (and, from the journal, the step and the device).
  const ScopedLogFields run_fields(LogFields{run, std::nullopt, std::nullopt});
  idle_watch_.release();  // the run opens the devices for itself
  std::optional<StoredRun> stored;
  std::unique_ptr<StationRun> wired;
  try {
    {
      store::Database db(options_.db_path);
      store::RunStore runs(db);
      stored = prepare_stored_run(runs, run);
    }
    wired = std::make_unique<StationRun>(stored->station, options_.db_path, run,
                                         stored->start.start_time_s);
  } catch (const store::StoreError&) {
    throw;  // the database's trouble, not the run's: it stays as it is and is tried again
  } catch (const std::exception& e) {
    fail_before_start(run, e.what());
    return;
  }
  if (resuming) {
    record_event(run, "daemon",
                 fmt::format("resuming at step {} after an interruption", stored->start.first_step),
                 false);
  }
  spdlog::info("run {}: {} {} at step {}/{}", run, resuming ? "resuming" : "starting",
               stored->procedure_name, stored->start.first_step + 1, stored->plan.steps.size());
  live_.update([&](LiveSnapshot& s) {
    s.run = run;
    s.progress = {};
    s.progress.step = stored->start.first_step;
    s.progress.steps = stored->plan.steps.size();
  });

  drivers::Station& station = wired->station();
  store::RunStore& runs = wired->runs();
  ObservedJournal journal(wired->store_journal(), hub_, live_, run);
  journal.set_devices(device_names(options_.station));
  auto next_device_read = std::chrono::steady_clock::now();
  const auto on_progress = [&](RunEngine&, const Progress& p) {
    if (heartbeat_) heartbeat_();
    // Live telemetry about twice a second of wall time, paused or not (this runs every tick).
    if (journal.telemetry_due())
      journal.publish_telemetry(station.table().read_state(), station.chamber().read_state());
    const auto now = std::chrono::steady_clock::now();
    const bool read_devices_now = now >= next_device_read;
    if (read_devices_now) next_device_read = now + kDeviceReadPeriod;
    live_.update([&](LiveSnapshot& s) {
      s.progress = p;
      if (read_devices_now) s.devices = read_devices(station);
    });
  };

  RunState final_state = RunState::kFailed;
  std::string reason;
  try {
    const CampaignResult result =
        wired->run(stored->plan, stored->start, journal, on_progress, commands_);
    final_state = result.state;
    reason = result.exit_reason;
  } catch (const std::exception& e) {
    // Storage failure: the engine made the station safe before this propagated.
    reason = std::string("internal error: ") + e.what();
    spdlog::error("run {}: {}", run, reason);
    try {
      runs.set_run_status(run, "failed", std::nullopt, store::Stamp::now(station.clock().now_s()),
                          reason);
    } catch (const std::exception& e2) {
      spdlog::error("run {}: recording the failure: {}", run, e2.what());
    }
  }

  const bool stopped_on_full_disk =
      final_state == RunState::kInterrupted && store::says_disk_full(reason);
  if (final_state == RunState::kInterrupted || final_state == RunState::kHeld) {
    // The engine recorded the run as interrupted (or held) in the same write that ended it: a
    // crash from here on still leaves it resumable.
    const auto first = runs.first_unfinished_step(run);
    const std::string message =
        final_state == RunState::kHeld
            ? fmt::format(
                  "checkpointed while paused: station made safe; held at step {} for an "
                  "operator's resume or abort on restart",
                  first ? *first : 0)
            : fmt::format("checkpointed: station made safe; resumes at step {} on restart",
                          first ? *first : 0);
    record_event(run, "daemon", message, false);
    spdlog::warn("run {}: {} ({})", run, message, reason);
  } else {
    store::dequeue_run(wired->database(), run);
    spdlog::info("run {}: {}{}", run, to_string(final_state),
                 reason.empty() ? "" : " (" + reason + ")");
  }
  if (stopped_on_full_disk) {
    wired.reset();  // the run's connections closed before the space left is read
    measure_after_full_ = true;
  }
}

void RunService::record_event(std::int64_t run, const std::string& who, const std::string& message,
                              bool operator_action) {
  store::Database db(options_.db_path);
  store::RunStore runs(db);
  store::EventRecord e;
  e.run_id = run;
  e.time_s = last_station_time_s(runs.load_run(run));
  e.kind = operator_action ? store::EventKind::kOperator : store::EventKind::kInfo;
  e.source = who;
  e.message = message;
  runs.add_event(e);
  hub_.publish("event", {{"run", run},
                         {"time_s", e.time_s},
                         {"kind", std::string(to_string(e.kind))},
                         {"source", who},
                         {"message", message}});
}

void RunService::record_action(std::int64_t run, const std::string& who,
                               const std::string& message) {
  record_event(run, who, message);
}

std::int64_t RunService::submit(const procedures::Procedure& procedure,
                                const procedures::Overrides& overrides, const std::string& who,
                                const UnitSerials& units) {
  const procedures::Plan plan = procedures::make_plan(procedure, options_.station, overrides);
  procedures::require_valid(plan);         // every violation, before anything is written
  units_for_run(options_.station, units);  // a unit missing or unknown, before anything either
  if (auto why = disk_shortfall()) throw OutOfSpace(*why + "; free space, then submit again");
  std::int64_t run = 0;
  {
    store::Database db(options_.db_path);
    store::RunStore runs(db);
    run = create_run_record(runs, options_.station, procedure, plan, units);
    // Enqueued before it is marked queued: a crash in between leaves an idle run, never a
    // queued run outside the queue.
    store::enqueue_run(db, run, who);
    runs.set_run_status(run, store::kQueuedStatus);
  }
  record_event(run, who,
               fmt::format("submitted {} ({} steps, estimated {:.0f} s)", procedure.name,
                           plan.steps.size(), plan.total_s));
  hub_.publish("run", {{"run", run}, {"state", store::kQueuedStatus}});
  {
    std::lock_guard lock(mutex_);
    ++generation_;
  }
  wake_.notify_all();
  return run;
}

std::string RunService::status_of(std::int64_t run) {
  store::Database db(options_.db_path);
  return store::RunStore(db).run_status(run);  // InputError when there is none
}

void RunService::command_current(std::int64_t run, EngineCommand command) {
  std::lock_guard lock(mutex_);
  if (current_ != run) {
    throw ActionRefused(fmt::format("run {} is not on the station", run));
  }
  commands_->push(std::move(command));
}

void RunService::pause(std::int64_t run, bool immediate, const std::string& who) {
  const std::string status = status_of(run);
  if (has_ended(status)) throw ActionRefused(fmt::format("run {} has ended ({})", run, status));
  const Progress p = live_.snapshot().progress;
  {
    std::lock_guard lock(mutex_);
    if (current_ != run) {
      throw ActionRefused(
          fmt::format("run {} is {}; only the running run can be paused", run, status));
    }
  }
  if (p.state == RunState::kPaused)
    throw ActionRefused(fmt::format("run {} is already paused", run));
  command_current(run, {EngineCommand::Kind::kPause, immediate, std::nullopt, "", who});
}

void RunService::resume(std::int64_t run, const std::string& who) {
  const std::string status = status_of(run);
  bool was_held = false;
  {
    std::lock_guard lock(mutex_);
    if (held_ == run) {
      resume_held_ = true;
      was_held = true;
      ++generation_;
    }
  }
  if (was_held) {
    record_event(run, who, "resume requested (held run)");
    wake_.notify_all();
    return;
  }
  const LiveSnapshot live = live_.snapshot();
  if (live.run != run || live.progress.state != RunState::kPaused) {
    throw ActionRefused(
        fmt::format("run {} is {}; only a paused or held run can be resumed", run, status));
  }
  command_current(run, {EngineCommand::Kind::kResume, false, std::nullopt, "", who});
}

void RunService::abort(std::int64_t run, const std::string& why, const std::string& who) {
  const std::string status = status_of(run);
  // Checked first: an ended run may still be on the station for a moment while it winds up.
  if (has_ended(status))
    throw ActionRefused(
        fmt::format("run {} has ended ({}); there is nothing to abort", run, status));
  bool was_held = false;
  const std::string reason = fmt::format("aborted by {}: {}", who, why);
  {
    std::lock_guard lock(mutex_);
    if (current_ == run) {
      commands_->push({EngineCommand::Kind::kAbort, false, std::nullopt, why, who});
      return;
    }
    if (held_ == run) {
      held_.reset();
      resume_held_ = false;
      was_held = true;
      ++generation_;
    } else if (const std::string now = status_of(run); now != store::kQueuedStatus) {
      // Read again under the lock: the run thread may have taken the run meanwhile.
      throw ActionRefused(fmt::format("run {} is {}; there is nothing to abort", run, now));
    }
    // Ended under the lock execute() claims a run under: a queued run cannot start meanwhile.
    store::Database db(options_.db_path);
    store::RunStore runs(db);
    const double t_s = last_station_time_s(runs.load_run(run));
    runs.set_run_status(run, "aborted", std::nullopt, store::Stamp::now(t_s), reason);
    store::dequeue_run(db, run);
  }
  record_event(run, who,
               (was_held ? "abort of the held run: " : "abort of the queued run: ") + why);
  if (was_held) live_.update([](LiveSnapshot& s) { s.held.reset(); });
  hub_.publish("run", {{"run", run}, {"state", "aborted"}, {"reason", reason}});
  wake_.notify_all();
}

void RunService::skip(std::int64_t run, std::optional<std::size_t> step, const std::string& why,
                      const std::string& who) {
  const std::string status = status_of(run);
  if (has_ended(status)) throw ActionRefused(fmt::format("run {} has ended ({})", run, status));
  const LiveSnapshot live = live_.snapshot();
  if (live.run != run) {
    throw ActionRefused(fmt::format(
        "run {} is {}; only a step of the run on the station can be skipped", run, status));
  }
  if (step && *step != live.progress.step) {
    throw ActionRefused(
        fmt::format("run {} is at step {}, not step {}", run, live.progress.step, *step));
  }
  if (step && *step >= live.progress.steps) {
    throw ActionRefused(fmt::format("run {} has no step {}", run, *step));
  }
  command_current(run, {EngineCommand::Kind::kSkip, false, step, why, who});
}

}  // namespace calstand::daemon::service
