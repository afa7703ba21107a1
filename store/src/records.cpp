#include "store/records.hpp"

#include <array>
#include <string>
#include <utility>

#include "store/error.hpp"

namespace calstand::store {

bool run_has_ended(std::string_view status) {
  return status == "completed" || status == "aborted" || status == "failed" || status == "imported";
}
namespace {

constexpr std::array<std::pair<StepStatus, std::string_view>, 6> kStepStatus{{
    {StepStatus::kPending, "pending"},
    {StepStatus::kRunning, "running"},
    {StepStatus::kCompleted, "completed"},
    {StepStatus::kFailed, "failed"},
    {StepStatus::kSkipped, "skipped"},
    {StepStatus::kInvalidated, "invalidated"},
}};

constexpr std::array<std::pair<EventKind, std::string_view>, 4> kEventKind{{
    {EventKind::kInfo, "info"},
    {EventKind::kFault, "fault"},
    {EventKind::kInterlock, "interlock"},
    {EventKind::kOperator, "operator"},
}};

}  // namespace

std::string_view to_string(StepStatus status) {
  for (const auto& [s, name] : kStepStatus) {
    if (s == status) return name;
  }
  return "?";
}

StepStatus parse_step_status(std::string_view text) {
  for (const auto& [s, name] : kStepStatus) {
    if (name == text) return s;
  }
  throw StoreError("read step", "unknown step status '" + std::string(text) + "'");
}

std::string_view to_string(EventKind kind) {
  for (const auto& [k, name] : kEventKind) {
    if (k == kind) return name;
  }
  return "?";
}

EventKind parse_event_kind(std::string_view text) {
  for (const auto& [k, name] : kEventKind) {
    if (name == text) return k;
  }
  throw StoreError("read event", "unknown event kind '" + std::string(text) + "'");
}

}  // namespace calstand::store
