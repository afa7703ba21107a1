#pragma once

#include <string>
#include <vector>

#include "drivers/can_socket.hpp"
#include "drivers/can_transport.hpp"

namespace calstand::drivers {

/// A Linux SocketCAN raw socket (PF_CAN, SOCK_RAW, CAN_RAW) bound to one interface ("can0",
/// "vcan0"). Receive filters run in the kernel (CAN_RAW_FILTER), so frames of other ids never
/// wake the reader. Frames carry the kernel's receive time (SO_TIMESTAMPNS). Classic CAN only
/// (8-byte payloads; CAN FD frames are not enabled on the socket). The constructor does no
/// I/O; open() does; closes on destruction.
class SocketCanPort final : public CanTransport {
 public:
  explicit SocketCanPort(std::string interface);

  const std::string& name() const override { return interface_; }
  /// Throws std::runtime_error naming the interface: no such interface (with how to check the
  /// driver or bring up vcan), no CAN support in the kernel, not a CAN interface, or the OS
  /// error text.
  void open() override;
  void close() noexcept override { socket_.close(); }
  CanReadResult read(std::chrono::milliseconds timeout) override {
    return socket_.read(timeout, {});
  }
  std::string write(const can_frame& frame, std::chrono::milliseconds timeout) override {
    return socket_.write(frame, timeout);
  }
  void set_filters(std::span<const canid_t> ids) override;

 private:
  void apply_filters();

  std::string interface_;
  std::vector<can_filter> filters_;
  CanSocket socket_;
};

}  // namespace calstand::drivers
