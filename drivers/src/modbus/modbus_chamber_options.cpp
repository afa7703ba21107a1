#include "drivers/modbus_chamber_options.hpp"

#include <fmt/format.h>

#include <cmath>

#include "core/error.hpp"
#include "core/schemas.hpp"

namespace calstand::drivers {
namespace {

using nlohmann::json;

const std::string kWhere = "chamber.connection";

}  // namespace

std::string ModbusChamberOptions::link_name() const {
  if (transport == ModbusTransport::kTcp) return fmt::format("tcp {}:{}", host, port);
  return "rtu " + serial.path;
}

ModbusChamberOptions ModbusChamberOptions::from_config(const core::ChamberConfig& config) {
  ModbusChamberOptions o;
  o.min_c = config.min_c;
  o.max_c = config.max_c;
  o.max_ramp_c_per_min = config.max_ramp_c_per_min;
  o.ambient_c = config.ambient_c;
  if (!(std::isfinite(o.min_c) && std::isfinite(o.max_c) && o.min_c < o.max_c)) {
    throw core::InputError("chamber.max_c", "must be above chamber.min_c");
  }
  if (!(std::isfinite(o.max_ramp_c_per_min) && o.max_ramp_c_per_min > 0.0)) {
    throw core::InputError("chamber.max_ramp_c_per_min", "must be positive");
  }

  const json& c = config.connection;
  // The schema checks every field (types, ranges, which fields each transport takes, the unit
  // id range of each); what is left is reading them, with the documented defaults.
  core::validate_part_or_throw(core::schema_definition("station.schema.json", "modbus_connection"),
                               c, "", kWhere);
  if (c.at("transport") == "tcp") {
    o.transport = ModbusTransport::kTcp;
    o.host = c.at("host").get<std::string>();
    o.port = c.value("port", o.port);
  } else {
    o.transport = ModbusTransport::kRtu;
    o.serial.path = c.at("path").get<std::string>();
    o.serial.baud_rate = c.value("baud", o.serial.baud_rate);
    o.serial.parity = parity_from_name(c.value("parity", "none"), kWhere + ".parity");
  }
  o.unit_id = c.value("unit_id", o.unit_id);
  const auto order = c.contains("word_order")
                         ? word_order_from_json(c.at("word_order"), kWhere + ".word_order")
                         : WordOrder::kHighFirst;
  o.map = register_map_from_json(c.at("map"), kWhere + ".map", order);
  o.timeout_ms = c.value("timeout_ms", o.timeout_ms);
  o.poll_period_ms = c.value("poll_period_ms", o.poll_period_ms);
  o.stale_after_s = c.value("stale_after_s", o.stale_after_s);
  return o;
}

}  // namespace calstand::drivers
