#pragma once

#include <chrono>
#include <cstdint>
#include <span>
#include <string>

#include "drivers/serial_port.hpp"

namespace calstand::drivers {

/// poll()-based I/O on a non-blocking file descriptor, shared by every ByteTransport that has
/// one (serial port, pseudo-terminal, TCP socket). `who` names the link in error messages
/// (device path or host:port).

/// Reads what is available, waiting up to `timeout` for the first byte; bytes == 0 (ok) on
/// timeout; an error on end of stream (the other end hung up) or an OS error.
IoResult read_fd(int fd, std::span<std::uint8_t> buffer, std::chrono::milliseconds timeout,
                 const std::string& who);
/// Writes all of `bytes` within `timeout` in total; a partial write is an error.
IoResult write_fd(int fd, std::span<const std::uint8_t> bytes, std::chrono::milliseconds timeout,
                  const std::string& who);
/// Milliseconds left until `deadline` on the steady clock, clamped to [0, INT_MAX]: a timeout
/// for poll() that is never negative (which would wait forever) and never overflows.
int remaining_ms(std::chrono::steady_clock::time_point deadline);
/// "who: what: strerror(err)".
std::string os_error_text(const std::string& who, const char* what, int err);

}  // namespace calstand::drivers
