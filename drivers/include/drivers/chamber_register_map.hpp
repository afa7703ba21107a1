#pragma once

#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace calstand::drivers {

/// Which Modbus table a value lives in: holding registers (read 0x03, written 0x06/0x10) or
/// input registers (read-only, 0x04).
enum class RegisterKind { kHolding, kInput };

/// How a value is stored in registers.
enum class RegisterEncoding {
  kInt16,    ///< one register, two's complement, value = count * scale
  kUint16,   ///< one register, unsigned, value = count * scale
  kFloat32,  ///< two registers holding an IEEE 754 single, order given by WordOrder
};

/// Order of the two 16-bit words of a 32-bit value (each word is big-endian on the wire, as
/// Modbus defines; only the word order varies between controllers).
enum class WordOrder {
  kHighFirst,  ///< the lower address holds the most significant word ("big-endian", ABCD)
  kLowFirst,   ///< the lower address holds the least significant word ("word swapped", CDAB)
};

std::string_view to_string(RegisterEncoding encoding);
std::string_view to_string(WordOrder order);

/// One engineering value on the controller: where it is and how it is encoded.
struct RegisterField {
  std::uint16_t address = 0;  ///< protocol address (zero-based, as sent on the wire)
  RegisterKind kind = RegisterKind::kHolding;
  RegisterEncoding encoding = RegisterEncoding::kInt16;
  double scale = 1.0;  ///< engineering units per count (int16/uint16), e.g. 0.1 for tenths
  WordOrder word_order = WordOrder::kHighFirst;  ///< float32 only

  /// Registers the value occupies: 1, or 2 for float32.
  int register_count() const { return encoding == RegisterEncoding::kFloat32 ? 2 : 1; }
  /// Smallest step the encoding can express [engineering units]: scale, or 0 for float32.
  double resolution() const { return encoding == RegisterEncoding::kFloat32 ? 0.0 : scale; }
};

/// The registers of one value: words[0] goes to `address`, words[1] (float32) to address + 1.
struct RegisterWords {
  std::array<std::uint16_t, 2> words{};
  int count = 1;
  std::span<const std::uint16_t> span() const { return {words.data(), std::size_t(count)}; }
};

/// Encodes `value` (rounded to the nearest count for integer encodings). nullopt when it cannot
/// be represented: not finite, or beyond the encoding's range after scaling.
std::optional<RegisterWords> encode_value(const RegisterField& field, double value);
/// Decodes the field's registers (`words` holds register_count() words, in address order).
/// float32 may decode to NaN or infinity; callers treat those as invalid readings.
double decode_value(const RegisterField& field, std::span<const std::uint16_t> words);

/// The controller's operating-mode register: one holding register whose value selects closed-loop
/// control or off (the chamber's standby).
struct ModeField {
  std::uint16_t address = 0;  ///< protocol address of a holding register
  std::uint16_t control = 0;  ///< value meaning "controlling to the setpoint" (auto)
  std::uint16_t standby = 0;  ///< value meaning "off": the air drifts to ambient
};

/// A bit-oriented alarm word the controller keeps: each set bit is an alarm it reports (which
/// alarm a bit means is the controller's manual's business; the driver reports the word).
struct AlarmRegister {
  std::uint16_t address = 0;  ///< protocol address of a holding register
  std::string name;           ///< what the word holds, for fault texts (e.g. "chamber alarms")
};

/// Where a chamber controller keeps its process value, setpoint and mode, as data: built-in
/// maps for known controllers, or a generic map from the station file. Temperatures in degC.
struct ChamberRegisterMap {
  std::string name;             ///< e.g. "watlow-f4t"; shown in errors and status
  RegisterField process_value;  ///< chamber air temperature [degC]; holding or input
  RegisterField setpoint;       ///< active setpoint [degC]; holding (written)
  /// Absent on controllers without a mode register (e.g. the F4 as mapped here): the driver then
  /// falls back to writing the setpoint to the chamber's ambient temperature for standby.
  std::optional<ModeField> mode;
  /// The controller's own setpoint ramp rate [degC/min], holding. Present only when the
  /// controller ramps by itself; otherwise the driver steps the setpoint at the requested ramp.
  std::optional<RegisterField> ramp_rate;
  /// Raw process-value words the controller reports on a sensor fault (open thermocouple, etc.),
  /// for single-register encodings. A float32 process value that is NaN or infinite is always a
  /// fault.
  std::vector<std::uint16_t> sensor_fault_raw;
  /// Alarm words read with every poll; any bit set is a chamber fault (and an event), not a
  /// lost link. Empty for controllers mapped without them.
  std::vector<AlarmRegister> alarms;

  /// Sets the word order of every float32 field (controllers configure it globally).
  void set_word_order(WordOrder order);
  /// Throws core::InputError naming `where`.<field> when the map cannot work: a written value
  /// in input registers, a zero or non-finite scale, fields that overlap.
  void validate(const std::string& where) const;
};

/// Watlow F4 over Modbus RTU: signed int16 in tenths of a degree (decimal places set to 1 on the
/// controller), process value (input 1) at holding register 100, static setpoint at 300, no mode
/// register. Sensor fault: 32767 and -32768 (full scale, our assumption; see the protocol doc).
ChamberRegisterMap watlow_f4_map();
/// Watlow F4T loop 1: float32 in two holding registers, process value 2820, closed-loop setpoint
/// 2782, control mode 2730 (10 = auto, 62 = off). The word order must match the controller's
/// Modbus "data map" setting.
ChamberRegisterMap watlow_f4t_map(WordOrder order = WordOrder::kHighFirst);
/// Cincinnati Sub-Zero EZT-570i/EZT-570S, loop 1 (air temperature), from the controller's User
/// Communication Reference Manual, section 2.4 (docs/protocols.md, "CSZ EZT-570"): signed int16
/// with one implied decimal (scale 0.1: the manual leaves the decimal point to the loop's
/// configuration; a generic map with another scale covers a loop set otherwise), setpoint 60,
/// process value 61, chamber on/off in the manual event word 22 (1 = on, 0 = off: bit 0 only,
/// every other event off), alarm words 55 to 58. Sensor fault: the int16 full-scale words.
ChamberRegisterMap csz_ezt570_map();

/// The names of the built-in maps, for errors and help: "watlow-f4, watlow-f4t, csz-ezt570".
std::string builtin_map_names();
/// The built-in map `name`, or nullopt when there is none by that name.
std::optional<ChamberRegisterMap> builtin_map(std::string_view name,
                                              WordOrder word_order = WordOrder::kHighFirst);

/// Parses "high_first" / "low_first"; throws core::InputError naming `where` otherwise.
WordOrder word_order_from_json(const nlohmann::json& j, const std::string& where);

/// A map from the station file: a built-in name ("watlow-f4", "watlow-f4t", "csz-ezt570") or a
/// generic map object (fields documented in docs/protocols.md, "Chamber over Modbus"). `word_order`
/// applies to float32 fields. Throws core::InputError naming the field path under `where` (e.g.
/// `chamber.connection.map.setpoint.address`) and why.
ChamberRegisterMap register_map_from_json(const nlohmann::json& j, const std::string& where,
                                          WordOrder word_order);

}  // namespace calstand::drivers
