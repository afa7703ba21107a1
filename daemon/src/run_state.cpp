#include "daemon/run_state.hpp"

namespace calstand::daemon {

std::string_view to_string(RunState state) {
  switch (state) {
    case RunState::kIdle: return "idle";
    case RunState::kRunning: return "running";
    case RunState::kPaused: return "paused";
    case RunState::kAborting: return "aborting";
    case RunState::kCompleted: return "completed";
    case RunState::kAborted: return "aborted";
    case RunState::kFailed: return "failed";
    case RunState::kInterrupted: return "interrupted";
    case RunState::kHeld: return "held";
  }
  return "unknown";
}

bool is_terminal(RunState state) {
  return state == RunState::kCompleted || state == RunState::kAborted ||
         state == RunState::kFailed;
}

}  // namespace calstand::daemon
