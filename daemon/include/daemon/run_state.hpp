#pragma once

#include <optional>
#include <string_view>

#include "store/records.hpp"

namespace calstand::daemon {

/// The states of a run. Terminal: completed, aborted, failed. Interrupted: stopped with the
/// station safe for a checkpoint (a daemon stopping); it resumes at its first unfinished step.
/// Held: interrupted while an operator had it paused, or waiting for an operator after a crash
/// (recovery policy hold); it resumes only when an operator says so.
enum class RunState {
  kIdle,
  kRunning,
  kPaused,
  kAborting,
  kCompleted,
  kAborted,
  kFailed,
  kInterrupted,
  kHeld
};

std::string_view to_string(RunState state);
/// The state named `name` as to_string() writes it; nullopt for any other text.
std::optional<RunState> run_state_named(std::string_view name);
bool is_terminal(RunState state);
/// Whether a run whose stored status is `status` is over for good: a terminal state, or
/// "imported" (recorded elsewhere, never run here). Interrupted and held runs are not: the
/// daemon or an operator resumes them.
bool has_ended(std::string_view status);

/// What kind of thing an event records (the store's kinds: info, fault, interlock, operator).
using EventKind = store::EventKind;

}  // namespace calstand::daemon
