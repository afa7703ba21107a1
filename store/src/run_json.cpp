#include "store/run_json.hpp"

#include <optional>
#include <string>

namespace calstand::store {
namespace {

template <typename T>
nlohmann::json value_or_null(const std::optional<T>& value) {
  return value ? nlohmann::json(*value) : nlohmann::json();
}

}  // namespace

nlohmann::json to_json(const RunSummary& run) {
  return {{"id", run.id},
          {"procedure", run.procedure_name},
          {"status", run.status},
          {"steps_done", run.steps_done},
          {"steps_total", run.steps_total},
          {"created_utc", run.created_utc},
          {"started_utc", run.started_utc},
          {"ended_utc", run.ended_utc},
          {"exit_reason", run.exit_reason}};
}

nlohmann::json to_json(const StepRecord& step) {
  return {{"index", step.index},
          {"kind", step.kind},
          {"label", step.label},
          {"status", std::string(to_string(step.status))},
          {"reason", step.reason},
          {"attempts", step.attempts},
          {"good_attempt", value_or_null(step.good_attempt)},
          {"started_clock_s", value_or_null(step.started_clock_s)},
          {"ended_clock_s", value_or_null(step.ended_clock_s)},
          {"origin", step.origin},
          {"commanded", step.commanded}};
}

nlohmann::json to_json(const EventRecord& event) {
  return {{"id", event.id},
          {"time_s", event.time_s},
          {"wall_utc", event.wall_utc},
          {"kind", std::string(to_string(event.kind))},
          {"source", event.source},
          {"message", event.message},
          {"detail", event.detail}};
}

nlohmann::json to_json(const RunUnit& unit) {
  return {
      {"imu", unit.imu}, {"model", unit.model}, {"serial", unit.serial}, {"source", unit.source}};
}

nlohmann::json units_json(const std::vector<RunUnit>& units) {
  nlohmann::json out = nlohmann::json::array();
  for (const RunUnit& u : units) out.push_back(to_json(u));
  return out;
}

}  // namespace calstand::store
