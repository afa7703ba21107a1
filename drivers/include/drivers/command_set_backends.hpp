#pragma once
// How a station file names a command-set device: a backend that stands for a built-in set
// ("espec", "aerotech"), or "line" (or "acutrol" for the ACUTROL3000's headers) with
// `command_set` (docs/protocols.md, "Choosing a set").

#include <optional>
#include <string>
#include <string_view>

#include "core/station_config.hpp"
#include "drivers/command_set.hpp"

namespace calstand::drivers::line {

/// The built-in set a backend stands for ("espec" -> "espec"); nullopt for the backends that
/// are not command sets of their own ("sim", "modbus", "acutrol", "line").
std::optional<std::string> builtin_set_of_backend(std::string_view backend);

/// The command set of a station's table or chamber: its `command_set` when given, else its
/// backend's built-in; nullopt when the device is driven otherwise (sim, modbus, acutrol without
/// a command set). Throws core::InputError naming `table.command_set` / `chamber.command_set`.
std::optional<CommandSet> station_command_set(const core::TableConfig& table);
std::optional<CommandSet> station_command_set(const core::ChamberConfig& chamber);

/// A station file's backend and command_set that name the set `set_name`.
struct StationNaming {
  std::string backend;
  std::string command_set;  ///< empty when the backend names the set
};
StationNaming station_naming(const std::string& set_name, DeviceKind device);

}  // namespace calstand::drivers::line
