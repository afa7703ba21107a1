#pragma once

#include <optional>

#include "core/chamber_state.hpp"
#include "drivers/device.hpp"

namespace calstand::drivers {

/// A temperature chamber. Temperatures in degC, ramps in degC/min.
class Chamber : public Device {
 public:
  /// Controls the air to `target_c`, ramping at `ramp_c_per_min` (default: the chamber's).
  virtual Result set_temperature(double target_c, std::optional<double> ramp_c_per_min) = 0;
  /// Stops controlling (the air drifts to ambient): the safe state.
  virtual Result standby() = 0;
  virtual core::ChamberState read_state() = 0;
};

}  // namespace calstand::drivers
