#pragma once

#include <string_view>

#include "store/records.hpp"

namespace calstand::daemon {

/// The states of a run. Terminal: completed, aborted, failed. Interrupted: stopped with the
/// station safe for a checkpoint (a daemon stopping); it resumes at its first unfinished step.
enum class RunState { kIdle, kRunning, kPaused, kAborting, kCompleted, kAborted, kFailed, kInterrupted };

std::string_view to_string(RunState state);
bool is_terminal(RunState state);

/// What kind of thing an event records (the store's kinds: info, fault, interlock, operator).
using EventKind = store::EventKind;

}  // namespace calstand::daemon
