#include "drivers/tcp_client.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <fmt/format.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cstring>

#include "core/error.hpp"
#include "drivers/fd_io.hpp"

namespace calstand::drivers {
namespace {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

int poll_ms(Clock::time_point deadline) {
  const auto left = std::chrono::duration_cast<milliseconds>(deadline - Clock::now());
  return static_cast<int>(std::clamp<long long>(left.count(), 0, INT_MAX));
}

milliseconds left_until(Clock::time_point deadline) {
  return std::max(milliseconds(0),
                  std::chrono::duration_cast<milliseconds>(deadline - Clock::now()));
}

/// The IPv4 address of `host`: numeric at once; a name through the resolver (which may block
/// on DNS beyond the timeout: stations should give controllers numeric addresses).
bool resolve(const std::string& host, in_addr& out, std::string& error) {
  if (::inet_pton(AF_INET, host.c_str(), &out) == 1) return true;
  addrinfo hints{};
  hints.ai_family = AF_INET;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* found = nullptr;
  const int rc = ::getaddrinfo(host.c_str(), nullptr, &hints, &found);
  if (rc != 0 || found == nullptr) {
    error = fmt::format("cannot resolve host '{}': {}", host, ::gai_strerror(rc));
    return false;
  }
  out = reinterpret_cast<sockaddr_in*>(found->ai_addr)->sin_addr;
  ::freeaddrinfo(found);
  return true;
}

}  // namespace

IoResult send_fd(int fd, std::span<const std::uint8_t> bytes, milliseconds timeout,
                 const std::string& who) {
  const auto deadline = Clock::now() + timeout;
  std::size_t sent = 0;
  while (sent < bytes.size()) {
    const ssize_t n = ::send(fd, bytes.data() + sent, bytes.size() - sent, MSG_NOSIGNAL);
    if (n > 0) {
      sent += static_cast<std::size_t>(n);
      continue;
    }
    if (n < 0 && errno != EAGAIN && errno != EINTR) {
      return {sent, os_error_text(who, "send", errno)};
    }
    pollfd pfd{fd, POLLOUT, 0};
    const int ready = ::poll(&pfd, 1, poll_ms(deadline));
    if (ready < 0 && errno != EINTR) return {sent, os_error_text(who, "poll", errno)};
    if (ready == 0) return {sent, who + ": write timed out"};
  }
  return {sent, {}};
}

void TcpOptions::validate() const {
  if (host.empty()) throw core::InputError("tcp.host", "must name the controller, e.g. 127.0.0.1");
  if (port == 0) throw core::InputError("tcp.port", "must be 1..65535");
  if (connect_timeout.count() <= 0) throw core::InputError("tcp.connect_timeout", "must be > 0 ms");
  if (initial_backoff.count() <= 0 || max_backoff < initial_backoff) {
    throw core::InputError("tcp.backoff", "need 0 < initial_backoff <= max_backoff");
  }
}

void ReconnectBackoff::failed(TimePoint now) {
  not_before_ = now + next_delay_;
  next_delay_ = std::min(max_, next_delay_ * 2);
}

void ReconnectBackoff::succeeded() { next_delay_ = initial_; }

milliseconds ReconnectBackoff::wait_left(TimePoint now) const {
  if (now >= not_before_) return milliseconds(0);
  // Rounded up so that "retry in 0 ms" is never said while an attempt is still refused.
  return std::chrono::ceil<milliseconds>(not_before_ - now);
}

TcpClient::TcpClient(TcpOptions options)
    : options_(std::move(options)),
      peer_(fmt::format("{}:{}", options_.host, options_.port)),
      backoff_(options_.initial_backoff, options_.max_backoff) {}

TcpClient::~TcpClient() { close(); }

void TcpClient::close() noexcept {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

void TcpClient::drop() {
  close();
  backoff_.lost(Clock::now());
}

std::string TcpClient::connect(milliseconds timeout) {
  if (fd_ >= 0) return {};
  const auto now = Clock::now();
  if (!backoff_.may_attempt(now)) {
    return fmt::format("{}: not connected (next attempt in {} ms){}", peer_,
                       backoff_.wait_left(now).count(),
                       last_error_.empty() ? "" : "; last attempt: " + last_error_);
  }
  auto error = try_connect(std::min(timeout, options_.connect_timeout));
  if (!error.empty()) {
    ++failed_attempts_;
    backoff_.failed(Clock::now());
    last_error_ = error;
    return error;
  }
  backoff_.succeeded();
  last_error_.clear();
  if (connections_++ > 0) ++reconnects_;
  return {};
}

std::string TcpClient::try_connect(milliseconds timeout) {
  in_addr address{};
  std::string error;
  if (!resolve(options_.host, address, error)) return peer_ + ": " + error;
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) return os_error_text(peer_, "socket", errno);
  sockaddr_in sa{};
  sa.sin_family = AF_INET;
  sa.sin_port = htons(options_.port);
  sa.sin_addr = address;
  // Non-blocking connect, then poll: the only way to bound the time a connect may take.
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&sa), sizeof sa) != 0) {
    if (errno != EINPROGRESS) {
      const int err = errno;
      ::close(fd);
      return os_error_text(peer_, "connect", err);
    }
    const auto deadline = Clock::now() + timeout;
    pollfd pfd{fd, POLLOUT, 0};
    int ready = 0;
    do {
      ready = ::poll(&pfd, 1, poll_ms(deadline));
    } while (ready < 0 && errno == EINTR);
    if (ready <= 0) {
      const int err = errno;
      ::close(fd);
      return ready == 0 ? fmt::format("{}: connect timed out after {} ms", peer_, timeout.count())
                        : os_error_text(peer_, "poll", err);
    }
    int so_error = 0;
    socklen_t len = sizeof so_error;
    ::getsockopt(fd, SOL_SOCKET, SO_ERROR, &so_error, &len);
    if (so_error != 0) {
      ::close(fd);
      return os_error_text(peer_, "connect", so_error);
    }
  }
  // Commands are short lines answered one at a time: Nagle would only add latency.
  const int one = 1;
  ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
  fd_ = fd;
  return {};
}

IoResult TcpClient::read(std::span<std::uint8_t> buffer, milliseconds timeout) {
  // A zero-timeout read only drains an open link: an attempt with no time cannot succeed and
  // would only push the backoff further out.
  if (fd_ < 0 && timeout.count() <= 0) return {0, peer_ + ": not connected"};
  const auto deadline = Clock::now() + timeout;
  if (auto error = connect(timeout); !error.empty()) return {0, error};
  IoResult r = read_fd(fd_, buffer, left_until(deadline), peer_);
  if (!r.ok()) drop();
  return r;
}

IoResult TcpClient::write(std::span<const std::uint8_t> bytes, milliseconds timeout) {
  const auto deadline = Clock::now() + timeout;
  if (auto error = connect(timeout); !error.empty()) return {0, error};
  IoResult r = send_fd(fd_, bytes, left_until(deadline), peer_);
  // A partial write leaves the peer with half a command: only a new connection resynchronises.
  if (!r.ok()) drop();
  return r;
}

}  // namespace calstand::drivers
