#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

namespace calstand::drivers {

/// Outcome of one transport call. The cyclic path returns this rather than throwing: a timeout
/// is ok with zero bytes; a lost link is an error saying why (device path and errno text).
struct IoResult {
  std::size_t bytes = 0;  ///< bytes transferred [bytes]
  std::string error;      ///< empty when ok

  bool ok() const { return error.empty(); }
};

/// A byte stream to a device (serial line, TCP socket, or a test double). Drivers speak their
/// protocol over this so that they can be tested without the real link. Not thread safe.
class ByteTransport {
 public:
  virtual ~ByteTransport() = default;
  /// Reads what is available into `buffer`, waiting up to `timeout` for the first byte.
  /// Returns bytes == 0 (ok) on timeout.
  virtual IoResult read(std::span<std::uint8_t> buffer, std::chrono::milliseconds timeout) = 0;
  /// Writes all of `bytes`, waiting up to `timeout` in total for the link to accept them.
  /// A partial write (timeout) is an error reporting the bytes that were sent.
  virtual IoResult write(std::span<const std::uint8_t> bytes,
                         std::chrono::milliseconds timeout) = 0;
};

enum class Parity { kNone, kEven, kOdd };

/// The parity named "none", "even" or "odd" (as station files write it). Throws
/// core::InputError naming `where` for any other name.
Parity parity_from_name(const std::string& name, const std::string& where = "parity");

/// Settings of a serial line: 8 data bits, 1 stop bit, no flow control (what IMUs use).
struct SerialOptions {
  std::string path;        ///< device node, e.g. /dev/ttyUSB0
  int baud_rate = 115200;  ///< [bit/s]; one of the standard rates (see validate())
  Parity parity = Parity::kNone;

  /// Throws core::InputError naming the field (path empty, baud rate not a standard rate).
  void validate() const;
};

/// A POSIX serial port in raw mode (no echo, no line editing, no byte translation: binary frames
/// pass unchanged). The constructor does no I/O; open() does. Closes on destruction.
class SerialPort final : public ByteTransport {
 public:
  explicit SerialPort(SerialOptions options);
  ~SerialPort() override;
  SerialPort(const SerialPort&) = delete;
  SerialPort& operator=(const SerialPort&) = delete;

  /// Opens and configures the line, discarding bytes received before the call. Throws
  /// core::InputError for bad options and std::runtime_error naming the path and the OS error
  /// (errno text) when the device cannot be opened or configured. Reopens if already open.
  void open();
  void close() noexcept;
  /// Drops what the line received and nobody has read yet (tcflush).
  void discard_input() noexcept;
  bool is_open() const { return fd_ >= 0; }
  const SerialOptions& options() const { return options_; }

  IoResult read(std::span<std::uint8_t> buffer, std::chrono::milliseconds timeout) override;
  IoResult write(std::span<const std::uint8_t> bytes, std::chrono::milliseconds timeout) override;

 private:
  std::string os_error(const char* what, int err) const;

  SerialOptions options_;
  int fd_ = -1;
};

}  // namespace calstand::drivers
