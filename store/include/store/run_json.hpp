#pragma once

#include <nlohmann/json.hpp>

#include "store/records.hpp"

namespace calstand::store {

/// The one JSON shape of a stored run's parts, wherever calstand shows them (calstandd's
/// GET /runs, /runs/{id}, /runs/{id}/steps and /runs/{id}/events; `calstand runs --json` and
/// `calstand show --json`); schemas/api.md documents it. Times `*_utc` are ISO 8601 wall
/// clock (empty when not yet), `*_clock_s` and `time_s` the station clock [s].
/// {"id", "procedure", "status", "steps_done", "steps_total", "created_utc", "started_utc",
///  "ended_utc", "exit_reason"}
nlohmann::json to_json(const RunSummary& run);
/// {"index", "kind", "label", "status", "reason", "attempts", "good_attempt" (null: none),
///  "started_clock_s", "ended_clock_s" (null: not yet), "origin", "commanded"}
nlohmann::json to_json(const StepRecord& step);
/// {"id", "time_s", "wall_utc", "kind", "source", "message", "detail"}
nlohmann::json to_json(const EventRecord& event);
/// `{"imu", "model", "serial", "source"}`.
nlohmann::json to_json(const RunUnit& unit);
/// An array of to_json(RunUnit).
nlohmann::json units_json(const std::vector<RunUnit>& units);

}  // namespace calstand::store
