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
  static_cast<LineLink&>(c) = LineLink::from_json(j, 9600);
  return c;
}

}  // namespace calstand::drivers
