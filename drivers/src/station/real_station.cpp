#include "drivers/real_station.hpp"

#include <fmt/format.h>

#include "core/error.hpp"
#include "drivers/acutrol_table.hpp"
#include "drivers/command_set_backends.hpp"
#include "drivers/line_chamber.hpp"
#include "drivers/line_table.hpp"
#if CALSTAND_WITH_SOCKETCAN
#include "drivers/can_imu.hpp"
#endif
#include "drivers/modbus_chamber.hpp"
#include "drivers/scpi_power_supply.hpp"
#include "drivers/serial_imu.hpp"

namespace calstand::drivers {
namespace {

[[noreturn]] void unknown_backend(const std::string& field, const std::string& backend,
                                  const char* known) {
  throw core::InputError(
      field, fmt::format("no driver for backend \"{}\" (real backends: {})", backend, known));
}

}  // namespace

RealStation::RealStation(const core::StationConfig& config, double start_time_s)
    : config_(config), clock_(config.time_scale, start_time_s) {
  // A command set (the backend's built-in, or the station file's command_set) drives the
  // device when there is one; otherwise its own driver.
  if (auto set = line::station_command_set(config_.table)) {
    table_ = make_line_table(config_.table, clock_, *set);
  } else if (config_.table.backend == "acutrol") {
    table_ = make_acutrol_table(config_.table, clock_);
  } else {
    unknown_backend("table.backend", config_.table.backend,
                    "acutrol, aerosmith, actidyn, aerotech, line");
  }
  if (auto set = line::station_command_set(config_.chamber)) {
    chamber_ = line::make_line_chamber(config_.chamber, clock_, *set);
  } else if (config_.chamber.backend == "modbus") {
    chamber_ = make_modbus_chamber(config_.chamber, clock_);
  } else {
    unknown_backend("chamber.backend", config_.chamber.backend,
                    "modbus, espec, simserv, thermotron, line");
  }
  for (std::size_t i = 0; i < config_.imus.size(); ++i) {
    const auto& imu = config_.imus[i];
    const std::string where = fmt::format("imus[{}].connection", i);
    if (imu.backend == "serial") {
      imus_.push_back(make_serial_imu(imu, clock_, where));
    } else if (imu.backend == "socketcan") {
#if CALSTAND_WITH_SOCKETCAN
      imus_.push_back(make_can_imu(imu, clock_, where));
#else
      throw core::InputError(fmt::format("imus[{}].backend", i),
                             "this calstand was built without SocketCAN "
                             "(-DCALSTAND_WITH_SOCKETCAN=OFF)");
#endif
    } else {
      unknown_backend(fmt::format("imus[{}].backend", i), imu.backend, "serial, socketcan");
    }
  }
  for (std::size_t i = 0; i < config_.power_supplies.size(); ++i) {
    const auto& p = config_.power_supplies[i];
    if (p.backend != "scpi") {
      unknown_backend(fmt::format("power_supplies[{}].backend", i), p.backend, "scpi");
    }
    supplies_.push_back(
        make_scpi_power_supply(p, clock_, fmt::format("power_supplies[{}].connection", i)));
  }
}

RealStation::~RealStation() {
  // The readers stop before the links close; the station is left as the engine left it
  // (make_safe() is the engine's job, not the destructor's).
  for (auto& imu : imus_) imu->deactivate();
}

}  // namespace calstand::drivers
