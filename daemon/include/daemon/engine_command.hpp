#pragma once

#include <cstddef>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace calstand::daemon {

/// One request to a running engine: an operator's (pause, resume, abort, skip) or the
/// daemon's (interrupt: a checkpoint because it is stopping).
struct EngineCommand {
  enum class Kind { kPause, kResume, kAbort, kInterrupt, kSkip };
  Kind kind = Kind::kPause;
  bool immediate = false;           ///< kPause: at once, not at the next step boundary
  std::optional<std::size_t> step;  ///< kSkip: the step the operator means (none: the current)
  std::string why;                  ///< kAbort, kInterrupt, kSkip: the reason recorded
  std::string who;                  ///< who asked, recorded with the request
};

/// Requests to one engine from any thread, taken by the engine's own thread in the order they
/// were pushed (a pause and an abort arriving together are applied in that order: the run
/// ends aborted). push() never waits for the engine: the lock is held only to append or to
/// swap the list, never across I/O. Thread-safe.
class EngineCommandQueue {
 public:
  void push(EngineCommand command);
  /// Every request pushed since the last call, oldest first (empty when none).
  std::vector<EngineCommand> take_all();
  /// Drops the requests waiting (a new run starts with none).
  void clear();

 private:
  std::mutex mutex_;
  std::vector<EngineCommand> pending_;
};

}  // namespace calstand::daemon
