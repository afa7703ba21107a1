#include "daemon/stored_run.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "core/error.hpp"
#include "daemon/run_state.hpp"
#include "procedures/procedure.hpp"

namespace calstand::daemon {

StoredRun prepare_stored_run(store::RunStore& runs, std::int64_t run) {
  const store::RunRecord record = runs.load_run(run);
  const auto& status = record.summary.status;
  if (has_ended(status)) {
    throw core::InputError(
        fmt::format("run {}", run),
        fmt::format("the run is {}; only an interrupted run can resume", status));
  }
  const auto first = runs.first_unfinished_step(run);
  if (!first)
    throw core::InputError(fmt::format("run {}", run), "every step of the run is already done");

  StoredRun out;
  out.station =
      core::StationConfig::from_json(record.station_snapshot, fmt::format("run {} station", run));
  const procedures::Procedure procedure =
      procedures::parse_procedure(record.procedure_text, record.summary.procedure_name);
  out.procedure_name = procedure.name;
  procedures::Overrides overrides;
  for (const auto& [k, v] : record.parameters.items()) overrides[k] = v;
  out.plan = procedures::make_plan(procedure, out.station, overrides);
  procedures::require_valid(out.plan);
  if (out.plan.steps.size() != record.steps.size()) {
    throw core::InputError(fmt::format("run {}", run),
                           "the stored procedure no longer expands to the stored steps");
  }

  int next_attempt = 1;
  double last_time_s = 0.0;
  for (const auto& s : record.steps) {
    if (s.ended_clock_s) last_time_s = std::max(last_time_s, *s.ended_clock_s);
    if (s.started_clock_s) last_time_s = std::max(last_time_s, *s.started_clock_s);
    if (s.index < *first) continue;
    if (s.status == store::StepStatus::kCompleted || s.status == store::StepStatus::kSkipped)
      continue;
    for (int a = 1; a <= s.attempts; ++a) runs.discard_attempt(run, s.index, a);
    if (s.index == *first) next_attempt = s.attempts + 1;
  }
  for (const auto& e : record.events) last_time_s = std::max(last_time_s, e.time_s);
  out.start = {*first, next_attempt, last_time_s, {}};
  for (const auto& s : record.steps) {
    if (s.status == store::StepStatus::kSkipped && s.index < *first)
      out.start.skipped_steps.push_back(s.index);
  }
  return out;
}

}  // namespace calstand::daemon
