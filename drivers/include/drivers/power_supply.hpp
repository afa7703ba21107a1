#pragma once

#include <string>

#include "drivers/device.hpp"

namespace calstand::drivers {

/// What a supply reports in one reading.
struct PowerReading {
  bool ok = false;         ///< false: unreadable (why in `message`); the values are the last good
  bool output_on = false;  ///< the output as last commanded and confirmed
  double voltage_v = 0.0;  ///< measured at the output [V]
  double current_a = 0.0;  ///< measured at the output [A]
  double time_s = 0.0;     ///< station clock when read [s]
  std::string message;     ///< why not ok
};

/// A programmable power supply feeding one IMU (station file `power_supplies[]`). configure()
/// opens the link and sets the voltage and current limit from the station file; it never
/// switches the output, so bringing a station up does not power-cycle its units.
class PowerSupply : public Device {
 public:
  /// The name of the IMU this supply feeds (imus[].name).
  virtual const std::string& imu_name() const = 0;
  /// Switches the output on or off; the supply confirms it (no error reported) or the call
  /// fails saying why.
  virtual Result set_output(bool on) = 0;
  /// Output voltage setpoint [V].
  virtual Result set_voltage(double volts) = 0;
  /// Current limit [A].
  virtual Result set_current_limit(double amps) = 0;
  /// Measured voltage and current, and the output state. Never throws.
  virtual PowerReading read() = 0;
  /// The station file's safe state: "off" switches the output off, "on" leaves it as it is.
  /// Allowed in every lifecycle state (best effort on a broken link).
  virtual Result make_safe() = 0;
};

}  // namespace calstand::drivers
