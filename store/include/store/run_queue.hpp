#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "store/database.hpp"

namespace calstand::store {

/// Run statuses of the station daemon beside the engine's (running, paused, completed, ...).
inline constexpr const char* kQueuedStatus = "queued";  ///< waiting in run_queue
inline constexpr const char* kHeldStatus = "held";      ///< interrupted, waits for an operator
inline constexpr const char* kInterruptedStatus = "interrupted";  ///< checkpointed by a daemon stop

/// A queued run, as table run_queue holds it.
struct QueuedRun {
  std::int64_t run = 0;
  std::string submitted_utc;
  std::string submitted_by;
};

/// Puts run `run` (created with status 'queued') at the end of the daemon's queue.
/// Throws StoreError on SQL failure.
void enqueue_run(Database& db, std::int64_t run, const std::string& submitted_by);

/// The queued runs, oldest first (runs whose status is still 'queued').
std::vector<QueuedRun> queued_runs(Database& db);

/// Removes `run` from the queue (it started, or was aborted before starting).
void dequeue_run(Database& db, std::int64_t run);

/// Runs cut off before they ended: status running, paused, held or interrupted, oldest first.
std::vector<std::int64_t> interrupted_runs(Database& db);

/// Sets a run that stopped without ending back to a resumable `status` (held or interrupted):
/// clears its end time and records `reason` as its exit reason.
void mark_run_resumable(Database& db, std::int64_t run, const std::string& status,
                        const std::string& reason);

}  // namespace calstand::store
