#include "drivers/socketpair_can.hpp"

#include <sys/socket.h>

#include <cerrno>
#include <stdexcept>

#include "drivers/fd_io.hpp"

namespace calstand::drivers {

std::pair<std::unique_ptr<SocketPairCan>, std::unique_ptr<SocketPairCan>>
SocketPairCan::make_pair() {
  int fds[2];
  if (::socketpair(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0, fds) != 0) {
    throw std::runtime_error(
        os_error_text("socketpair", "socketpair(AF_UNIX, SOCK_SEQPACKET)", errno));
  }
  return {std::make_unique<SocketPairCan>(fds[0], "socketpair[0]"),
          std::make_unique<SocketPairCan>(fds[1], "socketpair[1]")};
}

SocketPairCan::SocketPairCan(int connected_fd, std::string name)
    : name_(std::move(name)), socket_(connected_fd, name_) {}

void SocketPairCan::open() {
  if (!socket_.is_open())
    throw std::runtime_error(name_ + ": closed (a socket pair cannot be reopened)");
}

void SocketPairCan::set_filters(std::span<const canid_t> ids) {
  // exact_id_filters() of nothing is the pass-all filter; keep empty to skip the check.
  filters_ = ids.empty() ? std::vector<can_filter>{} : exact_id_filters(ids);
}

}  // namespace calstand::drivers
