#include "drivers/modbus_chamber_options.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/error.hpp"

namespace calstand::drivers {
namespace {

using nlohmann::json;

const std::string kWhere = "chamber.connection";

std::string at(std::string_view field) { return kWhere + "." + std::string(field); }

int integer_in(const json& j, std::string_view field, int lo, int hi) {
  if (!j.is_number_integer() || j.get<std::int64_t>() < lo || j.get<std::int64_t>() > hi) {
    throw core::InputError(at(field),
                           fmt::format("must be an integer in [{}, {}], got {}", lo, hi, j.dump()));
  }
  return static_cast<int>(j.get<std::int64_t>());
}

std::string text(const json& j, std::string_view field) {
  if (!j.is_string() || j.get<std::string>().empty()) {
    throw core::InputError(at(field), "must be a non-empty string, got " + j.dump());
  }
  return j.get<std::string>();
}

Parity parity_from_json(const json& j) {
  if (j == "none") return Parity::kNone;
  if (j == "even") return Parity::kEven;
  if (j == "odd") return Parity::kOdd;
  throw core::InputError(at("parity"), "must be \"none\", \"even\" or \"odd\", got " + j.dump());
}

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
  if (!c.is_object()) throw core::InputError(kWhere, "must be an object");
  const std::initializer_list<std::string_view> known = {
      "transport", "host", "port",       "path",       "baud",           "parity",
      "unit_id",   "map",  "word_order", "timeout_ms", "poll_period_ms", "stale_after_s"};
  for (const auto& [key, value] : c.items()) {
    bool found = false;
    for (auto k : known) found = found || key == k;
    if (!found) throw core::InputError(at(key), "unknown field");
  }

  if (!c.contains("transport")) throw core::InputError(at("transport"), "is required (tcp or rtu)");
  const auto& transport = c.at("transport");
  if (transport == "tcp") {
    o.transport = ModbusTransport::kTcp;
    if (c.contains("path") || c.contains("baud") || c.contains("parity")) {
      throw core::InputError(kWhere, "path/baud/parity belong to transport \"rtu\", not \"tcp\"");
    }
    if (!c.contains("host")) throw core::InputError(at("host"), "is required for tcp");
    o.host = text(c.at("host"), "host");
    if (c.contains("port")) o.port = integer_in(c.at("port"), "port", 1, 65535);
  } else if (transport == "rtu") {
    o.transport = ModbusTransport::kRtu;
    if (c.contains("host") || c.contains("port")) {
      throw core::InputError(kWhere, "host/port belong to transport \"tcp\", not \"rtu\"");
    }
    if (!c.contains("path")) throw core::InputError(at("path"), "is required for rtu");
    o.serial.path = text(c.at("path"), "path");
    if (c.contains("baud")) o.serial.baud_rate = integer_in(c.at("baud"), "baud", 1, 4000000);
    if (c.contains("parity")) o.serial.parity = parity_from_json(c.at("parity"));
    try {
      o.serial.validate();
    } catch (const core::InputError& e) {
      // SerialOptions names its own fields; say where they came from in the station file.
      const std::string why = e.what();
      const auto field = e.where() == "serial.path" ? "path" : "baud";
      throw core::InputError(at(field), why.substr(std::min(why.size(), e.where().size() + 2)));
    }
  } else {
    throw core::InputError(at("transport"), "must be \"tcp\" or \"rtu\", got " + transport.dump());
  }

  // TCP gateways may use any unit id; on a serial line 0 is broadcast (no reply) and 248+ are
  // reserved.
  if (c.contains("unit_id")) {
    o.unit_id = o.transport == ModbusTransport::kTcp
                    ? integer_in(c.at("unit_id"), "unit_id", 0, 255)
                    : integer_in(c.at("unit_id"), "unit_id", 1, 247);
  }
  auto order = WordOrder::kHighFirst;
  if (c.contains("word_order")) order = word_order_from_json(c.at("word_order"), at("word_order"));
  if (!c.contains("map")) {
    throw core::InputError(at("map"),
                           "is required (\"watlow-f4\", \"watlow-f4t\" or a map object)");
  }
  o.map = register_map_from_json(c.at("map"), at("map"), order);

  if (c.contains("timeout_ms"))
    o.timeout_ms = integer_in(c.at("timeout_ms"), "timeout_ms", 1, 60000);
  if (c.contains("poll_period_ms")) {
    o.poll_period_ms = integer_in(c.at("poll_period_ms"), "poll_period_ms", 1, 60000);
  }
  if (c.contains("stale_after_s")) {
    const auto& s = c.at("stale_after_s");
    if (!s.is_number() || !(s.get<double>() > 0.0) || !std::isfinite(s.get<double>())) {
      throw core::InputError(at("stale_after_s"),
                             "must be a positive number of seconds, got " + s.dump());
    }
    o.stale_after_s = s.get<double>();
  }
  return o;
}

}  // namespace calstand::drivers
