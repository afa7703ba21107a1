#include "drivers/fd_io.hpp"

#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cstring>

namespace calstand::drivers {

int remaining_ms(std::chrono::steady_clock::time_point deadline) {
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
      deadline - std::chrono::steady_clock::now());
  return static_cast<int>(std::clamp<long long>(left.count(), 0, INT_MAX));
}

std::string os_error_text(const std::string& who, const char* what, int err) {
  return who + ": " + what + ": " + std::strerror(err);
}

IoResult read_fd(int fd, std::span<std::uint8_t> buffer, std::chrono::milliseconds timeout,
                 const std::string& who) {
  if (buffer.empty()) return {};
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    pollfd pfd{fd, POLLIN, 0};
    const int ready = ::poll(&pfd, 1, remaining_ms(deadline));
    if (ready < 0) {
      if (errno == EINTR) continue;  // a signal is not a timeout: wait out the rest
      return {0, os_error_text(who, "poll", errno)};
    }
    if (ready == 0) return {};  // timeout, no data
    const ssize_t n = ::read(fd, buffer.data(), buffer.size());
    if (n > 0) return {static_cast<std::size_t>(n), {}};
    if (n < 0 && (errno == EINTR || errno == EAGAIN)) continue;
    if (n < 0) return {0, os_error_text(who, "read", errno)};
    // poll said readable but there is nothing: the other end hung up.
    return {0, who + ": read: end of stream (device gone)"};
  }
}

IoResult write_fd(int fd, std::span<const std::uint8_t> bytes, std::chrono::milliseconds timeout,
                  const std::string& who) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  std::size_t sent = 0;
  while (sent < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + sent, bytes.size() - sent);
    if (n > 0) {
      sent += static_cast<std::size_t>(n);
      continue;
    }
    if (n < 0 && errno != EAGAIN && errno != EINTR)
      return {sent, os_error_text(who, "write", errno)};
    pollfd pfd{fd, POLLOUT, 0};
    const int ready = ::poll(&pfd, 1, remaining_ms(deadline));
    if (ready < 0 && errno != EINTR) return {sent, os_error_text(who, "poll", errno)};
    if (ready == 0) return {sent, who + ": write timed out"};
  }
  return {sent, {}};
}

}  // namespace calstand::drivers
