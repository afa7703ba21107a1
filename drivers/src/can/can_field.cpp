#include "drivers/can_field.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

namespace calstand::drivers {
namespace {

/// Position in the payload (8 * byte + bit-in-byte) of the field's value bit k (k = 0 is the
/// least significant bit of the value).
std::uint32_t payload_bit(const CanField& f, std::uint32_t k) {
  if (f.byte_order == ByteOrder::kLittle) return f.start_bit + k;
  // Big-endian: stream position p counts MSB first; value bit k sits at the field's last
  // stream position minus k.
  const std::uint32_t p = f.start_bit + f.length_bits - 1 - k;
  return 8 * (p / 8) + (7 - p % 8);
}

std::uint64_t low_mask(std::uint32_t bits) {
  return bits >= 64 ? ~std::uint64_t{0} : (std::uint64_t{1} << bits) - 1;
}

}  // namespace

std::string_view to_string(ByteOrder order) {
  return order == ByteOrder::kLittle ? "little" : "big";
}

std::string_view to_string(FieldType type) {
  switch (type) {
    case FieldType::kUnsigned:
      return "unsigned";
    case FieldType::kSigned:
      return "signed";
    case FieldType::kFloat:
      return "float";
  }
  return "?";
}

std::uint64_t CanField::occupied_mask() const {
  std::uint64_t mask = 0;
  for (std::uint32_t k = 0; k < length_bits; ++k) mask |= std::uint64_t{1} << payload_bit(*this, k);
  return mask;
}

std::uint32_t CanField::bytes_needed() const {
  const std::uint64_t mask = occupied_mask();
  return mask == 0 ? 0 : static_cast<std::uint32_t>((64 - std::countl_zero(mask) + 7) / 8);
}

std::uint64_t CanField::extract_raw(std::span<const std::uint8_t, 8> payload) const {
  std::uint64_t raw = 0;
  for (std::uint32_t k = 0; k < length_bits; ++k) {
    const std::uint32_t p = payload_bit(*this, k);
    raw |= std::uint64_t{(payload[p / 8] >> (p % 8)) & 1u} << k;
  }
  return raw;
}

void CanField::insert_raw(std::span<std::uint8_t, 8> payload, std::uint64_t raw) const {
  for (std::uint32_t k = 0; k < length_bits; ++k) {
    const std::uint32_t p = payload_bit(*this, k);
    const auto bit = static_cast<std::uint8_t>(1u << (p % 8));
    if ((raw >> k) & 1u) {
      payload[p / 8] = static_cast<std::uint8_t>(payload[p / 8] | bit);
    } else {
      payload[p / 8] = static_cast<std::uint8_t>(payload[p / 8] & ~bit);
    }
  }
}

double CanField::decode(std::span<const std::uint8_t, 8> payload) const {
  const std::uint64_t raw = extract_raw(payload);
  double value = 0.0;
  switch (type) {
    case FieldType::kUnsigned:
      value = static_cast<double>(raw);
      break;
    case FieldType::kSigned: {
      // Sign-extend from length_bits.
      const std::uint64_t sign = std::uint64_t{1} << (length_bits - 1);
      value = static_cast<double>(static_cast<std::int64_t>((raw ^ sign) - sign));
      break;
    }
    case FieldType::kFloat:
      value = length_bits == 32 ? double{std::bit_cast<float>(static_cast<std::uint32_t>(raw))}
                                : std::bit_cast<double>(raw);
      break;
  }
  return value * scale + offset;
}

void CanField::encode(std::span<std::uint8_t, 8> payload, double physical) const {
  const double counts = (physical - offset) / scale;
  std::uint64_t raw = 0;
  switch (type) {
    case FieldType::kUnsigned: {
      // Saturate in long double so that 2^64 - 1 is not rounded up past the range.
      const long double top = static_cast<long double>(low_mask(length_bits));
      long double c = std::isnan(counts) ? 0.0L : std::round(static_cast<long double>(counts));
      c = std::clamp(c, 0.0L, top);
      raw = c >= 18446744073709551615.0L ? ~std::uint64_t{0} : static_cast<std::uint64_t>(c);
      break;
    }
    case FieldType::kSigned: {
      const long double top = std::ldexp(1.0L, static_cast<int>(length_bits) - 1);
      long double c = std::isnan(counts) ? 0.0L : std::round(static_cast<long double>(counts));
      c = std::clamp(c, -top, top - 1.0L);
      raw = static_cast<std::uint64_t>(static_cast<std::int64_t>(c)) & low_mask(length_bits);
      break;
    }
    case FieldType::kFloat:
      raw = length_bits == 32 ? std::bit_cast<std::uint32_t>(static_cast<float>(counts))
                              : std::bit_cast<std::uint64_t>(counts);
      break;
  }
  insert_raw(payload, raw);
}

}  // namespace calstand::drivers
