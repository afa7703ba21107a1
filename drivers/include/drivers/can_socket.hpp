#pragma once

#include <chrono>
#include <span>
#include <string>
#include <vector>

#include "drivers/can_transport.hpp"

namespace calstand::drivers {

/// Frame I/O on a socket carrying one struct can_frame per message (a CAN_RAW socket or a
/// SOCK_SEQPACKET pair), shared by SocketCanPort and SocketPairCan. Owns the descriptor.
/// Reads ask for SO_TIMESTAMPNS and return the kernel's receive time when one comes.
/// read() from one thread; write() may be called from another.
class CanSocket {
 public:
  CanSocket() = default;
  /// Takes ownership of `fd` (made non-blocking; SO_TIMESTAMPNS requested).
  CanSocket(int fd, std::string who);
  ~CanSocket();
  CanSocket(CanSocket&& other) noexcept;
  CanSocket& operator=(CanSocket&& other) noexcept;
  CanSocket(const CanSocket&) = delete;
  CanSocket& operator=(const CanSocket&) = delete;

  int fd() const { return fd_; }
  bool is_open() const { return fd_ >= 0; }
  void close() noexcept;

  /// Reads one message. `user_filters` (if not empty) are applied here, for sockets whose
  /// kernel cannot (socket pairs): frames that fail them are consumed and not returned, and
  /// the wait goes on for the rest of the timeout.
  CanReadResult read(std::chrono::milliseconds timeout, std::span<const can_filter> user_filters);
  std::string write(const can_frame& frame, std::chrono::milliseconds timeout);

 private:
  int fd_ = -1;
  std::string who_;
};

}  // namespace calstand::drivers
