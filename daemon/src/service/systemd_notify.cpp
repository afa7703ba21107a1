#include "daemon/service/systemd_notify.hpp"

#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstddef>
#include <cstdlib>
#include <cstring>
#include <string>
#include <system_error>
#include <utility>

namespace calstand::daemon::service {
namespace {

// sockaddr_un for a path, or for an abstract name when it starts with '@' (sd_notify(3)).
std::pair<sockaddr_un, socklen_t> notify_address(const std::string& path) {
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  if (path.size() >= sizeof(addr.sun_path)) {
    throw std::system_error(ENAMETOOLONG, std::generic_category(), "NOTIFY_SOCKET " + path);
  }
  std::memcpy(addr.sun_path, path.data(), path.size());
  if (path[0] == '@') addr.sun_path[0] = '\0';
  // An abstract name has no terminating NUL: its length is exactly the name's.
  const auto len = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + path.size() +
                                          (path[0] == '@' ? 0 : 1));
  return {addr, len};
}

}  // namespace

SystemdNotifier::SystemdNotifier(std::string socket_path,
                                 std::optional<std::chrono::microseconds> watchdog)
    : path_(std::move(socket_path)), watchdog_(watchdog) {
  if (path_.empty() || (path_[0] != '/' && path_[0] != '@')) {
    throw std::system_error(EAFNOSUPPORT, std::generic_category(),
                            "NOTIFY_SOCKET '" + path_ + "' is neither a path nor an @name");
  }
  notify_address(path_);  // checks the length before a socket is opened
  fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd_ < 0) throw std::system_error(errno, std::generic_category(), "socket(AF_UNIX)");
}

SystemdNotifier::~SystemdNotifier() {
  if (fd_ >= 0) ::close(fd_);
}

SystemdNotifier::SystemdNotifier(SystemdNotifier&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)),
      path_(std::move(other.path_)),
      watchdog_(std::exchange(other.watchdog_, std::nullopt)) {}

SystemdNotifier& SystemdNotifier::operator=(SystemdNotifier&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    fd_ = std::exchange(other.fd_, -1);
    path_ = std::move(other.path_);
    watchdog_ = std::exchange(other.watchdog_, std::nullopt);
  }
  return *this;
}

SystemdNotifier SystemdNotifier::from_environment() {
  const char* socket = std::getenv("NOTIFY_SOCKET");
  const char* usec = std::getenv("WATCHDOG_USEC");
  const char* pid = std::getenv("WATCHDOG_PID");
  std::string path = socket ? socket : "";
  std::optional<std::chrono::microseconds> watchdog;
  // WATCHDOG_PID names the process the watchdog is meant for; another's is not ours.
  const bool for_us = pid == nullptr || std::strtoll(pid, nullptr, 10) == ::getpid();
  if (usec != nullptr && for_us) {
    const long long us = std::strtoll(usec, nullptr, 10);
    if (us > 0) watchdog = std::chrono::microseconds(us);
  }
  ::unsetenv("NOTIFY_SOCKET");
  ::unsetenv("WATCHDOG_USEC");
  ::unsetenv("WATCHDOG_PID");
  if (path.empty()) return {};
  return SystemdNotifier(std::move(path), watchdog);
}

bool SystemdNotifier::notify(std::string_view message) const {
  if (fd_ < 0) return false;
  const auto [addr, len] = notify_address(path_);
  ssize_t sent = 0;
  do {
    sent = ::sendto(fd_, message.data(), message.size(), MSG_NOSIGNAL,
                    reinterpret_cast<const sockaddr*>(&addr), len);
  } while (sent < 0 && errno == EINTR);
  return sent == static_cast<ssize_t>(message.size());
}

}  // namespace calstand::daemon::service
