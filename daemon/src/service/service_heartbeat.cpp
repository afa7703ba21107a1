#include "daemon/service/service_heartbeat.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <utility>

namespace calstand::daemon::service {
namespace {

// The status is looked at this often at most: often enough that `systemctl status` is current,
// rarely enough that copying the live snapshot costs nothing next to an engine tick.
constexpr auto kStatusLookPeriod = std::chrono::milliseconds(250);

}  // namespace

std::string status_line(const LiveSnapshot& live) {
  if (live.run) {
    const bool paused = live.progress.state == RunState::kPaused;
    std::string line =
        fmt::format("{} run {} step {}/{}", paused ? "paused" : "running", *live.run,
                    std::min(live.progress.step + 1, std::max<std::size_t>(live.progress.steps, 1)),
                    live.progress.steps);
    if (!paused && !live.progress.phase.empty()) line += " (" + live.progress.phase + ")";
    return line;
  }
  if (live.held) {
    return fmt::format("held: run {} waits for an operator's resume or abort", *live.held);
  }
  if (live.waiting) return "waiting: " + *live.waiting;
  return "idle";
}

ServiceHeartbeat::ServiceHeartbeat(const SystemdNotifier& notifier,
                                   std::function<LiveSnapshot()> snapshot)
    : notifier_(notifier), snapshot_(std::move(snapshot)) {
  look_period_ = kStatusLookPeriod;
  ping_period_ = std::chrono::hours(24);
  if (const auto w = notifier_.watchdog()) {
    // sd_watchdog_enabled(3): ping in half the interval; the status is looked at as often.
    ping_period_ = std::chrono::duration_cast<std::chrono::steady_clock::duration>(*w / 2);
    look_period_ = std::min(look_period_, ping_period_);
  }
}

void ServiceHeartbeat::beat() {
  if (!notifier_.enabled()) return;
  const auto now = std::chrono::steady_clock::now();
  if (now < next_look_) return;
  next_look_ = now + look_period_;
  std::string message;
  if (notifier_.watchdog() && now >= next_ping_) {
    message = "WATCHDOG=1\n";
    next_ping_ = now + ping_period_;
  }
  std::string status = status_line(snapshot_());
  if (status != last_status_) {
    // One line: systemd shows the value up to the newline.
    std::replace(status.begin(), status.end(), '\n', ' ');
    message += "STATUS=" + status + "\n";
    last_status_ = std::move(status);
  }
  if (!message.empty()) notifier_.notify(message);
}

}  // namespace calstand::daemon::service
