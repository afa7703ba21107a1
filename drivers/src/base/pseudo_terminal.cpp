#include "drivers/pseudo_terminal.hpp"

#include <fcntl.h>
#include <stdlib.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <stdexcept>

#include "drivers/fd_io.hpp"

namespace calstand::drivers {

PseudoTerminal::PseudoTerminal() {
  master_ = ::posix_openpt(O_RDWR | O_NOCTTY | O_NONBLOCK);
  if (master_ < 0)
    throw std::runtime_error(os_error_text("pseudo-terminal", "posix_openpt", errno));
  if (::grantpt(master_) != 0 || ::unlockpt(master_) != 0) {
    const int err = errno;
    ::close(master_);
    throw std::runtime_error(os_error_text("pseudo-terminal", "grantpt/unlockpt", err));
  }
  slave_path_ = ::ptsname(master_);
  slave_ = ::open(slave_path_.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK);
  termios tio{};
  if (slave_ < 0 || ::tcgetattr(slave_, &tio) != 0) {
    const int err = errno;
    if (slave_ >= 0) ::close(slave_);
    ::close(master_);
    throw std::runtime_error(os_error_text(slave_path_, "open", err));
  }
  // Raw before any client opens it: an echoing terminal would send every frame back.
  ::cfmakeraw(&tio);
  ::tcsetattr(slave_, TCSANOW, &tio);
}

PseudoTerminal::~PseudoTerminal() {
  if (slave_ >= 0) ::close(slave_);
  if (master_ >= 0) ::close(master_);
}

IoResult PseudoTerminal::read(std::span<std::uint8_t> buffer, std::chrono::milliseconds timeout) {
  return read_fd(master_, buffer, timeout, slave_path_ + " (master)");
}

IoResult PseudoTerminal::write(std::span<const std::uint8_t> bytes,
                               std::chrono::milliseconds timeout) {
  return write_fd(master_, bytes, timeout, slave_path_ + " (master)");
}

}  // namespace calstand::drivers
