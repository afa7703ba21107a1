#include "drivers/device.hpp"

namespace calstand::drivers {

std::string_view to_string(DeviceState state) {
  switch (state) {
    case DeviceState::kUnconfigured:
      return "unconfigured";
    case DeviceState::kInactive:
      return "inactive";
    case DeviceState::kActive:
      return "active";
    case DeviceState::kError:
      return "error";
  }
  return "unknown";
}

}  // namespace calstand::drivers
