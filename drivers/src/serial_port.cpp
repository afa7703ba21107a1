#include "drivers/serial_port.hpp"

#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <utility>

#include "core/error.hpp"

namespace calstand::drivers {
namespace {

struct BaudCode {
  int rate_bps;
  speed_t code;
};

// termios wants symbolic speeds; only these are offered on every Linux serial driver.
constexpr std::array kBaudCodes{
    BaudCode{9600, B9600},     BaudCode{19200, B19200},   BaudCode{38400, B38400},
    BaudCode{57600, B57600},   BaudCode{115200, B115200}, BaudCode{230400, B230400},
    BaudCode{460800, B460800}, BaudCode{921600, B921600},
};

std::optional<speed_t> baud_code(int rate_bps) {
  for (const auto& b : kBaudCodes) {
    if (b.rate_bps == rate_bps) return b.code;
  }
  return std::nullopt;
}

/// Milliseconds left until `deadline`, clamped to [0, INT_MAX] for poll().
int remaining_ms(std::chrono::steady_clock::time_point deadline) {
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
      deadline - std::chrono::steady_clock::now());
  if (left.count() <= 0) return 0;
  return left.count() > 0x7FFFFFFF ? 0x7FFFFFFF : static_cast<int>(left.count());
}

}  // namespace

void SerialOptions::validate() const {
  if (path.empty()) throw core::InputError("serial.path", "must name a device, e.g. /dev/ttyUSB0");
  if (!baud_code(baud_rate)) {
    std::string rates;
    for (const auto& b : kBaudCodes) {
      rates += (rates.empty() ? "" : ", ") + std::to_string(b.rate_bps);
    }
    throw core::InputError(
        "serial.baud_rate",
        std::to_string(baud_rate) + " bit/s is not supported (one of " + rates + ")");
  }
}

SerialPort::SerialPort(SerialOptions options) : options_(std::move(options)) {}

SerialPort::~SerialPort() { close(); }

std::string SerialPort::os_error(const char* what, int err) const {
  return options_.path + ": " + what + ": " + std::strerror(err);
}

void SerialPort::open() {
  options_.validate();
  close();
  // O_NOCTTY: a serial IMU must never become our controlling terminal (a hang-up would signal
  // us). O_NONBLOCK: open must not wait for carrier detect; reads wait in poll() instead.
  const int fd = ::open(options_.path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) throw std::runtime_error(os_error("cannot open serial port", errno));

  termios tio{};
  if (::tcgetattr(fd, &tio) != 0) {
    const int err = errno;
    ::close(fd);
    throw std::runtime_error(os_error("not a terminal device (tcgetattr)", err));
  }
  ::cfmakeraw(&tio);
  tio.c_cflag |= CLOCAL | CREAD;  // ignore modem lines; enable the receiver
  tio.c_cflag &= ~static_cast<tcflag_t>(CSTOPB | CRTSCTS | PARENB | PARODD);
  if (options_.parity != Parity::kNone) {
    tio.c_cflag |= PARENB;
    if (options_.parity == Parity::kOdd) tio.c_cflag |= PARODD;
    // Drop bytes with a parity error rather than pass them on: the frame CRC then sees a
    // short frame and the decoder resynchronises, which it does anyway.
    tio.c_iflag |= INPCK | IGNPAR;
  }
  tio.c_iflag &= ~static_cast<tcflag_t>(IXON | IXOFF | IXANY);  // 0x11/0x13 are data, not flow
  tio.c_cc[VMIN] = 0;  // poll() does the waiting, so read() never blocks
  tio.c_cc[VTIME] = 0;
  const speed_t speed = *baud_code(options_.baud_rate);
  if (::cfsetispeed(&tio, speed) != 0 || ::cfsetospeed(&tio, speed) != 0 ||
      ::tcsetattr(fd, TCSANOW, &tio) != 0) {
    const int err = errno;
    ::close(fd);
    throw std::runtime_error(os_error("cannot configure serial port (tcsetattr)", err));
  }
  // Bytes that arrived before we configured the line were read with the wrong settings.
  ::tcflush(fd, TCIFLUSH);
  fd_ = fd;
}

void SerialPort::close() noexcept {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

IoResult SerialPort::read(std::span<std::uint8_t> buffer, std::chrono::milliseconds timeout) {
  if (fd_ < 0) return {0, options_.path + ": serial port is not open"};
  if (buffer.empty()) return {};
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    pollfd pfd{fd_, POLLIN, 0};
    const int ready = ::poll(&pfd, 1, remaining_ms(deadline));
    if (ready < 0) {
      if (errno == EINTR) continue;  // a signal is not a timeout: wait out the rest
      return {0, os_error("poll", errno)};
    }
    if (ready == 0) return {};  // timeout, no data
    const ssize_t n = ::read(fd_, buffer.data(), buffer.size());
    if (n > 0) return {static_cast<std::size_t>(n), {}};
    if (n < 0 && (errno == EINTR || errno == EAGAIN)) continue;
    if (n < 0) return {0, os_error("read", errno)};
    // poll said readable but there is nothing: the other end hung up.
    return {0, options_.path + ": read: end of stream (device gone)"};
  }
}

IoResult SerialPort::write(std::span<const std::uint8_t> bytes, std::chrono::milliseconds timeout) {
  if (fd_ < 0) return {0, options_.path + ": serial port is not open"};
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  std::size_t sent = 0;
  while (sent < bytes.size()) {
    const ssize_t n = ::write(fd_, bytes.data() + sent, bytes.size() - sent);
    if (n > 0) {
      sent += static_cast<std::size_t>(n);
      continue;
    }
    if (n < 0 && errno != EAGAIN && errno != EINTR) return {sent, os_error("write", errno)};
    pollfd pfd{fd_, POLLOUT, 0};
    const int ready = ::poll(&pfd, 1, remaining_ms(deadline));
    if (ready < 0 && errno != EINTR) return {sent, os_error("poll", errno)};
    if (ready == 0) return {sent, options_.path + ": write timed out"};
  }
  return {sent, {}};
}

}  // namespace calstand::drivers
