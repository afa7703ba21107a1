#pragma once

// The host's half of the STIM300 dialogue (docs/protocols.md, "Sensonor STIM300").

#include "drivers/imu_wire_format.hpp"
#include "drivers/stim300_options.hpp"

namespace calstand::drivers::stim300 {

/// Reads the part number (N), serial number (I) and configuration (C) datagrams while the unit
/// streams, and checks that the unit streams what the station file asks: the sample rate, and
/// the datagram, output units, accelerometer range and termination where the options name
/// them. The STIM300 stores these in its service mode, which calstand does not drive: a unit
/// set up otherwise is refused with what its configuration datagram says.
class Stim300Configurator final : public ImuConfigurator {
 public:
  Stim300Configurator(WireFormatSettings settings, Stim300Options options);
  UnitIdentity configure(ByteTransport& link) override;

 private:
  WireFormatSettings settings_;
  Stim300Options options_;
};

}  // namespace calstand::drivers::stim300
