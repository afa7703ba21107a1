#include "core/chamber_state.hpp"
#include "core/table_state.hpp"

namespace calstand::core {

std::string_view to_string(AxisMode mode) {
  switch (mode) {
    case AxisMode::kRest:
      return "rest";
    case AxisMode::kPosition:
      return "position";
    case AxisMode::kRate:
      return "rate";
    case AxisMode::kSine:
      return "sine";
    case AxisMode::kFault:
      return "fault";
  }
  return "unknown";
}

std::string_view to_string(ChamberMode mode) {
  switch (mode) {
    case ChamberMode::kStandby:
      return "standby";
    case ChamberMode::kActive:
      return "active";
    case ChamberMode::kFault:
      return "fault";
  }
  return "unknown";
}

}  // namespace calstand::core
