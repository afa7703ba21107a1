#include "drivers/serial_reopen.hpp"

#include <fmt/format.h>

namespace calstand::drivers {

Result reopen_with_backoff(SerialPort& port, ReconnectBackoff& backoff) {
  if (port.is_open()) return Result::success();
  const auto now = std::chrono::steady_clock::now();
  if (!backoff.may_attempt(now)) {
    return Result::failure(fmt::format("{}: not open (next attempt in {} ms)", port.options().path,
                                       backoff.wait_left(now).count()));
  }
  try {
    port.open();
    backoff.succeeded();
    return Result::success();
  } catch (const std::exception& e) {
    backoff.failed(now);
    return Result::failure(e.what());
  }
}

}  // namespace calstand::drivers
