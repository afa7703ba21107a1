#pragma once

#include <chrono>
#include <functional>
#include <string>

#include "daemon/service/live_status.hpp"
#include "daemon/service/systemd_notify.hpp"

namespace calstand::daemon::service {

/// The STATUS= line systemd shows for a live snapshot: "running run 12 step 3/24 (capturing)",
/// "paused run 12 step 3/24", "waiting: <why>" (a run that cannot start now), "held: run 12
/// waits for an operator's resume or abort", or "idle". Steps counted from 1.
std::string status_line(const LiveSnapshot& live);

/// What the run thread tells systemd each time round its loop (between runs) and each engine
/// tick (in a run): the STATUS= line when it changed, and WATCHDOG=1 at least every half
/// watchdog interval. Fed from the run thread only, the thread that drives the devices: if it
/// hangs, the pings stop and systemd restarts the daemon (WatchdogSec=). Other threads (the
/// API's) keep running then, and must not ping.
///
/// Thread safety: beat() from one thread (the run thread) only.
class ServiceHeartbeat {
 public:
  /// `notifier` and the snapshot source outlive the heartbeat.
  ServiceHeartbeat(const SystemdNotifier& notifier, std::function<LiveSnapshot()> snapshot);

  /// Cheap when nothing is due (one clock read): the engine calls it every tick, thousands of
  /// times a second on a simulated clock.
  void beat();

 private:
  const SystemdNotifier& notifier_;
  std::function<LiveSnapshot()> snapshot_;
  std::chrono::steady_clock::duration look_period_;  // how often the status is read
  std::chrono::steady_clock::duration ping_period_;  // half the watchdog interval
  std::chrono::steady_clock::time_point next_look_{};
  std::chrono::steady_clock::time_point next_ping_{};
  std::string last_status_;
};

}  // namespace calstand::daemon::service
