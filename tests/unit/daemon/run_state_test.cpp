#include "daemon/run_state.hpp"

#include <gtest/gtest.h>

namespace calstand::daemon {
namespace {

TEST(RunState, EveryStateIsFoundByItsName) {
  for (auto s : {RunState::kIdle, RunState::kRunning, RunState::kPaused, RunState::kAborting,
                 RunState::kCompleted, RunState::kAborted, RunState::kFailed,
                 RunState::kInterrupted, RunState::kHeld}) {
    EXPECT_EQ(run_state_named(to_string(s)), s) << to_string(s);
  }
  EXPECT_FALSE(run_state_named("Completed").has_value());
  EXPECT_FALSE(run_state_named("").has_value());
}

// One list of final statuses serves the daemon (refusing actions on ended runs), resume and the
// watch client: a checkpointed run is not over, an imported one is.
TEST(RunState, OnlyTerminalAndImportedRunsHaveEnded) {
  for (const char* ended : {"completed", "aborted", "failed", "imported"}) {
    EXPECT_TRUE(has_ended(ended)) << ended;
  }
  for (const char* open :
       {"queued", "running", "paused", "aborting", "interrupted", "held", "idle", ""}) {
    EXPECT_FALSE(has_ended(open)) << open;
  }
  // The store's list (which the fleet's sync reads) is the engine's terminal states.
  for (auto s : {RunState::kIdle, RunState::kRunning, RunState::kPaused, RunState::kAborting,
                 RunState::kCompleted, RunState::kAborted, RunState::kFailed,
                 RunState::kInterrupted, RunState::kHeld}) {
    EXPECT_EQ(has_ended(to_string(s)), is_terminal(s)) << to_string(s);
  }
}

}  // namespace
}  // namespace calstand::daemon
