#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <future>
#include <memory>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "core/station_config.hpp"
#include "daemon/campaign.hpp"
#include "daemon/engine_command.hpp"
#include "daemon/service/event_hub.hpp"
#include "daemon/service/live_status.hpp"
#include "daemon/service/station_watch.hpp"
#include "drivers/turntable.hpp"
#include "procedures/procedure.hpp"

namespace calstand::daemon::service {

/// What the daemon does on start with a run that was cut off (status running, paused, held or
/// interrupted in the database): resume it at once, or hold it with the station safe until an
/// operator resumes or aborts it.
enum class RecoveryPolicy { kAuto, kHold };

/// "auto" or "hold"; throws core::InputError naming `where` otherwise.
RecoveryPolicy parse_recovery_policy(const std::string& name, const std::string& where);

struct ServiceOptions {
  core::StationConfig station;  ///< the station this daemon owns
  std::string db_path;          ///< its SQLite database (the queue lives there)
  RecoveryPolicy recovery = RecoveryPolicy::kAuto;
};

/// An operator request that does not apply to the run as it is (e.g. pause a queued run,
/// resume a run that is not paused). what() says why.
class ActionRefused : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A new run refused because the database's filesystem has too little space for it (station
/// policy min_free_disk_mb). what() says how much is free and how much is needed.
class OutOfSpace : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The daemon's run queue and run thread: one run at a time on the station, queued runs
/// oldest first, operator actions recorded as events with who asked.
///
/// Thread safety: every public method may be called from any thread (API handlers); runs
/// execute on the service's own thread, and operator actions reach the engine through that
/// thread (the engine's journal is not shared between threads).
class RunService {
 public:
  RunService(ServiceOptions options, EventHub& hub);
  /// Calls stop("service destroyed") when still running.
  ~RunService();
  RunService(const RunService&) = delete;
  RunService& operator=(const RunService&) = delete;

  /// Starts the run thread: it first deals with an interrupted run per the recovery policy,
  /// then takes queued runs.
  void start();

  /// Stops the run thread: a run in progress is aborted to the station's safe state and set
  /// back to 'interrupted' (it resumes at its first unfinished step on the next start), with
  /// `why` recorded. Blocks until the station is safe. Idempotent.
  void stop(const std::string& why);

  /// Plans `procedure` with `overrides` on the station and queues it as a new run; returns the
  /// run id, with the serials given for its units (`units`, by IMU name). Throws
  /// procedures::ProcedureError listing every violation when the plan breaks a rule,
  /// core::InputError for a unit the station lacks or a serial it requires and lacks,
  /// OutOfSpace when the disk is too full to start it (nothing is written then).
  std::int64_t submit(const procedures::Procedure& procedure,
                      const procedures::Overrides& overrides, const std::string& who,
                      const UnitSerials& units = {});
  /// Records an operator action taken on run `run` outside the engine (a fit, a diagnosis) as
  /// an operator event with who asked, in the run's events and on the live stream. Throws
  /// core::InputError when there is no such run.
  void record_action(std::int64_t run, const std::string& who, const std::string& message);

  /// Operator actions on run `run`. Throw core::InputError when there is no such run,
  /// ActionRefused when the action does not apply to its state.
  /// pause: the running run, at the next step boundary or at once (`immediate`).
  void pause(std::int64_t run, bool immediate, const std::string& who);
  /// resume: the paused run, or the held one (an interrupted run waiting for an operator).
  void resume(std::int64_t run, const std::string& who);
  /// abort: the running or paused run (to the safe state), a held run, or a queued one.
  void abort(std::int64_t run, const std::string& why, const std::string& who);
  /// skip: the step in progress of the run on the station (or, while it is paused, the step
  /// that would run next). `step`, when given, is the step the operator means: refused when
  /// the run is elsewhere now, and not applied when the run moves on before the engine sees it.
  void skip(std::int64_t run, std::optional<std::size_t> step, const std::string& why,
            const std::string& who);

  /// The operator's close of latched table interlocks, between runs only (ActionRefused while
  /// a run is on the station). Done on the run thread, which owns the devices between runs;
  /// recorded as a station event with `who` and the time. A queued run held by the interlock
  /// starts afterwards by itself.
  drivers::InterlockClosure close_interlocks(const std::string& who);

  /// Called on the run thread at least every `period` between runs and on every engine tick
  /// in a run (systemd's watchdog and status: ServiceHeartbeat); set before start(). The run
  /// thread calls nothing else of the kind, so a hang in it stops the calls.
  void set_heartbeat(std::function<void()> beat, std::chrono::milliseconds period);

  LiveSnapshot snapshot() const { return live_.snapshot(); }
  const ServiceOptions& options() const { return options_; }

 private:
  void run_thread();
  /// Between runs: reads the table and the chamber into the live status and the stream.
  void watch_idle();
  /// The next run to execute and whether it resumes an interrupted one; none when there is
  /// nothing to do now (or a run is held).
  std::optional<std::pair<std::int64_t, bool>> next_run();
  void hold(std::int64_t run);
  /// Why no run may start now (disk space, a latched interlock); none when one may.
  std::optional<std::string> start_blocker();
  /// Shows `why` in the live status and records it once on `run`, the run that waits.
  void note_waiting(std::int64_t run, const std::optional<std::string>& why);
  /// Serves an operator's interlock close waiting for the run thread.
  void serve_interlock_request();
  void execute(std::int64_t run, bool resuming);
  void fail_before_start(std::int64_t run, const std::string& why);
  void record_event(std::int64_t run, const std::string& who, const std::string& message,
                    bool operator_action = true);
  /// Queues `command` for the run on the station; refuses unless `run` is that run.
  void command_current(std::int64_t run, EngineCommand command);
  std::string status_of(std::int64_t run);

  ServiceOptions options_;
  EventHub& hub_;
  LiveStatus live_;
  IdleStationWatch idle_watch_;  // run thread only

  mutable std::mutex mutex_;
  std::condition_variable wake_;
  bool stopping_ = false;
  std::uint64_t generation_ = 0;         // bumped on every change the run thread waits for
  std::optional<std::int64_t> current_;  // the run on the station
  std::optional<std::int64_t> held_;     // the interrupted run waiting for an operator
  bool resume_held_ = false;
  // An operator's interlock close, served by the run thread between runs.
  struct InterlockRequest {
    std::string who;
    std::promise<drivers::InterlockClosure> done;
  };
  std::shared_ptr<InterlockRequest> interlock_request_;
  std::optional<std::string> waiting_reason_;  // run thread only: last recorded wait
  // After a run stopped on a full disk, the free bytes needed before runs start again (what
  // was free then plus the policy's minimum; 0: none): space must really be back, or the run
  // would resume, fill the disk and stop again in a loop. Set by the run thread, read by submit.
  std::atomic<std::uint64_t> free_bytes_needed_after_full_{0};
  // A run stopped on a full disk and the space then free is not measured yet: measured once the
  // run's connections are closed, at the next look (its write-ahead log counted as free, since
  // a reader may still hold it).
  std::atomic<bool> measure_after_full_{false};
  /// Why no run may start for lack of space; none when there is enough.
  std::optional<std::string> disk_shortfall();
  // Requests for the run on the station, taken by its engine on the engine thread; pushed under
  // mutex_ (so only while `current_` is the run meant), taken without it.
  std::shared_ptr<EngineCommandQueue> commands_ = std::make_shared<EngineCommandQueue>();
  std::thread thread_;
  std::function<void()> heartbeat_;  // run thread only, once started
  std::chrono::milliseconds heartbeat_period_{std::chrono::seconds(1)};
};

}  // namespace calstand::daemon::service
