#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace calstand::store {

/// Status of a step (column steps.status).
enum class StepStatus { kPending, kRunning, kCompleted, kFailed, kSkipped, kInvalidated };
std::string_view to_string(StepStatus status);
/// Inverse of to_string; throws StoreError on an unknown name (a corrupt database).
StepStatus parse_step_status(std::string_view text);

/// Kind of an event (column events.kind).
enum class EventKind { kInfo, kFault, kInterlock, kOperator };
std::string_view to_string(EventKind kind);
/// Inverse of to_string; throws StoreError on an unknown name.
EventKind parse_event_kind(std::string_view text);

/// A device of a station as registered in table devices.
struct DeviceRecord {
  std::string kind;     ///< "table", "chamber" or "imu"
  std::string name;     ///< e.g. "imu0"
  std::string backend;  ///< e.g. "sim", "modbus"
};

/// Whether a run whose stored status (runs.status) is `status` is over for good: completed,
/// aborted or failed (the run engine's terminal states), or imported (recorded elsewhere, never
/// run here). Interrupted and held runs are not: the daemon or an operator resumes them. Its
/// rows then never change again (what the fleet's sync relies on).
bool run_has_ended(std::string_view status);

/// What a new run records about itself.
struct NewRun {
  std::optional<std::int64_t> station_id;  ///< from RunStore::upsert_station, or none
  std::string procedure_name;
  std::string procedure_text;  ///< exact text; its SHA-256 is stored beside it
  nlohmann::json parameters = nlohmann::json::object();        ///< values after --set overrides
  nlohmann::json station_snapshot = nlohmann::json::object();  ///< station config at start
  std::string status = "idle";                                 ///< run engine state name
};

/// One expanded step as the plan gives it.
struct NewStep {
  std::string kind;  ///< e.g. "capture", "move", "rate", "set_temperature"
  std::string label;
  nlohmann::json commanded = nlohmann::json::object();  ///< commanded state, with units in keys
  std::string origin;  ///< JSON path in the procedure, e.g. "steps[3].steps[1]"
};

/// A step as stored.
struct StepRecord {
  std::int64_t id = 0;
  std::size_t index = 0;
  std::string kind;
  std::string label;
  nlohmann::json commanded;
  std::string origin;
  StepStatus status = StepStatus::kPending;
  std::string reason;                     ///< why failed/invalidated/skipped ("" otherwise)
  int attempts = 0;                       ///< attempts started
  std::optional<int> good_attempt;        ///< the attempt holding the step's data
  std::optional<double> started_clock_s;  ///< station clock [s]
  std::optional<double> ended_clock_s;    ///< station clock [s]
  std::string started_utc;
  std::string ended_utc;
};

/// An event to record or as stored.
struct EventRecord {
  std::int64_t id = 0;                 ///< set by the store
  std::optional<std::int64_t> run_id;  ///< none: station-wide
  double time_s = 0.0;                 ///< station clock [s]
  std::string wall_utc;                ///< empty: the store stamps the wall clock now
  EventKind kind = EventKind::kInfo;
  std::string source;  ///< e.g. "engine", "table", "capture_writer", "operator"
  std::string message;
  nlohmann::json detail;  ///< null or any JSON
};

/// One line of a run listing.
struct RunSummary {
  std::int64_t id = 0;
  std::string procedure_name;
  std::string status;
  std::size_t steps_done = 0;  ///< completed steps
  std::size_t steps_total = 0;
  std::string created_utc;
  std::string started_utc;  ///< empty when not started
  std::string ended_utc;    ///< empty while running
  std::string exit_reason;
};

/// The unit in one IMU slot of a run (table run_units).
struct RunUnit {
  std::string imu;     ///< the slot's name at the station, e.g. imu0
  std::string model;   ///< model or spec sheet name; empty when unknown
  std::string serial;  ///< serial number; empty when nobody knows it
  /// Where the serial came from: "device" (read from the unit), "submitted" (given with the
  /// run, `--unit imu0=SN`), or "station" (fixed in the station file).
  std::string source = "station";
};

/// A whole run as stored, without samples and telemetry.
struct RunRecord {
  RunSummary summary;
  std::optional<std::int64_t> station_id;
  std::string procedure_text;
  std::string procedure_sha256;
  nlohmann::json parameters;
  nlohmann::json station_snapshot;
  std::optional<double> started_clock_s;
  std::optional<double> ended_clock_s;
  std::vector<StepRecord> steps;
  std::vector<EventRecord> events;
  std::vector<RunUnit> units;  ///< the unit in each IMU slot, when recorded (migration 5)
};

}  // namespace calstand::store
