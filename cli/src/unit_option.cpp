#include "unit_option.hpp"

#include "core/error.hpp"

namespace calstand::cli {

daemon::UnitSerials parse_unit_options(const std::vector<std::string>& args) {
  daemon::UnitSerials out;
  for (const std::string& arg : args) {
    const auto eq = arg.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == arg.size()) {
      throw core::InputError("--unit " + arg, "expected NAME=SERIAL, e.g. imu0=SN1234");
    }
    if (!out.emplace(arg.substr(0, eq), arg.substr(eq + 1)).second) {
      throw core::InputError("--unit " + arg, "IMU " + arg.substr(0, eq) + " is given twice");
    }
  }
  return out;
}

}  // namespace calstand::cli
