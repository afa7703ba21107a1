#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/chamber_state.hpp"
#include "core/table_state.hpp"
#include "store/database.hpp"
#include "store/records.hpp"
#include "store/stamp.hpp"

namespace calstand::store {

/// Runs, steps, events and telemetry: what the run engine records, and what `calstand runs`
/// and `calstand show` read. Samples go through CaptureWriter instead.
///
/// Works on the caller's connection; not thread safe (one RunStore per thread and connection).
/// Every method throws StoreError naming the SQL operation when SQLite fails, and
/// core::InputError when a run or step does not exist (an id from the user).
class RunStore {
 public:
  /// `db` must outlive the RunStore.
  explicit RunStore(Database& db) : db_(db) {}

  /// The connection this store works on.
  Database& database() { return db_; }

  /// Registers or updates station `name` with its configuration and devices (the device list
  /// is replaced). Returns the station id.
  std::int64_t upsert_station(const std::string& name, const nlohmann::json& config,
                              const std::vector<DeviceRecord>& devices);

  /// Creates a run; computes the procedure's SHA-256; stamps created_utc. Returns the run id.
  std::int64_t create_run(const NewRun& run);

  /// Appends steps after the run's existing ones (indexes continue from there), all in one
  /// transaction. Returns their step ids, in order.
  std::vector<std::int64_t> add_steps(std::int64_t run, const std::vector<NewStep>& steps);

  /// The id of step `index` of `run`.
  std::int64_t step_id(std::int64_t run, std::size_t index);

  /// Step transitions. `attempt` is the engine's attempt number of that step; running sets the
  /// start time and counts the attempt, completed sets the end time and the good attempt.
  void mark_step_running(std::int64_t run, std::size_t index, int attempt, const Stamp& at);
  void mark_step_completed(std::int64_t run, std::size_t index, int attempt, const Stamp& at);
  void mark_step_failed(std::int64_t run, std::size_t index, const Stamp& at,
                        const std::string& why);
  void mark_step_invalidated(std::int64_t run, std::size_t index, const std::string& why);
  void mark_step_skipped(std::int64_t run, std::size_t index, const std::string& why);

  /// Deletes every sample chunk and step mean of attempt `attempt` of the step (an invalidated
  /// or interrupted capture, or the unfinished attempt found on crash resume). Samples still
  /// queued in a CaptureWriter are not touched: use CaptureWriter::discard_attempt for those.
  void discard_attempt(std::int64_t run, std::size_t index, int attempt);

  /// Records an event; returns its id. An empty wall_utc is stamped now.
  std::int64_t add_event(const EventRecord& event);
  /// The newest `limit` station-wide events (no run: an interlock closed between runs, ...),
  /// oldest first.
  std::vector<EventRecord> station_events(std::size_t limit);

  /// Telemetry rows (the caller decimates, e.g. with TelemetryDecimator); batches are one
  /// transaction.
  void add_table_telemetry(std::int64_t run, const core::TableState& state);
  void add_table_telemetry(std::int64_t run, std::span<const core::TableState> states);
  void add_chamber_telemetry(std::int64_t run, const core::ChamberState& state);
  void add_chamber_telemetry(std::int64_t run, std::span<const core::ChamberState> states);
  /// The table telemetry of `run` with station time in [from_s, to_s], in time order: time,
  /// encoder angles [deg] and rates [deg/s] and modes (fault text is not stored).
  std::vector<core::TableState> table_telemetry(
      std::int64_t run, double from_s = -std::numeric_limits<double>::infinity(),
      double to_s = std::numeric_limits<double>::infinity());
  /// The chamber telemetry of `run` with station time in [from_s, to_s], in time order (time,
  /// air temperature, setpoint and mode; fault text is not stored).
  std::vector<core::ChamberState> chamber_telemetry(
      std::int64_t run, double from_s = -std::numeric_limits<double>::infinity(),
      double to_s = std::numeric_limits<double>::infinity());

  /// Sets the run's status; `started` sets the start time (first call only), `ended` the end
  /// time; `exit_reason` (why a run aborted or failed) replaces the old one when not empty.
  void set_run_status(std::int64_t run, const std::string& status,
                      const std::optional<Stamp>& started = std::nullopt,
                      const std::optional<Stamp>& ended = std::nullopt,
                      const std::string& exit_reason = "");

  /// Runs newest first: at most `limit` (every one when none) with ids below `before_id` (any
  /// when none). A page of a long history; the next page starts before the last id of this one.
  /// Here and in load_run(), a run stored `running` or `paused` whose process is gone (nobody
  /// holds its RunLock) reads `interrupted`.
  std::vector<RunSummary> list_runs(std::optional<std::size_t> limit = std::nullopt,
                                    std::optional<std::int64_t> before_id = std::nullopt);
  /// One run with its steps (by index) and events (in order).
  RunRecord load_run(std::int64_t run);
  /// The stored status of `run` alone, as stored (one row; the daemon asks it on every operator
  /// action).
  std::string run_status(std::int64_t run);
  /// The steps of `run` by index.
  std::vector<StepRecord> load_steps(std::int64_t run);
  /// Index of the first step that is not completed or skipped (where a resumed run starts);
  /// none when every step is done.
  std::optional<std::size_t> first_unfinished_step(std::int64_t run);

 private:
  void require_run(std::int64_t run);
  Database& db_;
};

/// Keeps one telemetry row per `period_s` of station time (the first always): the engine
/// polls devices faster than telemetry needs to be stored. Rows are due on a fixed grid from
/// the first one, so polling jitter does not stretch the period (a tolerance of 1 ns absorbs
/// rounding in times such as 0.01 * i).
class TelemetryDecimator {
 public:
  explicit TelemetryDecimator(double period_s = 0.1) : period_s_(period_s) {}
  /// True when a row at `time_s` [s] should be stored.
  bool accept(double time_s) {
    if (time_s < due_s_ - 1e-9) return false;
    // After a gap longer than one period (or at the first row), start the grid at this row.
    due_s_ = time_s - due_s_ < period_s_ ? due_s_ + period_s_ : time_s + period_s_;
    return true;
  }

 private:
  double period_s_;
  double due_s_ = -std::numeric_limits<double>::infinity();  ///< next row due [s]
};

}  // namespace calstand::store
