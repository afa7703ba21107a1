#include "drivers/serial_port.hpp"

#include <fcntl.h>
#include <poll.h>
#include <sys/file.h>
#include <termios.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <utility>

#include "core/error.hpp"
#include "drivers/fd_io.hpp"

namespace calstand::drivers {
namespace {

struct BaudCode {
  int rate_bps;
  speed_t code;
};

// termios wants symbolic speeds. Up to 921600 every Linux serial driver offers them; the
// megabaud rates are Linux's own (an MTi at 2 kHz, a STIM300 or an Epson at 2 kHz need more
// than 921600 bit/s) and the USB adapters these units ship with (FTDI) take them.
constexpr std::array kBaudCodes{
    BaudCode{9600, B9600},       BaudCode{19200, B19200},     BaudCode{38400, B38400},
    BaudCode{57600, B57600},     BaudCode{115200, B115200},   BaudCode{230400, B230400},
    BaudCode{460800, B460800},   BaudCode{921600, B921600},   BaudCode{1000000, B1000000},
    BaudCode{1500000, B1500000}, BaudCode{2000000, B2000000}, BaudCode{3000000, B3000000},
    BaudCode{4000000, B4000000},
};

std::optional<speed_t> baud_code(int rate_bps) {
  for (const auto& b : kBaudCodes) {
    if (b.rate_bps == rate_bps) return b.code;
  }
  return std::nullopt;
}

}  // namespace

Parity parity_from_name(const std::string& name, const std::string& where) {
  if (name == "none") return Parity::kNone;
  if (name == "even") return Parity::kEven;
  if (name == "odd") return Parity::kOdd;
  throw core::InputError(where, "\"" + name + "\" is not none, even or odd");
}

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
  return os_error_text(options_.path, what, err);
}

void SerialPort::open() {
  options_.validate();
  close();
  // O_NOCTTY: a serial IMU must never become our controlling terminal (a hang-up would signal
  // us). O_NONBLOCK: open must not wait for carrier detect; reads wait in poll() instead.
  const int fd = ::open(options_.path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) throw std::runtime_error(os_error("cannot open serial port", errno));
  // One reader per line: two processes reading one IMU would split its bytes between them
  // (a run and `calstand device imu stream` at once). An advisory lock, held while open.
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    ::close(fd);
    throw std::runtime_error(err == EWOULDBLOCK
                                 ? options_.path + ": in use by another process (locked)"
                                 : os_error("cannot lock serial port", err));
  }

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

void SerialPort::discard_input() noexcept {
  if (fd_ >= 0) ::tcflush(fd_, TCIFLUSH);
}

IoResult SerialPort::read(std::span<std::uint8_t> buffer, std::chrono::milliseconds timeout) {
  if (fd_ < 0) return {0, options_.path + ": serial port is not open"};
  return read_fd(fd_, buffer, timeout, options_.path);
}

IoResult SerialPort::write(std::span<const std::uint8_t> bytes, std::chrono::milliseconds timeout) {
  if (fd_ < 0) return {0, options_.path + ": serial port is not open"};
  return write_fd(fd_, bytes, timeout, options_.path);
}

}  // namespace calstand::drivers
