#include "drivers/command_set_backends.hpp"

#include <array>

namespace calstand::drivers::line {
namespace {

// Backends that stand for a built-in set of the same name.
constexpr std::array<std::string_view, 6> kNamedBackends{"espec",     "simserv", "thermotron",
                                                         "aerosmith", "actidyn", "aerotech"};

template <class Config>
std::optional<CommandSet> command_set_of(const Config& config, DeviceKind device,
                                         const char* where) {
  if (!config.command_set.empty()) {
    return load_command_set(config.command_set, "", device, std::string(where) + ".command_set");
  }
  if (const auto name = builtin_set_of_backend(config.backend)) {
    return load_command_set(*name, "", device, std::string(where) + ".backend");
  }
  return std::nullopt;
}

}  // namespace

std::optional<std::string> builtin_set_of_backend(std::string_view backend) {
  for (const auto named : kNamedBackends) {
    if (named == backend) return std::string(named);
  }
  return std::nullopt;
}

std::optional<CommandSet> station_command_set(const core::TableConfig& table) {
  return command_set_of(table, DeviceKind::kTable, "table");
}

std::optional<CommandSet> station_command_set(const core::ChamberConfig& chamber) {
  return command_set_of(chamber, DeviceKind::kChamber, "chamber");
}

StationNaming station_naming(const std::string& set_name, DeviceKind device) {
  if (builtin_set_of_backend(set_name)) return {set_name, ""};
  // The ACUTROL3000's short headers are the acutrol backend's other dialect.
  if (device == DeviceKind::kTable && set_name.rfind("acutrol", 0) == 0) {
    return {"acutrol", set_name};
  }
  return {"line", set_name};
}

}  // namespace calstand::drivers::line
