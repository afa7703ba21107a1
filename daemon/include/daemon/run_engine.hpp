#pragma once

#include <atomic>
#include <cstddef>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "daemon/engine_command.hpp"
#include "daemon/run_journal.hpp"
#include "daemon/run_state.hpp"
#include "drivers/station.hpp"
#include "procedures/plan.hpp"
#include "procedures/procedure.hpp"

namespace calstand::daemon {

/// What to do when an IMU stream misbehaves during a capture (sequence gap, stale stream).
enum class GapPolicy {
  kRecord,         ///< record an event and keep the capture
  kRepeatCapture,  ///< invalidate the capture and repeat it
  kAbort,          ///< abort the run to the safe state
};

/// "record", "repeat_capture", "abort" (station file names); throws std::invalid_argument
/// for anything else.
GapPolicy parse_gap_policy(const std::string& name);

/// Where the run is, for progress bars and status requests.
struct Progress {
  RunState state = RunState::kIdle;
  std::size_t step = 0;   ///< index of the current step
  std::size_t steps = 0;  ///< number of steps in the run
  std::string label;      ///< the current step's label
  std::string phase;      ///< e.g. "soaking", "moving", "settling", "capturing"
  double station_time_s = 0.0;
  double eta_s = 0.0;  ///< estimated station time still needed [s]
};

/// Options of the engine, with defaults a lab would pick.
struct EngineOptions {
  double tick_s = 0.1;                   ///< control-loop period in station time [s]
  double telemetry_period_s = 1.0;       ///< table/chamber telemetry recording period [s]
  double move_timeout_s = 600.0;         ///< a move must settle within this [s]
  double rate_settle_timeout_s = 120.0;  ///< a rate must settle within this [s]
  double capture_band_factor = 2.0;      ///< capture invalid when |air - setpoint| exceeds this
                                         ///< times the soak tolerance
  double imu_stale_s = 1.0;              ///< no sample for this long is a stale stream [s]
  /// A stream whose time stamps fall back against its device clock by more than this many wall
  /// seconds (times the station's time_scale) was stamped late before: its capture is treated
  /// as one that saw the stream stale (stale_policy) [s].
  double late_stamp_wall_s = 0.02;
  /// A capture repeated for late stamps starts once every stream's stamps have held this many
  /// wall seconds (times the time_scale): a reader still catching up sets them back again, and
  /// an immediate repeat would be spent on the same hold-up [s].
  double stamps_hold_wall_s = 1.0;
  /// A table or chamber link down (unreadable, not faulted) is ridden out this long [s].
  double link_outage_s = 5.0;
  GapPolicy gap_policy = GapPolicy::kRecord;
  GapPolicy stale_policy = GapPolicy::kRepeatCapture;
  int max_capture_attempts = 3;  ///< repeats of an invalidated capture before failing
  /// Before repeating a capture invalidated by a stale stream, wait up to this long for the
  /// stream to come back [s].
  double stream_recovery_timeout_s = 30.0;
  /// When the station cannot be made safe at the end of a run (a device's link is down), the
  /// engine keeps trying for this long in real seconds before giving up and saying so.
  double safe_state_retry_s = 30.0;
  /// Called from the engine's thread at most once per tick.
  std::function<void(const Progress&)> on_progress;
  /// The options a station's fault policy (station file `policy`) sets; the rest default.
  static EngineOptions from_policy(const core::FaultPolicy& policy);
  /// Real seconds to sleep per tick while paused on a virtual clock (keeps a paused simulated
  /// run from spinning the CPU).
  double paused_real_sleep_s = 0.01;
};

/// Runs the expanded steps of a procedure on a station, recording everything in a journal.
///
/// Safety: any abort, failure or completion leaves the station safe (table at rest, chamber
/// in standby); device calls never throw (drivers return Result), journal (storage) errors
/// propagate after the station has been made safe.
/// Requests (pause(), resume(), abort(), interrupt(), skip(), or EngineCommand pushed to the
/// engine's command queue) may come from any thread: they wait in the queue, and the engine's
/// thread takes them in order at its next tick (or while paused), records each as an operator
/// event and acts on it. run() runs on the caller's thread.
class RunEngine {
 public:
  /// `commands`: the queue requests arrive through (e.g. the daemon's, which outlives one
  /// engine); the engine makes its own when null.
  RunEngine(drivers::Station& station, RunJournal& journal, procedures::Plan plan,
            EngineOptions options = {}, std::shared_ptr<EngineCommandQueue> commands = nullptr);

  /// Runs from step `first_step` (0 for a new run; the first unfinished step when resuming
  /// after a crash, in which case the temperature and table state that step needs are
  /// re-established first). Blocks until the run is completed, aborted or failed.
  /// `first_attempt` numbers the first step's attempt (after a crash: one more than the
  /// attempts already recorded, whose samples the caller discarded).
  /// `skipped`: steps before `first_step` the operator skipped (re-establishing ignores them).
  RunState run(std::size_t first_step = 0, int first_attempt = 1,
               const std::vector<std::size_t>& skipped = {});

  /// Pause at the next step boundary, or at once (`immediate`: an interrupted capture is
  /// discarded and repeated on resume).
  void pause(bool immediate, const std::string& who = "operator");
  void resume(const std::string& who = "operator");
  /// Abort: the station goes to its safe state and the reason is recorded.
  void abort(const std::string& why, const std::string& who = "operator");
  /// Stop for a checkpoint (the daemon is stopping): the station goes to its safe state as for
  /// an abort, but the run ends interrupted (held when it was paused), not aborted, in one
  /// journal write: the step in progress stays unfinished and a resume redoes it. An abort
  /// requested before or after stays an abort.
  void interrupt(const std::string& why, const std::string& who = "daemon");
  /// Skip the step in progress (a capture in progress is discarded, a rate step's axis comes
  /// to rest), or, while paused, the step that would run next (the run stays paused). The step
  /// is recorded as skipped with who and why; the run goes on with the next one. A skipped
  /// temperature step leaves its setpoint commanded: the following captures still hold the
  /// chamber air to its band, and re-soak when it is out of it.
  /// `step`: the index the operator means; when the run has moved past it by the time the
  /// request is applied, nothing is skipped and an event says so.
  void skip(const std::string& why, const std::string& who = "operator",
            std::optional<std::size_t> step = std::nullopt);

  /// The queue this engine takes its requests from.
  EngineCommandQueue& commands() { return *commands_; }

  RunState state() const { return state_.load(); }
  Progress progress() const;
  /// Why the run ended aborted or failed (empty otherwise).
  std::string exit_reason() const;

 private:
  struct Interrupted {};  // unwinds a step on an immediate pause
  struct Aborted {
    std::string why;
  };
  struct StepFailed {
    std::string why;
  };
  struct Skipped {};  // unwinds the current step on an operator skip

  void execute(std::size_t index);
  void set_temperature(const procedures::Step& step, std::size_t index);
  void soak(const procedures::Step& step, std::size_t index);
  void move(const procedures::Step& step, std::size_t index);
  void rate(const procedures::Step& step, std::size_t index);
  /// An oscillation: the sine, settle cycles, the capture with every table reading traced,
  /// then the axis back at rest at its start angle.
  void oscillate(const procedures::Step& step, std::size_t index);
  /// Records the IMUs for `duration_s`; repeats invalidated attempts; returns the good attempt.
  int capture(std::size_t index, double duration_s, int first_attempt);
  void wait_for(double duration_s, const char* phase);
  /// A `power` step: switches the supplies, waits for the streams to start (on), settles.
  void power(const procedures::Step& step, std::size_t index);
  void wait_for_streams();
  void reestablish(std::size_t first_step, const std::vector<std::size_t>& skipped);
  /// Records the identity each IMU reports (those whose protocol says); throws StepFailed
  /// when a slot holds another unit than the run is for.
  void identify_units();
  void tick();
  /// Takes the requests waiting in the queue and applies them in order (engine thread).
  void take_commands();
  void apply(const EngineCommand& command);
  void poll_imus();
  void check_interlocks();
  void record_device_events();
  void handle_pause_at_boundary();
  /// Records step `index` as skipped (the operator's request) and leaves the station as the
  /// next step expects it (a skipped rate step's axis at rest).
  void skip_step(std::size_t index);
  /// Brings `axis` to rest after rate step `index`: a command lost to a link outage is sent
  /// again until it reaches the controller (the outage ridden out by the policy, so the run
  /// aborts to the safe state past its limit); a refusal fails the step.
  void bring_to_rest(drivers::TableAxis axis, std::size_t index);
  /// True when a skip request applies to the current step now (false while re-establishing
  /// the station after a crash; a request meant for a step that has ended is dropped).
  bool skip_wanted();
  void finish(RunState final_state, const std::string& reason);
  void set_phase(const char* phase);
  void record_event(EventKind kind, const std::string& source, const std::string& message);

  drivers::Station& station_;
  RunJournal& journal_;
  procedures::Plan plan_;
  EngineOptions options_;

  std::shared_ptr<EngineCommandQueue> commands_;
  std::atomic<RunState> state_{RunState::kIdle};
  // The requests applied so far (take_commands()); engine thread only.
  bool pause_requested_ = false;
  bool pause_immediate_ = false;
  bool resume_requested_ = false;
  bool abort_requested_ = false;
  bool interrupt_requested_ = false;  // the abort is a checkpoint (see interrupt())
  bool skip_requested_ = false;
  std::optional<std::size_t> skip_step_;  // the step a skip request means
  std::string abort_reason_;
  std::string skip_reason_;
  bool reestablishing_ = false;  // resuming after a crash: pause and skip wait for the first step
  mutable std::mutex mutex_;     // guards progress_ and exit_reason_ (read by other threads)
  Progress progress_;
  std::string exit_reason_;

  // Capture in progress (nullopt between captures).
  struct Capturing {
    std::size_t step;
    int attempt;
    std::optional<std::string> invalid_reason;
    double start_s = 0.0;  // samples taken before this (station time) belong to no step
    double end_s = 0.0;    // ... and samples taken at or after this
    /// Per IMU: a sample at or after end_s has arrived, so every sample of the window has
    /// (streams deliver in order).
    std::vector<bool> reached_end;
  };
  std::optional<Capturing> capturing_;
  int attempt_ = 1;              // attempt number of the current step
  double step_started_s_ = 0.0;  // station time the current step (attempt) started [s]

  // Temperature band of the last set_temperature step (captures must stay in it).
  std::optional<double> setpoint_c_;
  procedures::SoakCriterion soak_;
  double band_c_ = 0.0;

  // Table and chamber links that dropped: since when (station time), while they are down.
  std::optional<double> table_link_down_since_s_;
  std::optional<double> chamber_link_down_since_s_;
  /// Rides out a link outage of `device` (records it with `fault_text`, aborts past the
  /// policy's limit); false when `link_lost` is not set (a fault the controller reports).
  bool ride_out_link_outage(const std::string& device, bool link_lost,
                            const std::string& fault_text, std::optional<double>& down_since_s);
  /// Records that `device`'s link is back after an outage.
  void note_link_back(const std::string& device, std::optional<double>& down_since_s);

  // IMU stream health, per device.
  struct ImuHealth {
    std::optional<std::uint32_t> last_sequence;
    /// Station minus device time: of the last sample, and the highest since `offset_high_at_s`
    /// (device time). Constant while the driver's time stamps hold; set back when the driver
    /// finds they were late.
    std::optional<double> last_stamp_offset_s;
    double stamp_offset_high_s = 0.0;
    double offset_high_at_s = 0.0;
    double set_back_said_s = 0.0;   ///< how much of the fall from that high was reported [s]
    double set_back_at_s = -1e300;  ///< station time the stamps were last seen set back [s]
    double last_device_time_s = 0.0;
    double last_sample_s = 0.0;
    bool stale = false;
    /// Switched off by a power step: its silence is meant, not a stale stream.
    bool unpowered = false;
  };
  /// How far the driver set the time stamps of `samples` back against their device clock
  /// (beyond late_stamp_wall_s): the stamps before were late by as much; 0 when they held.
  double stamps_set_back_s(ImuHealth& health, const std::vector<core::ImuSample>& samples) const;
  std::vector<ImuHealth> imu_health_;
  double last_telemetry_s_ = -1e300;
  /// While an oscillation runs: the control tick [s], short enough to sample the encoder's sine
  /// (kTracePerCycle readings a period), each reading traced to the journal; 0 otherwise.
  double trace_tick_s_ = 0.0;
};

}  // namespace calstand::daemon
