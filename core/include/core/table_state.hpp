#pragma once

#include <string>
#include <string_view>

namespace calstand::core {

/// Control mode of one table axis.
enum class AxisMode {
  kRest,      ///< servo holding, no command (power-up and safe state)
  kPosition,  ///< moving to or holding a commanded angle
  kRate,      ///< turning at a commanded rate
  kSine,      ///< oscillating: angle = start + amplitude sin(2 pi f t) about its start angle
  kFault,     ///< stopped by a fault; commands are refused until the fault is cleared
};

std::string_view to_string(AxisMode mode);

/// State of one axis as the controller reports it.
struct AxisState {
  double angle_deg = 0.0;  ///< encoder reading, wrapped to [-180, 180) [deg]
  double rate_dps = 0.0;   ///< angular rate about the axis, right-handed [deg/s]
  AxisMode mode = AxisMode::kRest;
  /// position mode: settled within tolerance; rate mode: rate settled; sine mode: the sine has
  /// run for the settle time
  bool in_position = true;
  bool fault = false;
  std::string fault_text;  ///< why the axis faulted (empty when fault is false)
};

/// State of the dual-axis table at one instant.
struct TableState {
  double time_s = 0.0;  ///< station clock [s]
  AxisState outer;
  AxisState inner;
  /// The controller could not be read (link down, timeouts, unreadable replies): the fields
  /// are the last known, and both axes carry `fault` with the reason. The engine rides such an
  /// outage out for the policy's link_outage_s instead of aborting at once.
  bool link_lost = false;
};

}  // namespace calstand::core
