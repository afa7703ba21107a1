#pragma once
// A controller's line protocol as data (docs/protocols.md, "Command sets"): for each operation
// the device supports, the lines to send and how to read the replies. A chamber or a rate table
// that speaks line-based ASCII is a command-set file, not a driver: LineChamber and LineTable
// drive any of them, and sim-station serves the simulated devices in any of them
// (CommandSetServer).
//
// Strings in a command set are byte strings written as Latin-1: "\u00b6" is the single byte 0xB6
// (Weiss SimServ's field separator), not its two-byte UTF-8 form.

#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <regex>
#include <string>
#include <string_view>
#include <vector>

namespace calstand::drivers::line {

/// The kind of device a command set drives.
enum class DeviceKind { kChamber, kTable };

/// How a reply field is read from a capture group of the reply's pattern.
struct FieldSpec {
  enum class Kind {
    kNumber,  ///< a decimal number, times `scale`
    kText,    ///< the group's text as it is
    kBit,     ///< bit `bit` of the group read as an integer in `base`: true or false
    kMap,     ///< the group's text looked up in `map` (a text result; unlisted: `otherwise`)
    kMatch,   ///< true when the group matched at all (an optional group)
  };
  Kind kind = Kind::kNumber;
  int group = 1;        ///< capture group of the step's reply pattern (1 = first)
  double scale = 1.0;   ///< kNumber: value = number * scale (e.g. 0.001 for millidegrees)
  int bit = 0;          ///< kBit: bit number, 0 = least significant
  int base = 10;        ///< kBit: 10 or 16
  bool invert = false;  ///< kBit, kMatch: the opposite truth
  std::map<std::string, std::string> map;  ///< kMap: device text -> value
  std::optional<std::string> otherwise;    ///< kMap: value of an unlisted text (none: bad reply)
};

/// A value read from a reply: a number, a truth or a text.
struct FieldValue {
  std::optional<double> number;
  std::optional<bool> truth;
  std::optional<std::string> text;
};
using Fields = std::map<std::string, FieldValue>;

/// One line sent and the reply it expects (or none).
struct Step {
  /// Template of the line (terminator and address prefix excluded): fmt replacement fields
  /// with the operation's named arguments, e.g. ":D:P {axis},{angle_deg:.4f}".
  std::string command;
  /// Pattern of the reply line (ECMAScript regex, whole line); none: the device answers nothing
  /// to this command.
  std::optional<std::regex> reply;
  std::string reply_source;  ///< the pattern as written (messages)
  std::map<std::string, FieldSpec> fields;
  /// For simulators only (CommandSetServer): the reply as a template of the fields, e.g.
  /// "{air_c:.1f},{setpoint_c:.1f}". Absent: the step cannot be served.
  std::optional<std::string> reply_format;
};

/// An operation: the steps sent in order (e.g. a mode then a demand).
struct Operation {
  std::vector<Step> steps;
};

/// A reply that means the controller refused the command; `text_group` holds its words.
struct ErrorPattern {
  std::regex pattern;
  std::string source;  ///< as written
  int text_group = 0;  ///< 0: the whole line
};

/// How the lines travel.
struct LineFormat {
  std::string terminator = "\r\n";  ///< appended to every command line
  /// Put before every command line: a template with {address} (RS-485 multi-drop), e.g.
  /// "{address},"; empty: none.
  std::string prefix;
  std::string address;       ///< the station file's connection.address overrides it
  int timeout_ms = 1000;     ///< per reply
  int delay_ms = 0;          ///< wait after each command without a reply (slow controllers)
  int default_tcp_port = 0;  ///< used when the connection gives none (0: must be given)
  int default_baud = 9600;   ///< used when the connection gives none
};

/// A command set, parsed and checked.
struct CommandSet {
  std::string name;
  DeviceKind device = DeviceKind::kChamber;
  std::string source;  ///< the public document it was written from (docs)
  LineFormat line;
  std::vector<ErrorPattern> errors;
  /// For simulators only: the refusal reply, a template with {text}; empty: none served.
  std::string error_format;
  /// Operation name -> steps. Chamber operations: identify, read_air, read_setpoint, read_mode,
  /// set_setpoint, set_ramp, start, standby, read_alarms. Table operations: identify,
  /// set_limits, position, rate, sine, stop, read_position, read_rate, read_status,
  /// read_interlock, close_interlock. Which are required: docs/protocols.md.
  std::map<std::string, Operation> operations;
  /// Table only: the wire names of the axes ({axis} in templates), e.g. "1"/"2" or "X"/"Y".
  std::string outer_axis = "1";
  std::string inner_axis = "2";
  /// The set's own numbers a driver may need (e.g. "constant_mode_ramp": 0), free form.
  nlohmann::json extras = nlohmann::json::object();

  const Operation* find(std::string_view operation) const;
  bool has(std::string_view operation) const { return find(operation) != nullptr; }
};

/// Parses a command set from its JSON (schemas/command-set.schema.json, then the cross-field
/// rules: each operation the device kind requires, every field's group within its pattern,
/// templates that fmt accepts). Throws core::InputError naming `where` + the field and why.
CommandSet parse_command_set(const nlohmann::json& doc, const std::string& where);

/// The built-in command set `name` (drivers/command_sets/*.json, compiled in), or nullopt.
std::optional<CommandSet> builtin_command_set(std::string_view name);
/// The built-in names of one device kind, sorted.
std::vector<std::string> builtin_command_set_names(DeviceKind device);

/// A station file's `command_set`: a built-in name, or a file path (relative to the station
/// file's folder `base_dir` when not absolute). Throws core::InputError naming `where`.
CommandSet load_command_set(const std::string& name_or_path, const std::string& base_dir,
                            DeviceKind device, const std::string& where);

/// Named arguments of a template: numbers and texts.
struct Arguments {
  std::map<std::string, double> numbers;
  std::map<std::string, std::string> texts;
};

/// The line of `step` with `args` put in (no terminator, no prefix). Throws core::InputError
/// when the template names an argument not given (`where`: the operation, for messages).
std::string render(const std::string& templ, const Arguments& args, const std::string& where);

/// Latin-1 text of a JSON string (each code point below 256 one byte); throws core::InputError
/// naming `where` for a code point beyond.
std::string latin1_of(const std::string& utf8, const std::string& where);

/// The fields of `step` read from `reply`, or why the reply is not what the step expects.
struct ParsedReply {
  Fields fields;
  std::string error;  ///< non-empty: a bad reply (the pattern did not match, a field unreadable)
};
ParsedReply parse_reply(const Step& step, std::string_view reply);

/// The controller's words when `reply` is one of the set's error replies, else nullopt.
std::optional<std::string> match_error(const CommandSet& set, std::string_view reply);

}  // namespace calstand::drivers::line
