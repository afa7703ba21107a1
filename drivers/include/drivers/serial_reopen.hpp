#pragma once
// Reopening a serial line that failed, paced by a backoff: the table and the power supply
// drivers (a controller behind a serial line may be power-cycled or unplugged) share it.

#include "drivers/device.hpp"
#include "drivers/serial_port.hpp"
#include "drivers/tcp_client.hpp"

namespace calstand::drivers {

/// Opens `port` unless it is open; an attempt only when `backoff` allows one (otherwise a
/// failure saying when the next may be made), the outcome fed back to it. Never throws: a
/// failure carries the port's own message.
Result reopen_with_backoff(SerialPort& port, ReconnectBackoff& backoff);

}  // namespace calstand::drivers
