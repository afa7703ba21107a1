#pragma once

#include <cstdint>
#include <span>
#include <string_view>

namespace calstand::drivers {

/// Order of a field's bytes in a CAN payload.
///   kLittle (Intel): bit n of the payload is bit n % 8 of byte n / 8; the field's least
///                    significant bit is at start_bit and the field runs upward.
///   kBig (Motorola, "MSB first"): bit n of the payload is bit 7 - n % 8 of byte n / 8 (the
///                    payload read as one big-endian bit string); the field's most significant
///                    bit is at start_bit and the field runs forward.
/// For byte-aligned fields both reduce to the familiar byte orders: start_bit = 8 * start_byte.
enum class ByteOrder { kLittle, kBig };

/// How a field's raw bits become a number.
enum class FieldType { kUnsigned, kSigned, kFloat };  ///< kFloat: IEEE 754, 32 or 64 bits

std::string_view to_string(ByteOrder order);
std::string_view to_string(FieldType type);

/// Where one value sits in a classic CAN payload (8 bytes, 64 bits) and how it scales:
/// physical = raw * scale + offset. A plain value, validated by the map parser
/// (CanSignalMap::from_json), not here: the functions below assume a valid layout.
struct CanField {
  std::uint32_t start_bit = 0;    ///< see ByteOrder for the numbering [bit]
  std::uint32_t length_bits = 8;  ///< 1..64 (32 or 64 for kFloat) [bit]
  ByteOrder byte_order = ByteOrder::kLittle;
  FieldType type = FieldType::kUnsigned;
  double scale = 1.0;   ///< physical units per count (or per float unit)
  double offset = 0.0;  ///< physical units added after scaling

  /// Payload bits the field occupies (bit 8 * b + k is bit k of byte b), for overlap checks.
  std::uint64_t occupied_mask() const;
  /// Payload bytes needed to hold the field: the frame's length must be at least this [bytes].
  std::uint32_t bytes_needed() const;

  /// The field's raw bits, right-aligned (no sign extension).
  std::uint64_t extract_raw(std::span<const std::uint8_t, 8> payload) const;
  /// Writes the low length_bits of `raw` into the field, leaving other bits untouched.
  void insert_raw(std::span<std::uint8_t, 8> payload, std::uint64_t raw) const;

  /// The physical value (raw, sign-extended or reinterpreted as float, then scaled).
  /// May be NaN or infinite for float fields: the caller decides what that means.
  double decode(std::span<const std::uint8_t, 8> payload) const;
  /// Writes `physical` (quantised to the nearest count; saturated at the type's range for
  /// integers, so an out-of-range value reads back as the nearest representable one).
  void encode(std::span<std::uint8_t, 8> payload, double physical) const;
};

}  // namespace calstand::drivers
