#include <fmt/format.h>

#include "core/error.hpp"
#include "core/schemas.hpp"
#include "drivers/scpi_power_supply.hpp"

namespace calstand::drivers {

ScpiConnection ScpiConnection::from_json(const nlohmann::json& j, const std::string& where) {
  // The schema checks every field (types, ranges, models); what is left is reading them with
  // the documented defaults.
  core::validate_part_or_throw(core::schema_definition("station.schema.json", "scpi_connection"), j,
                               "", where);
  ScpiConnection c;
  c.response_timeout = std::chrono::milliseconds(j.value("timeout_ms", 1000));
  c.commands = scpi::find_command_set(j.value("model", "generic"));
  if (c.commands == nullptr) {
    throw core::InputError(where + ".model", "no command table for this model");
  }
  if (j.at("transport") == "tcp") {
    c.transport = Transport::kTcp;
    c.tcp.host = j.at("host").get<std::string>();
    c.tcp.port = j.at("port").get<std::uint16_t>();
    c.tcp.connect_timeout = std::chrono::milliseconds(j.value("connect_timeout_ms", 1000));
  } else {
    c.transport = Transport::kSerial;
    c.serial.path = j.at("path").get<std::string>();
    c.serial.baud_rate = j.value("baud", 9600);
    c.serial.parity = parity_from_name(j.value("parity", "none"));
  }
  return c;
}

std::string ScpiConnection::describe() const {
  if (transport == Transport::kTcp) return fmt::format("tcp {}:{}", tcp.host, tcp.port);
  return "serial " + serial.path;
}

}  // namespace calstand::drivers
