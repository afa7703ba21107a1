#pragma once

#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "drivers/can_socket.hpp"
#include "drivers/can_transport.hpp"

namespace calstand::drivers {

/// Frames over one end of a connected socketpair(AF_UNIX, SOCK_SEQPACKET, 0): each message is
/// one struct can_frame, as a CAN_RAW socket delivers them. For tests and simulators on
/// machines whose kernel has no CAN (no vcan). Differences from SocketCanPort, by design:
/// - filters run in user space inside read() (frames failing them are consumed and skipped),
///   since the kernel knows nothing of CAN ids on a Unix socket;
/// - a message that is not 16 bytes long reads as kMalformed (a CAN_RAW socket never has one);
/// - the peer closing its end reads as kError "end of stream", like a link going down.
/// - kernel receive times come if the kernel stamps Unix sockets (Linux does), else none.
class SocketPairCan final : public CanTransport {
 public:
  /// Two connected ends: frames written to one are read from the other. Throws
  /// std::runtime_error with the OS error when the pair cannot be created.
  static std::pair<std::unique_ptr<SocketPairCan>, std::unique_ptr<SocketPairCan>> make_pair();

  /// Takes ownership of an already connected SOCK_SEQPACKET (or SOCK_DGRAM) descriptor.
  explicit SocketPairCan(int connected_fd, std::string name = "socketpair");

  const std::string& name() const override { return name_; }
  /// Nothing to open: the socket is connected from construction. Throws after close(), as a
  /// pair cannot be reconnected.
  void open() override;
  void close() noexcept override { socket_.close(); }
  CanReadResult read(std::chrono::milliseconds timeout) override {
    return socket_.read(timeout, filters_);
  }
  std::string write(const can_frame& frame, std::chrono::milliseconds timeout) override {
    return socket_.write(frame, timeout);
  }
  void set_filters(std::span<const canid_t> ids) override;

  /// The descriptor, for tests that send what a CAN socket never would (wrong sizes).
  int fd() const { return socket_.fd(); }

 private:
  std::string name_;
  std::vector<can_filter> filters_;  // empty: everything passes
  CanSocket socket_;
};

}  // namespace calstand::drivers
