#pragma once

#include <array>
#include <optional>
#include <string>
#include <string_view>

namespace calstand::drivers::scpi {

/// The command set of one model of programmable supply, as data: another model needs only
/// another row. Setting templates take the value through fmt (`{:.4f}`); queries answer one
/// line. Set commands are not answered (SCPI): the driver asks `error_query` after each one.
struct CommandSet {
  std::string_view model;            ///< the station file's `connection.model`
  std::string_view identify;         ///< -> one line naming the instrument
  std::string_view clear_status;     ///< empties the error queue
  std::string_view output_on;        ///< switches the output on
  std::string_view output_off;       ///< switches the output off
  std::string_view output_query;     ///< -> "1"/"0" (or "ON"/"OFF")
  std::string_view set_voltage;      ///< template, value in V
  std::string_view set_current;      ///< template (current limit), value in A
  std::string_view measure_voltage;  ///< -> V
  std::string_view measure_current;  ///< -> A
  std::string_view error_query;      ///< -> `<code>,"<text>"`; code 0: no error
};

/// Every model calstand knows. "generic": SCPI-1999 supply commands (most bench supplies:
/// Keysight E36xx, Rigol DP8xx, R&S HMP, Siglent SPD answer these).
inline constexpr std::array kCommandSets{
    CommandSet{"generic", "*IDN?", "*CLS", "OUTP ON", "OUTP OFF", "OUTP?", "VOLT {:.4f}",
               "CURR {:.4f}", "MEAS:VOLT?", "MEAS:CURR?", "SYST:ERR?"},
};

/// The command set of `model`, or nullptr.
const CommandSet* find_command_set(std::string_view model);

/// One entry of the instrument's error queue.
struct ErrorEntry {
  int code = 0;      ///< 0: no error; SCPI errors are negative, device-specific positive
  std::string text;  ///< without the quotes
};

/// Parses a `SYST:ERR?` reply (`-222,"Data out of range"`, `+0,"No error"`); nullopt when it
/// is not one.
std::optional<ErrorEntry> parse_error_entry(std::string_view reply);
/// A finite decimal number (SCPI NR1/NR2/NR3, e.g. `+2.80000E+01`); nullopt otherwise.
std::optional<double> parse_number(std::string_view reply);
/// `1`/`0`/`ON`/`OFF` (any case); nullopt otherwise.
std::optional<bool> parse_boolean(std::string_view reply);

}  // namespace calstand::drivers::scpi
