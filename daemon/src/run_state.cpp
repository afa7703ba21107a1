#include "daemon/run_state.hpp"

#include "store/records.hpp"

namespace calstand::daemon {

std::string_view to_string(RunState state) {
  switch (state) {
    case RunState::kIdle:
      return "idle";
    case RunState::kRunning:
      return "running";
    case RunState::kPaused:
      return "paused";
    case RunState::kAborting:
      return "aborting";
    case RunState::kCompleted:
      return "completed";
    case RunState::kAborted:
      return "aborted";
    case RunState::kFailed:
      return "failed";
    case RunState::kInterrupted:
      return "interrupted";
    case RunState::kHeld:
      return "held";
  }
  return "unknown";
}

std::optional<RunState> run_state_named(std::string_view name) {
  for (auto s : {RunState::kIdle, RunState::kRunning, RunState::kPaused, RunState::kAborting,
                 RunState::kCompleted, RunState::kAborted, RunState::kFailed,
                 RunState::kInterrupted, RunState::kHeld}) {
    if (to_string(s) == name) return s;
  }
  return std::nullopt;
}

bool is_terminal(RunState state) {
  return state == RunState::kCompleted || state == RunState::kAborted || state == RunState::kFailed;
}

bool has_ended(std::string_view status) { return store::run_has_ended(status); }

}  // namespace calstand::daemon
