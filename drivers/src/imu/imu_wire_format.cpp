#include "drivers/imu_wire_format.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include "core/error.hpp"

namespace calstand::drivers {

std::vector<std::string> imu_wire_format_names() {
  return {"calstand", "xsens", "vectornav", "epson", "stim300"};
}

const ImuWireFormat& imu_wire_format(const std::string& name, const std::string& where) {
  if (name == "calstand") return calstand_wire_format();
  if (name == "xsens") return xsens_wire_format();
  if (name == "vectornav") return vectornav_wire_format();
  if (name == "epson") return epson_wire_format();
  if (name == "stim300") return stim300_wire_format();
  throw core::InputError(where, fmt::format("unknown wire format \"{}\" (known: {})", name,
                                            fmt::join(imu_wire_format_names(), ", ")));
}

}  // namespace calstand::drivers
