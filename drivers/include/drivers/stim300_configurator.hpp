#pragma once

// The host's half of the STIM300 dialogue (docs/protocols.md, "Sensonor STIM300").

#include <chrono>

#include "drivers/imu_wire_format.hpp"
#include "drivers/stim300_options.hpp"

namespace calstand::drivers::stim300 {

/// Reads the part number (N), serial number (I) and configuration (C) datagrams while the unit
/// streams, then watches the stream for a moment and checks that the unit streams what the
/// station file asks: the sample rate (measured from the counter against the host clock), and
/// the datagram identifier and CR LF termination where the options name them. The STIM300
/// stores its configuration in its service mode, which calstand does not drive: a unit set up
/// otherwise is refused with what it streams.
class Stim300Configurator final : public ImuConfigurator {
 public:
  /// `observe`: how long the stream is watched after the dialogue.
  Stim300Configurator(WireFormatSettings settings, Stim300Options options,
                      std::chrono::milliseconds observe = std::chrono::milliseconds(500));
  UnitIdentity configure(ByteTransport& link) override;

 private:
  WireFormatSettings settings_;
  Stim300Options options_;
  std::chrono::milliseconds observe_;
};

}  // namespace calstand::drivers::stim300
