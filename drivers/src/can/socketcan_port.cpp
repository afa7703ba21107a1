#include "drivers/socketcan_port.hpp"

#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/socket.h>

#include <cerrno>
#include <stdexcept>

#include "drivers/fd_io.hpp"

namespace calstand::drivers {
namespace {

std::string bring_up_hint(const std::string& interface) {
  return "is the CAN driver loaded and the link up? check `ip link show " + interface +
         "`; for a rehearsal without hardware: modprobe vcan; ip link add dev vcan0 type vcan; "
         "ip link set up vcan0";
}

}  // namespace

SocketCanPort::SocketCanPort(std::string interface)
    : interface_(std::move(interface)), filters_(exact_id_filters({})) {}

void SocketCanPort::open() {
  if (socket_.is_open()) return;
  if (interface_.empty() || interface_.size() >= IFNAMSIZ) {
    throw std::runtime_error("\"" + interface_ + "\": not an interface name (1.." +
                             std::to_string(IFNAMSIZ - 1) + " characters)");
  }
  // Looked up before the socket is made, so that a typo reads as such even on a kernel
  // without CAN support.
  const unsigned index = ::if_nametoindex(interface_.c_str());
  if (index == 0) {
    throw std::runtime_error(interface_ + ": no such interface (" + bring_up_hint(interface_) +
                             ")");
  }
  const int fd = ::socket(PF_CAN, SOCK_RAW | SOCK_CLOEXEC, CAN_RAW);
  if (fd < 0) {
    const int err = errno;
    std::string why = os_error_text(interface_, "socket(PF_CAN, SOCK_RAW, CAN_RAW)", err);
    if (err == EAFNOSUPPORT || err == EPROTONOSUPPORT) {
      why += " (the kernel has no SocketCAN: modprobe can; modprobe can_raw)";
    }
    throw std::runtime_error(why);
  }
  CanSocket socket(fd, interface_);  // owns fd from here: closed if anything below throws
  socket_ = std::move(socket);
  try {
    apply_filters();
  } catch (...) {
    socket_.close();
    throw;
  }
  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = static_cast<int>(index);
  if (::bind(socket_.fd(), reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
    const int err = errno;
    socket_.close();
    std::string why = os_error_text(interface_, "bind", err);
    if (err == ENODEV)
      why += " (is it a CAN interface? `ip -details link show " + interface_ + "`)";
    if (err == ENETDOWN) why += " (the link is down: ip link set up " + interface_ + ")";
    throw std::runtime_error(why);
  }
}

void SocketCanPort::set_filters(std::span<const canid_t> ids) {
  filters_ = exact_id_filters(ids);
  if (socket_.is_open()) apply_filters();
}

void SocketCanPort::apply_filters() {
  const auto bytes = static_cast<socklen_t>(filters_.size() * sizeof(can_filter));
  if (::setsockopt(socket_.fd(), SOL_CAN_RAW, CAN_RAW_FILTER, filters_.data(), bytes) != 0) {
    throw std::runtime_error(os_error_text(interface_, "setsockopt(CAN_RAW_FILTER)", errno));
  }
}

}  // namespace calstand::drivers
