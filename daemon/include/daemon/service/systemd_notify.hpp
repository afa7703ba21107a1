#pragma once

#include <chrono>
#include <optional>
#include <string>
#include <string_view>

namespace calstand::daemon::service {

/// The service manager's notification socket: the datagram protocol of sd_notify(3), written
/// out (an AF_UNIX datagram of "KEY=VALUE" lines to $NOTIFY_SOCKET, a path or, with a leading
/// '@', an abstract name), so that calstandd needs no libsystemd. docs/packaging.md lists the
/// messages calstandd sends.
///
/// Thread safety: notify() may be called from any thread (one sendto() per message).
class SystemdNotifier {
 public:
  /// A notifier that sends nothing (not run by systemd, or Type= other than notify).
  SystemdNotifier() = default;
  /// Sends to `socket_path`; `watchdog` is the interval systemd expects pings within (none: no
  /// watchdog). Opens the socket here; throws std::system_error when it cannot.
  SystemdNotifier(std::string socket_path, std::optional<std::chrono::microseconds> watchdog);
  ~SystemdNotifier();
  SystemdNotifier(SystemdNotifier&& other) noexcept;
  SystemdNotifier& operator=(SystemdNotifier&& other) noexcept;
  SystemdNotifier(const SystemdNotifier&) = delete;
  SystemdNotifier& operator=(const SystemdNotifier&) = delete;

  /// From the environment systemd gives a Type=notify service: $NOTIFY_SOCKET, and
  /// $WATCHDOG_USEC when $WATCHDOG_PID is unset or this process. Removes the three variables
  /// from the environment, so that programs the daemon starts (a PDF printer) do not speak
  /// for it. Disabled when $NOTIFY_SOCKET is unset.
  static SystemdNotifier from_environment();

  bool enabled() const { return fd_ >= 0; }
  /// The watchdog interval systemd enforces (WatchdogSec=), when it does.
  std::optional<std::chrono::microseconds> watchdog() const { return watchdog_; }
  /// Sends `message` (newline-separated assignments, e.g. "READY=1\nSTATUS=idle"). Returns
  /// false when not enabled or the send failed (systemd gone: nothing to do about it).
  bool notify(std::string_view message) const;

 private:
  int fd_ = -1;
  std::string path_;
  std::optional<std::chrono::microseconds> watchdog_;
};

}  // namespace calstand::daemon::service
