#pragma once

#include <chrono>
#include <cstdint>
#include <span>
#include <string>

#include "drivers/serial_port.hpp"

namespace calstand::drivers {

/// Settings of a TCP client link.
struct TcpOptions {
  std::string host = "127.0.0.1";  ///< IPv4 address or host name
  std::uint16_t port = 0;
  std::chrono::milliseconds connect_timeout{1000};  ///< one connection attempt, at most
  /// Wait before the next attempt after a failed one: starts here, doubles per failure up to
  /// max_backoff, back to the start after a success. The first attempt after a link that
  /// worked is lost is made at once.
  std::chrono::milliseconds initial_backoff{100};
  std::chrono::milliseconds max_backoff{5000};

  /// Throws core::InputError naming the field (`tcp.host`, `tcp.port`, ...).
  void validate() const;
};

/// write_fd() for a socket: send() with MSG_NOSIGNAL, so that writing to a peer that hung up
/// is an error (EPIPE) instead of a SIGPIPE that kills the process. Same contract as write_fd.
IoResult send_fd(int fd, std::span<const std::uint8_t> bytes, std::chrono::milliseconds timeout,
                 const std::string& who);

/// Exponential backoff between reconnection attempts. Pure bookkeeping on steady_clock times
/// passed in, so that tests can reason about it without sleeping. Not thread safe.
class ReconnectBackoff {
 public:
  using TimePoint = std::chrono::steady_clock::time_point;
  ReconnectBackoff(std::chrono::milliseconds initial, std::chrono::milliseconds max)
      : initial_(initial), max_(max), next_delay_(initial) {}
  /// True when an attempt may be made at `now`.
  bool may_attempt(TimePoint now) const { return now >= not_before_; }
  /// An attempt failed at `now`: the next is not before now + delay, and the delay doubles.
  void failed(TimePoint now);
  /// An attempt succeeded: the delay goes back to the initial one.
  void succeeded();
  /// A working link was lost at `now`: the next attempt may be made at once.
  void lost(TimePoint now) { not_before_ = now; }
  /// Time left before the next attempt (zero when one may be made now).
  std::chrono::milliseconds wait_left(TimePoint now) const;
  /// The delay the next failure will impose.
  std::chrono::milliseconds next_delay() const { return next_delay_; }

 private:
  std::chrono::milliseconds initial_;
  std::chrono::milliseconds max_;
  std::chrono::milliseconds next_delay_;
  TimePoint not_before_{};
};

/// A ByteTransport over a TCP socket that reconnects by itself. The constructor does no I/O;
/// connect() or the first read()/write() opens the link. When the link fails (peer hung up, OS
/// error), the socket is closed and a later call reconnects, with exponential backoff between
/// failed attempts (TcpOptions). No call blocks longer than its timeout: a connection attempt
/// made inside read()/write() is bounded by what is left of the caller's timeout, and while the
/// backoff runs the call fails at once saying when the next attempt is due. Not thread safe
/// (the owning driver serialises calls).
class TcpClient final : public ByteTransport {
 public:
  explicit TcpClient(TcpOptions options);
  ~TcpClient() override;
  TcpClient(const TcpClient&) = delete;
  TcpClient& operator=(const TcpClient&) = delete;

  /// Connects now if not connected and the backoff allows, waiting at most
  /// min(timeout, connect_timeout). Empty string on success, otherwise why not (host:port and
  /// the OS error, or the backoff still running).
  std::string connect(std::chrono::milliseconds timeout);
  void close() noexcept;
  bool is_connected() const { return fd_ >= 0; }

  /// Reads what is available (IoResult as ByteTransport); reconnects first when needed, except
  /// with a zero timeout (a drain), which fails at once while not connected.
  IoResult read(std::span<std::uint8_t> buffer, std::chrono::milliseconds timeout) override;
  /// Writes all of `bytes`; reconnects first when needed.
  IoResult write(std::span<const std::uint8_t> bytes, std::chrono::milliseconds timeout) override;

  /// Successful connections after the first one [count].
  std::uint64_t reconnects() const { return reconnects_; }
  /// Connection attempts that failed [count].
  std::uint64_t failed_attempts() const { return failed_attempts_; }
  const std::string& peer() const { return peer_; }  ///< "host:port", for messages

 private:
  /// Opens the socket within `timeout`; empty string or the error.
  std::string try_connect(std::chrono::milliseconds timeout);
  /// Closes after an I/O error so the next call reconnects.
  void drop();

  TcpOptions options_;
  std::string peer_;
  int fd_ = -1;
  ReconnectBackoff backoff_;
  std::string last_error_;
  std::uint64_t connections_ = 0;
  std::uint64_t reconnects_ = 0;
  std::uint64_t failed_attempts_ = 0;
};

}  // namespace calstand::drivers
