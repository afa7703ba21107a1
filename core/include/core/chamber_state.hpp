#pragma once

#include <string>
#include <string_view>

namespace calstand::core {

/// Operating mode of the temperature chamber.
enum class ChamberMode {
  kStandby,  ///< controller idle: the air drifts to ambient (safe state)
  kActive,   ///< controlling the air to the setpoint
  kFault,    ///< controller alarm; refuses setpoints until cleared
};

std::string_view to_string(ChamberMode mode);

/// State of the chamber at one instant.
struct ChamberState {
  double time_s = 0.0;             ///< station clock [s]
  double air_temperature_c = 0.0;  ///< process value: chamber air [degC]
  double setpoint_c = 0.0;         ///< active setpoint [degC]
  ChamberMode mode = ChamberMode::kStandby;
  bool fault = false;
  std::string fault_text;
  /// The controller could not be read (link down, no valid reading for too long): the fields
  /// are the last known. Set together with `fault`; the engine rides such an outage out for
  /// the policy's link_outage_s instead of aborting at once.
  bool link_lost = false;
};

}  // namespace calstand::core
