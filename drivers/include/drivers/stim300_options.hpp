#pragma once

// The options of format stim300 (`connection.stim300`, schema `stim300_options`).

#include <cstdint>
#include <optional>

#include "drivers/imu_wire_format.hpp"
#include "drivers/stim300_protocol.hpp"

namespace calstand::drivers::stim300 {

struct Stim300Options {
  /// The normal-mode datagram the station expects; none: accept the one that arrives (the
  /// decoder locks onto the first valid datagram's identifier).
  std::optional<std::uint8_t> datagram;
  int accel_range_g = 10;  ///< the unit's accelerometer range [g]: 5, 10, 30 or 80
  GyroOutput gyro_output = GyroOutput::kAngularRate;
  AccelOutput accel_output = AccelOutput::kAcceleration;
  /// CR LF after each datagram: required (true), absent (false), or either (none).
  std::optional<bool> termination;
  /// Whether configure() measures the streamed rate against the host clock (off for a link that
  /// does not run in real time: a replayed capture, an accelerated simulation).
  bool rate_check = true;
};

/// The options of `settings` (already checked by the schema). Throws core::InputError naming
/// settings.where + ".key" for a value the schema cannot check (an unknown datagram name).
Stim300Options parse_stim300_options(const WireFormatSettings& settings);

}  // namespace calstand::drivers::stim300
