#include <fmt/format.h>

#include "core/error.hpp"
#include "core/schemas.hpp"
#include "drivers/acutrol_table.hpp"

namespace calstand::drivers {

AcutrolConnection AcutrolConnection::from_json(const nlohmann::json& j) {
  // The schema checks every field (types, ranges, which fields each transport takes); what is
  // left is reading them, with the documented defaults.
  core::validate_part_or_throw(core::schema_definition("station.schema.json", "acutrol_connection"),
                               j, "", "table.connection");
  AcutrolConnection c;
  c.response_timeout = std::chrono::milliseconds(j.value("timeout_ms", 500));
  static_cast<LineLink&>(c) = LineLink::from_json(j, 115200);
  return c;
}

}  // namespace calstand::drivers
