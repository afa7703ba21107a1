#pragma once

#include <chrono>
#include <cstdint>
#include <span>
#include <string>

#include "drivers/serial_port.hpp"

namespace calstand::drivers {

/// A pseudo-terminal that plays the device end of a serial line: the simulator (or a test)
/// reads and writes the master; the code under test opens slave_path() as it would open
/// /dev/ttyUSB0. The slave is set to raw mode at creation and one descriptor of it is held open
/// for the terminal's lifetime, so bytes pass unchanged (no echo) and the master never sees EIO
/// while no client has the slave open. Closes both on destruction.
class PseudoTerminal final : public ByteTransport {
 public:
  /// Throws std::runtime_error with the OS error when no pseudo-terminal can be made.
  PseudoTerminal();
  ~PseudoTerminal() override;
  PseudoTerminal(const PseudoTerminal&) = delete;
  PseudoTerminal& operator=(const PseudoTerminal&) = delete;

  const std::string& slave_path() const { return slave_path_; }
  int master_fd() const { return master_; }

  /// Reads what the client wrote on the slave (master side).
  IoResult read(std::span<std::uint8_t> buffer, std::chrono::milliseconds timeout) override;
  /// Writes towards the client. The terminal's input queue is small (4 KiB); when nobody reads
  /// the slave, the write times out with the bytes that fit.
  IoResult write(std::span<const std::uint8_t> bytes, std::chrono::milliseconds timeout) override;

 private:
  int master_ = -1;
  int slave_ = -1;
  std::string slave_path_;
};

}  // namespace calstand::drivers
