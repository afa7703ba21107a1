#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace calstand::daemon::service {

/// One live-status message (a server-sent event): `type` is e.g. "step", "run", "telemetry",
/// "event"; `seq` numbers messages from 1 in publication order.
struct LiveEvent {
  std::uint64_t seq = 0;
  std::string type;
  nlohmann::json data;
};

/// Fan-out of live-status messages from the run thread to any number of stream readers.
///
/// Publishers never block on readers: the hub keeps the last `capacity` messages and a reader
/// that falls further behind skips the oldest (live status, not a record: the database is the
/// record). Thread safe.
class EventHub {
 public:
  /// `epoch` names this hub's sequence (a daemon process): ids of another epoch are from a
  /// daemon that has since restarted. Default: the wall clock in milliseconds.
  explicit EventHub(std::size_t capacity = 4096, std::string epoch = "");

  void publish(std::string type, nlohmann::json data);

  /// The messages published after `after_seq` that are still kept, oldest first; waits up to
  /// `timeout` for one when there is none. Returns at once (empty) once the hub is closed.
  std::vector<LiveEvent> wait_after(std::uint64_t after_seq, std::chrono::milliseconds timeout);

  /// Sequence number of the last message published (0 before the first).
  std::uint64_t last_seq() const;

  /// The server-sent event id of message `seq`: "EPOCH-SEQ".
  std::string event_id(std::uint64_t seq) const;
  /// Where a reader that reconnects with `Last-Event-ID` resumes.
  struct Replay {
    std::uint64_t after_seq = 0;  ///< the sequence number after which it has seen nothing
    bool restarted = false;       ///< its id is of an earlier epoch: what that process had not
                                  ///< sent it is lost, however much it was
  };
  /// An id of this hub gives its sequence number; an id of an earlier epoch (the daemon
  /// restarted since) gives 0 (everything kept) and `restarted`; an id that is not one of ours,
  /// or lies in the future, gives nullopt (start live).
  std::optional<Replay> replay_after(const std::string& last_event_id) const;

  /// Wakes every waiting reader and makes later waits return at once (server shutdown).
  void close();
  bool closed() const;

 private:
  const std::size_t capacity_;
  const std::string epoch_;
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<LiveEvent> kept_;
  std::uint64_t last_seq_ = 0;
  bool closed_ = false;
};

}  // namespace calstand::daemon::service
