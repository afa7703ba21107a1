#pragma once

#include <linux/can.h>

#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "drivers/can_field.hpp"

namespace calstand::drivers {

/// One SG_ line of a DBC file (Vector CANdb++ format), with what CM_, VAL_ and SIG_VALTYPE_
/// said about it.
struct DbcSignal {
  enum class Mux { kPlain, kSwitch, kMultiplexed };       ///< none, `M`, `mN`
  enum class ValueType { kInteger, kFloat32, kFloat64 };  ///< SIG_VALTYPE_ 0 / 1 / 2

  std::string name;
  Mux mux = Mux::kPlain;
  std::uint32_t mux_value = 0;  ///< N of `mN`
  /// As written: Intel (@1) the least significant bit; Motorola (@0) the most significant bit,
  /// both in the DBC's sawtooth numbering (bit k of byte b is 8 * b + k).
  std::uint32_t start_bit = 0;
  std::uint32_t length_bits = 0;
  bool little_endian = true;  ///< @1 Intel, @0 Motorola
  bool is_signed = false;     ///< `-`
  ValueType value_type = ValueType::kInteger;
  double factor = 1.0;
  double offset = 0.0;
  double minimum = 0.0;
  double maximum = 0.0;
  std::string unit;
  std::vector<std::string> receivers;
  std::string comment;                         ///< CM_ SG_
  std::map<std::int64_t, std::string> values;  ///< VAL_: raw value -> the device's words
  std::size_t line = 0;                        ///< of the SG_ line

  /// The signal as a CanField (physical = raw * factor + offset). Motorola start bits are
  /// converted from the DBC's sawtooth numbering to CanField's big-endian bit string: the
  /// most significant bit at DBC bit s is stream position 8 * (s / 8) + 7 - s % 8.
  CanField field() const;
};

/// One BO_ of a DBC file.
struct DbcMessage {
  canid_t id = 0;  ///< 11-bit, or 29-bit with CAN_EFF_FLAG (BO_ ids with bit 31 set)
  std::string name;
  std::uint32_t dlc = 0;
  std::string sender;
  std::string comment;  ///< CM_ BO_
  std::vector<DbcSignal> signals;
  std::size_t line = 0;

  const DbcSignal* signal(std::string_view signal_name) const;
  /// The `M` switch signal, or nullptr.
  const DbcSignal* multiplexer() const;
};

/// A parsed DBC file: messages and their signals, with comments, value descriptions and float
/// value types attached; nodes and the version kept; attribute definitions and values, value
/// tables, environment variables, signal groups and the other sections skipped by rule (each
/// statement up to its `;`); CANdb++'s VECTOR__INDEPENDENT_SIG_MSG (BO_ 3221225472) is parsed
/// but is no message; a UTF-8 byte order mark is skipped. Refused by name with FILE:LINE: extended
/// multiplexing (SG_MUL_VAL_, `mNM` signals), CAN FD (DLC > 8, VFrameFormat *_FD), signals beyond
/// the message's bytes, and anything that is not DBC syntax. Errors are core::InputError
/// "FILE:LINE: why".
struct DbcFile {
  std::string file;  ///< as given, for messages
  std::string version;
  std::vector<std::string> nodes;  ///< BU_
  std::vector<DbcMessage> messages;

  const DbcMessage* message(std::string_view name) const;

  static DbcFile parse(std::string_view text, const std::string& file);
  /// Reads and parses `path` (as given). Errors name `path`.
  static DbcFile load(const std::string& path);
};

}  // namespace calstand::drivers
