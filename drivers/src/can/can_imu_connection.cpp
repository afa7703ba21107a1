#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <filesystem>

#include "core/error.hpp"
#include "drivers/can_imu.hpp"

namespace calstand::drivers {
namespace {

using nlohmann::json;

bool get_bool(const json& c, const char* key, bool fallback, const std::string& where) {
  if (!c.contains(key)) return fallback;
  if (!c.at(key).is_boolean()) {
    throw core::InputError(where + "." + key, "must be true or false, not " + c.at(key).dump());
  }
  return c.at(key).get<bool>();
}

}  // namespace

CanImuConnection CanImuConnection::from_json(const json& c, const std::string& where,
                                             const std::string& base_dir) {
  if (!c.is_object()) throw core::InputError(where, "must be an object");
  static constexpr std::array kKeys = {
      "interface",        "map",        "map_file",          "sample_rate_hz",
      "sequence_modulus", "filter_ids", "kernel_timestamps", "description"};
  for (const auto& [key, value] : c.items()) {
    if (std::find(kKeys.begin(), kKeys.end(), key) == kKeys.end()) {
      throw core::InputError(where + "." + key,
                             "unknown key (expected interface, map or map_file, sample_rate_hz, "
                             "sequence_modulus, filter_ids, kernel_timestamps)");
    }
  }
  CanImuConnection out;
  if (!c.contains("interface") || !c.at("interface").is_string() ||
      c.at("interface").get<std::string>().empty()) {
    throw core::InputError(where + ".interface",
                           "is required: the SocketCAN interface, e.g. \"can0\"");
  }
  out.interface = c.at("interface").get<std::string>();

  const bool inline_map = c.contains("map");
  const bool file_map = c.contains("map_file");
  if (inline_map == file_map) {
    throw core::InputError(where + ".map", inline_map ? "give map or map_file, not both"
                                                      : "is required (or map_file): which CAN id "
                                                        "carries which signal");
  }
  if (inline_map) {
    out.map = CanSignalMap::from_json(c.at("map"), where + ".map");
  } else {
    if (!c.at("map_file").is_string() || c.at("map_file").get<std::string>().empty()) {
      throw core::InputError(where + ".map_file", "must be a file path");
    }
    std::filesystem::path path = c.at("map_file").get<std::string>();
    if (path.is_relative() && !base_dir.empty()) path = std::filesystem::path(base_dir) / path;
    out.map = CanSignalMap::load(path.string(), where + ".map_file");
  }

  const json rate = c.value("sample_rate_hz", json());
  if (!rate.is_number() || !(rate.get<double>() > 0.0 && rate.get<double>() <= 100000.0)) {
    throw core::InputError(where + ".sample_rate_hz",
                           "is required: the IMU's output rate in Hz (0 < rate <= 100000)");
  }
  out.sample_rate_hz = rate.get<double>();

  const std::uint64_t wrap = out.map.sequence_wrap();
  out.sequence_modulus = wrap;
  if (c.contains("sequence_modulus")) {
    const json& m = c.at("sequence_modulus");
    const bool whole =
        m.is_number_integer() && (m.is_number_unsigned() || m.get<std::int64_t>() >= 0);
    if (!whole || m.get<std::uint64_t>() < 2 || m.get<std::uint64_t>() > wrap) {
      throw core::InputError(where + ".sequence_modulus",
                             fmt::format("must be a whole number in [2, {}] (the map's {}-bit "
                                         "sequence field wraps at {}), not {}",
                                         wrap, out.map.sequence.length_bits, wrap, m.dump()));
    }
    out.sequence_modulus = m.get<std::uint64_t>();
  }
  out.filter_ids = get_bool(c, "filter_ids", true, where);
  out.kernel_timestamps = get_bool(c, "kernel_timestamps", true, where);
  return out;
}

}  // namespace calstand::drivers
