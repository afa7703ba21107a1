#include <fmt/format.h>

#include <filesystem>

#include "core/error.hpp"
#include "core/schemas.hpp"
#include "drivers/can_imu.hpp"

namespace calstand::drivers {

using nlohmann::json;

CanImuConnection CanImuConnection::from_json(const json& c, const std::string& where,
                                             const std::string& base_dir) {
  // The schema checks every field; what is left is reading them and the rules between fields.
  core::validate_part_or_throw(
      core::schema_definition("station.schema.json", "socketcan_connection"), c, "", where);
  CanImuConnection out;
  out.interface = c.at("interface").get<std::string>();

  const bool inline_map = c.contains("map");
  const bool file_map = c.contains("map_file");
  const bool dbc = c.contains("dbc");
  // A schema can require exactly one of the keys only as "matches none of the forms"; this
  // names them.
  if (int{inline_map} + int{file_map} + int{dbc} != 1) {
    throw core::InputError(where + ".map",
                           inline_map || file_map || dbc
                               ? "give one of map, map_file and dbc, not several"
                               : "is required (or map_file, or dbc with signals): which CAN id "
                                 "carries which signal");
  }
  if (dbc != c.contains("signals")) {
    throw core::InputError(where + (dbc ? ".signals" : ".dbc"),
                           dbc ? "is required with dbc: the DBC message and signal of each value"
                               : "is required with signals: the DBC file they name");
  }
  for (const char* key : {"sample_start", "status", "message_counters"}) {
    if (!dbc && c.contains(key))
      throw core::InputError(where + "." + key, "is only for a dbc layout");
  }
  auto resolved = [&](const std::string& key) {
    std::filesystem::path path = c.at(key).get<std::string>();
    if (path.is_relative() && !base_dir.empty()) path = std::filesystem::path(base_dir) / path;
    return path.string();
  };
  if (inline_map) {
    out.map = CanSignalMap::from_json(c.at("map"), where + ".map");
  } else if (file_map) {
    out.map = CanSignalMap::load(resolved("map_file"), where + ".map_file");
  } else {
    out.map = CanSignalMap::from_dbc(resolved("dbc"), c, where);
  }
  out.sample_rate_hz = c.at("sample_rate_hz").get<double>();

  // The limit depends on the map's sequence field, so the schema cannot state it.
  const std::uint64_t wrap = out.map.sequence_wrap();
  out.sequence_modulus = c.value("sequence_modulus", wrap);
  if (out.sequence_modulus > wrap) {
    throw core::InputError(
        where + ".sequence_modulus",
        fmt::format("must be a whole number in [2, {}] (the map's {}-bit "
                    "sequence field wraps at {}), not {}",
                    wrap, out.map.sequence.length_bits, wrap, out.sequence_modulus));
  }
  out.filter_ids = c.value("filter_ids", true);
  out.kernel_timestamps = c.value("kernel_timestamps", true);
  return out;
}

}  // namespace calstand::drivers
