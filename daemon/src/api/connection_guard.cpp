#include "connection_guard.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <openssl/ssl.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <climits>
#include <cstring>
#include <functional>
#include <nlohmann/json.hpp>

namespace calstand::daemon::api {

bool AddressCounter::admit(const std::string& address, int cap) {
  std::lock_guard lock(mutex_);
  int& held = held_[address];
  if (held >= cap) return false;
  ++held;
  return true;
}

void AddressCounter::release(const std::string& address) {
  std::lock_guard lock(mutex_);
  const auto it = held_.find(address);
  if (it == held_.end()) return;
  if (--it->second <= 0) held_.erase(it);
}

int AddressCounter::held(const std::string& address) const {
  std::lock_guard lock(mutex_);
  const auto it = held_.find(address);
  return it == held_.end() ? 0 : it->second;
}

namespace {

using Clock = std::chrono::steady_clock;
using std::chrono::milliseconds;

milliseconds to_ms(time_t sec, time_t usec) {
  return milliseconds(static_cast<long long>(sec) * 1000 + static_cast<long long>(usec) / 1000);
}

std::string address_of(const sockaddr_storage& addr, int* port) {
  char text[INET6_ADDRSTRLEN] = {};
  if (addr.ss_family == AF_INET) {
    const auto* a = reinterpret_cast<const sockaddr_in*>(&addr);
    ::inet_ntop(AF_INET, &a->sin_addr, text, sizeof text);
    if (port) *port = ntohs(a->sin_port);
  } else if (addr.ss_family == AF_INET6) {
    const auto* a = reinterpret_cast<const sockaddr_in6*>(&addr);
    ::inet_ntop(AF_INET6, &a->sin6_addr, text, sizeof text);
    if (port) *port = ntohs(a->sin6_port);
  }
  return text;
}

/// One connection as httplib's request parser reads and writes it: a non-blocking socket (with
/// TLS over it when `ssl`), every wait a poll() bounded by the read or write timeout and, while a
/// request is being read, by its deadline.
class GuardedStream final : public httplib::Stream {
 public:
  GuardedStream(socket_t sock, SSL* ssl, milliseconds read_timeout, milliseconds write_timeout)
      : sock_(sock), ssl_(ssl), read_timeout_(read_timeout), write_timeout_(write_timeout) {}

  void set_deadline(Clock::time_point at) { deadline_ = at; }
  /// Forgets what was read beyond the last request, as httplib does (its stream, buffer and
  /// all, lives for one request): the unread body of a request refused before its body was
  /// read is not taken for the start of the next one.
  void drop_read_ahead() { buffered_ = filled_ = 0; }
  /// Input already decrypted by TLS, not yet read (bytes in our own buffer are dropped at the
  /// next request: drop_read_ahead).
  bool has_pending_input() const { return ssl_ != nullptr && SSL_pending(ssl_) > 0; }

  bool is_readable() const override {
    return buffered_ < filled_ || has_pending_input() || wait(POLLIN, read_wait());
  }
  bool is_writable() const override { return wait(POLLOUT, write_timeout_) && peer_open(); }

  ssize_t read(char* ptr, size_t size) override {
    if (buffered_ == filled_) {
      if (size >= sizeof buffer_) return read_raw(ptr, size);
      const ssize_t n = read_raw(buffer_, sizeof buffer_);
      if (n <= 0) return n;
      buffered_ = 0;
      filled_ = static_cast<std::size_t>(n);
    }
    const std::size_t n = std::min(size, filled_ - buffered_);
    std::memcpy(ptr, buffer_ + buffered_, n);
    buffered_ += n;
    return static_cast<ssize_t>(n);
  }

  ssize_t write(const char* ptr, size_t size) override {
    for (;;) {
      if (ssl_ != nullptr) {
        const int n = SSL_write(ssl_, ptr, static_cast<int>(std::min<size_t>(size, INT_MAX)));
        if (n > 0) return n;
        const int e = SSL_get_error(ssl_, n);
        if (e == SSL_ERROR_WANT_WRITE && wait(POLLOUT, write_timeout_)) continue;
        if (e == SSL_ERROR_WANT_READ && wait(POLLIN, write_timeout_)) continue;
        return -1;
      }
      const ssize_t n = ::send(sock_, ptr, size, MSG_NOSIGNAL);
      if (n >= 0) return n;
      if (errno == EINTR) continue;
      if ((errno == EAGAIN || errno == EWOULDBLOCK) && wait(POLLOUT, write_timeout_)) continue;
      return -1;
    }
  }

  void get_remote_ip_and_port(std::string& ip, int& port) const override {
    sockaddr_storage addr{};
    socklen_t len = sizeof addr;
    if (::getpeername(sock_, reinterpret_cast<sockaddr*>(&addr), &len) == 0) {
      ip = address_of(addr, &port);
    }
  }
  void get_local_ip_and_port(std::string& ip, int& port) const override {
    sockaddr_storage addr{};
    socklen_t len = sizeof addr;
    if (::getsockname(sock_, reinterpret_cast<sockaddr*>(&addr), &len) == 0) {
      ip = address_of(addr, &port);
    }
  }
  socket_t socket() const override { return sock_; }

  /// The TLS handshake, within the deadline.
  bool handshake() {
    for (;;) {
      const int n = SSL_accept(ssl_);
      if (n == 1) return true;
      const int e = SSL_get_error(ssl_, n);
      if (e == SSL_ERROR_WANT_READ && wait(POLLIN, read_wait())) continue;
      if (e == SSL_ERROR_WANT_WRITE && wait(POLLOUT, write_timeout_)) continue;
      return false;
    }
  }

  /// Waits for `events` on the socket for at most `limit`; true when ready (or hung up: the
  /// next read or write then says so).
  bool wait(short events, milliseconds limit) const {
    if (limit.count() <= 0) return false;
    pollfd p{sock_, events, 0};
    for (;;) {
      const int n = ::poll(&p, 1, static_cast<int>(std::min<long long>(limit.count(), INT_MAX)));
      if (n < 0 && errno == EINTR) continue;
      return n > 0;
    }
  }

 private:
  /// How long a read may wait: the read timeout, cut short by the request's deadline.
  milliseconds read_wait() const {
    if (deadline_ == Clock::time_point::max()) return read_timeout_;
    const auto left = std::chrono::duration_cast<milliseconds>(deadline_ - Clock::now());
    return std::min(read_timeout_, left);
  }

  // The peer has not closed its end (a live stream ends when its client goes).
  bool peer_open() const {
    char byte = 0;
    const ssize_t n = ::recv(sock_, &byte, 1, MSG_PEEK | MSG_DONTWAIT);
    return n != 0;
  }

  ssize_t read_raw(char* ptr, size_t size) {
    for (;;) {
      if (ssl_ != nullptr) {
        const int n = SSL_read(ssl_, ptr, static_cast<int>(std::min<size_t>(size, INT_MAX)));
        if (n > 0) return n;
        const int e = SSL_get_error(ssl_, n);
        if (e == SSL_ERROR_WANT_READ && wait(POLLIN, read_wait())) continue;
        if (e == SSL_ERROR_WANT_WRITE && wait(POLLOUT, write_timeout_)) continue;
        return e == SSL_ERROR_ZERO_RETURN ? 0 : -1;
      }
      const ssize_t n = ::recv(sock_, ptr, size, 0);
      if (n >= 0) return n;
      if (errno == EINTR) continue;
      if ((errno == EAGAIN || errno == EWOULDBLOCK) && wait(POLLIN, read_wait())) continue;
      return -1;
    }
  }

  socket_t sock_;
  SSL* ssl_;
  milliseconds read_timeout_;
  milliseconds write_timeout_;
  Clock::time_point deadline_ = Clock::time_point::max();
  char buffer_[4096] = {};
  std::size_t buffered_ = 0;  ///< read position in buffer_
  std::size_t filled_ = 0;
};

struct ConnectionSettings {
  milliseconds read_timeout;
  milliseconds write_timeout;
  milliseconds keep_alive_timeout;
  std::size_t keep_alive_max_count = 1;
  const std::atomic<socket_t>* server_socket = nullptr;
  GuardLimits limits;
};

using ProcessRequest = std::function<bool(httplib::Stream&, bool, bool&)>;

// Between requests: the next one's first byte within the keep-alive timeout, looking every
// 100 ms whether the server is stopping (as httplib's own loop does).
bool next_request_arrives(GuardedStream& strm, const ConnectionSettings& s) {
  const auto until = Clock::now() + s.keep_alive_timeout;
  while (*s.server_socket != INVALID_SOCKET) {
    if (strm.has_pending_input()) return true;
    const auto left = std::chrono::duration_cast<milliseconds>(until - Clock::now());
    if (left.count() <= 0) return false;
    if (strm.wait(POLLIN, std::min(left, milliseconds(100)))) return true;
  }
  return false;
}

void refuse(GuardedStream& strm, const std::string& peer, int cap) {
  const std::string body =
      nlohmann::json({{"error", "this client address holds " + std::to_string(cap) +
                                    " connections already, the most one address may hold; "
                                    "close one or wait"},
                      {"where", "connection from " + peer}})
          .dump() +
      "\n";
  const std::string answer =
      "HTTP/1.1 503 Service Unavailable\r\nContent-Type: "
      "application/json\r\nRetry-After: 5\r\nConnection: close\r\n"
      "Content-Length: " +
      std::to_string(body.size()) + "\r\n\r\n" + body;
  std::size_t sent = 0;
  while (sent < answer.size()) {
    const ssize_t n = strm.write(answer.data() + sent, answer.size() - sent);
    if (n <= 0) break;
    sent += static_cast<std::size_t>(n);
  }
}

bool serve_connection(socket_t sock, SSL_CTX* tls, const ConnectionSettings& s,
                      AddressCounter& counter, const ProcessRequest& process) {
  sockaddr_storage addr{};
  socklen_t len = sizeof addr;
  std::string peer = "?";
  if (::getpeername(sock, reinterpret_cast<sockaddr*>(&addr), &len) == 0) {
    peer = address_of(addr, nullptr);
  }
  const int flags = ::fcntl(sock, F_GETFL, 0);
  ::fcntl(sock, F_SETFL, flags | O_NONBLOCK);
  SSL* ssl = nullptr;
  if (tls != nullptr) {
    ssl = SSL_new(tls);
    if (ssl != nullptr) SSL_set_fd(ssl, static_cast<int>(sock));
  }
  GuardedStream strm(sock, ssl, s.read_timeout, s.write_timeout);
  const auto deadline = [&] {
    return Clock::now() + std::chrono::seconds(s.limits.request_deadline_s);
  };
  bool ret = false;
  bool ready = tls == nullptr || ssl != nullptr;
  if (ready && ssl != nullptr) {
    strm.set_deadline(deadline());
    ready = strm.handshake();
  }
  if (ready) {
    if (!counter.admit(peer, s.limits.max_connections_per_address)) {
      refuse(strm, peer, s.limits.max_connections_per_address);
    } else {
      std::size_t count = s.keep_alive_max_count;
      while (count > 0 && next_request_arrives(strm, s)) {
        // Each request from its first byte: line, headers and body within the deadline.
        strm.set_deadline(deadline());
        strm.drop_read_ahead();
        const bool close_connection = count == 1;
        bool connection_closed = false;
        ret = process(strm, close_connection, connection_closed);
        if (!ret || connection_closed) break;
        --count;
      }
      counter.release(peer);
    }
  }
  if (ssl != nullptr) {
    if (ready) SSL_shutdown(ssl);
    SSL_free(ssl);
  }
  ::shutdown(sock, SHUT_RDWR);
  ::close(sock);
  return ret;
}

}  // namespace

bool GuardedServer::process_and_close_socket(socket_t sock) {
  const ConnectionSettings s{to_ms(read_timeout_sec_, read_timeout_usec_),
                             to_ms(write_timeout_sec_, write_timeout_usec_),
                             milliseconds(static_cast<long long>(keep_alive_timeout_sec_) * 1000),
                             keep_alive_max_count_,
                             &svr_sock_,
                             limits_};
  return serve_connection(sock, nullptr, s, counter_,
                          [this](httplib::Stream& strm, bool close, bool& closed) {
                            return process_request(strm, close, closed, nullptr);
                          });
}

bool GuardedSslServer::process_and_close_socket(socket_t sock) {
  const ConnectionSettings s{to_ms(read_timeout_sec_, read_timeout_usec_),
                             to_ms(write_timeout_sec_, write_timeout_usec_),
                             milliseconds(static_cast<long long>(keep_alive_timeout_sec_) * 1000),
                             keep_alive_max_count_,
                             &svr_sock_,
                             limits_};
  return serve_connection(sock, ssl_context(), s, counter_,
                          [this](httplib::Stream& strm, bool close, bool& closed) {
                            return process_request(strm, close, closed, nullptr);
                          });
}

}  // namespace calstand::daemon::api
