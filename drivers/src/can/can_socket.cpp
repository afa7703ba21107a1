#include "drivers/can_socket.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <string>
#include <utility>

#include "drivers/fd_io.hpp"

namespace calstand::drivers {

CanSocket::CanSocket(int fd, std::string who) : fd_(fd), who_(std::move(who)) {
  if (fd_ < 0) return;
  // Non-blocking: read() and write() wait in poll() so that a timeout is always honoured.
  ::fcntl(fd_, F_SETFL, ::fcntl(fd_, F_GETFL) | O_NONBLOCK);
  // Kernel receive times. Best effort: a socket that cannot give them still carries frames.
  const int on = 1;
  ::setsockopt(fd_, SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof on);
}

CanSocket::~CanSocket() { close(); }

CanSocket::CanSocket(CanSocket&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)), who_(std::move(other.who_)) {}

CanSocket& CanSocket::operator=(CanSocket&& other) noexcept {
  if (this != &other) {
    close();
    fd_ = std::exchange(other.fd_, -1);
    who_ = std::move(other.who_);
  }
  return *this;
}

void CanSocket::close() noexcept {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

CanReadResult CanSocket::read(std::chrono::milliseconds timeout,
                              std::span<const can_filter> user_filters) {
  using Status = CanReadResult::Status;
  if (fd_ < 0) return {Status::kError, {}, who_ + ": not open"};
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    pollfd pfd{fd_, POLLIN, 0};
    const int ready = ::poll(&pfd, 1, remaining_ms(deadline));
    if (ready < 0) {
      if (errno == EINTR) continue;
      return {Status::kError, {}, os_error_text(who_, "poll", errno)};
    }
    if (ready == 0) return {};  // timeout

    // One byte more than a can_frame so that an oversized message shows as such.
    alignas(can_frame) std::uint8_t buffer[sizeof(can_frame) + 1];
    iovec iov{buffer, sizeof buffer};
    alignas(cmsghdr) char control[CMSG_SPACE(sizeof(timespec)) * 2];
    msghdr msg{};
    msg.msg_iov = &iov;
    msg.msg_iovlen = 1;
    msg.msg_control = control;
    msg.msg_controllen = sizeof control;
    const ssize_t n = ::recvmsg(fd_, &msg, MSG_DONTWAIT);
    if (n < 0) {
      if (errno == EINTR || errno == EAGAIN) continue;
      return {Status::kError, {}, os_error_text(who_, "recvmsg", errno)};
    }
    if (n == 0) {
      // A CAN_RAW socket never reads 0 bytes; a socket pair does when the peer has gone.
      return {Status::kError, {}, who_ + ": read: end of stream (peer closed)"};
    }
    if (static_cast<std::size_t>(n) != sizeof(can_frame) || (msg.msg_flags & MSG_TRUNC)) {
      return {Status::kMalformed,
              {},
              who_ + ": a message of " + std::to_string(n) +
                  (n > static_cast<ssize_t>(sizeof(can_frame)) ? "+" : "") +
                  " bytes is not a can_frame (" + std::to_string(sizeof(can_frame)) + " bytes)"};
    }
    CanReadResult result;
    result.status = Status::kFrame;
    std::memcpy(&result.frame.frame, buffer, sizeof(can_frame));
    for (cmsghdr* c = CMSG_FIRSTHDR(&msg); c != nullptr; c = CMSG_NXTHDR(&msg, c)) {
      if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SCM_TIMESTAMPNS) {
        timespec ts{};
        std::memcpy(&ts, CMSG_DATA(c), sizeof ts);
        result.frame.kernel_time_s =
            static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
      }
    }
    if (!user_filters.empty() && !passes_filters(result.frame.frame.can_id, user_filters)) {
      continue;  // as the kernel would have: never seen
    }
    return result;
  }
}

std::string CanSocket::write(const can_frame& frame, std::chrono::milliseconds timeout) {
  if (fd_ < 0) return who_ + ": not open";
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    const ssize_t n = ::send(fd_, &frame, sizeof frame, MSG_DONTWAIT | MSG_NOSIGNAL);
    if (n == static_cast<ssize_t>(sizeof frame)) return {};
    if (n >= 0) return who_ + ": send: short write of " + std::to_string(n) + " bytes";
    if (errno == EINTR) continue;
    if (errno != EAGAIN && errno != ENOBUFS) return os_error_text(who_, "send", errno);
    // Transmit queue full. A CAN socket reports ENOBUFS without waking poll() when the queue
    // drains, so wait in short steps rather than for POLLOUT alone.
    if (remaining_ms(deadline) == 0) return who_ + ": send: timed out (transmit queue full)";
    pollfd pfd{fd_, POLLOUT, 0};
    ::poll(&pfd, 1, std::min(remaining_ms(deadline), 1));
  }
}

}  // namespace calstand::drivers
