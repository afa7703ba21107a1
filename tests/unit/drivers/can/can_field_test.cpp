#include "drivers/can_field.hpp"

#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <random>

namespace calstand::drivers {
namespace {

using Payload = std::array<std::uint8_t, 8>;

CanField field(std::uint32_t start_bit, std::uint32_t length_bits, ByteOrder order,
               FieldType type = FieldType::kUnsigned) {
  CanField f;
  f.start_bit = start_bit;
  f.length_bits = length_bits;
  f.byte_order = order;
  f.type = type;
  return f;
}

TEST(CanFieldTest, ByteAlignedFieldsReadInTheirByteOrder) {
  const Payload p{0x34, 0x12, 0, 0, 0, 0, 0, 0};
  EXPECT_EQ(field(0, 16, ByteOrder::kLittle).extract_raw(p), 0x1234u);
  EXPECT_EQ(field(0, 16, ByteOrder::kBig).extract_raw(p), 0x3412u);
  // The 24 bits at byte 0, big-endian: 34 12 00.
  EXPECT_EQ(field(0, 24, ByteOrder::kBig).extract_raw(p), 0x341200u);
}

TEST(CanFieldTest, BitFieldsFollowTheDocumentedNumbering) {
  // Little-endian: bit 4 is bit 4 of byte 0, running upward into byte 1.
  const Payload p{0xA0, 0x0B, 0, 0, 0, 0, 0, 0};
  EXPECT_EQ(field(4, 8, ByteOrder::kLittle).extract_raw(p), 0xBAu);
  // Big-endian: payload bit 4 is the low nibble of byte 0 (MSB first), running into byte 1's
  // high nibble.
  const Payload q{0x0C, 0xD0, 0, 0, 0, 0, 0, 0};
  EXPECT_EQ(field(4, 8, ByteOrder::kBig).extract_raw(q), 0xCDu);
  EXPECT_EQ(field(4, 8, ByteOrder::kBig).occupied_mask(),
            0xF00Fu);  // byte 0 bits 0-3, byte 1 bits 4-7
  EXPECT_EQ(field(4, 8, ByteOrder::kLittle).occupied_mask(), 0x0FF0u);
  EXPECT_EQ(field(4, 8, ByteOrder::kBig).bytes_needed(), 2u);
  EXPECT_EQ(field(56, 8, ByteOrder::kLittle).bytes_needed(), 8u);
}

TEST(CanFieldTest, SignedFieldsAreSignExtendedAndScaled) {
  Payload p{};
  CanField f = field(0, 12, ByteOrder::kLittle, FieldType::kSigned);
  f.scale = 0.5;
  f.offset = 10.0;
  f.insert_raw(p, 0xFFF);  // -1 in 12 bits
  EXPECT_DOUBLE_EQ(f.decode(p), -0.5 + 10.0);
  f.insert_raw(p, 0x800);  // most negative
  EXPECT_DOUBLE_EQ(f.decode(p), -2048 * 0.5 + 10.0);
}

TEST(CanFieldTest, FloatFieldsCarryIeeeValues) {
  Payload p{};
  const CanField f32 = field(8, 32, ByteOrder::kBig, FieldType::kFloat);
  f32.encode(p, 0.00123);
  EXPECT_FLOAT_EQ(static_cast<float>(f32.decode(p)), 0.00123f);
  const CanField f64 = field(0, 64, ByteOrder::kLittle, FieldType::kFloat);
  f64.encode(p, 12345.6789);
  EXPECT_DOUBLE_EQ(f64.decode(p), 12345.6789);
}

TEST(CanFieldTest, IntegerEncodingQuantisesAndSaturates) {
  Payload p{};
  CanField f = field(0, 16, ByteOrder::kLittle, FieldType::kSigned);
  f.scale = 0.01;
  f.encode(p, 1.234);
  EXPECT_NEAR(f.decode(p), 1.23, 1e-12);
  f.encode(p, 1e9);  // beyond +327.67: reads back as the top of the range
  EXPECT_NEAR(f.decode(p), 327.67, 1e-9);
  f.encode(p, -1e9);
  EXPECT_NEAR(f.decode(p), -327.68, 1e-9);
  CanField u = field(0, 64, ByteOrder::kBig);
  u.encode(p, 1e30);
  EXPECT_EQ(u.extract_raw(p), ~std::uint64_t{0});
  u.encode(p, -5.0);
  EXPECT_EQ(u.extract_raw(p), 0u);
}

TEST(CanFieldTest, InsertThenExtractRoundTripsAnyLayoutAndLeavesOtherBits) {
  std::mt19937_64 rng(20261122);
  for (int trial = 0; trial < 2000; ++trial) {
    const auto length = static_cast<std::uint32_t>(1 + rng() % 64);
    const auto start = static_cast<std::uint32_t>(rng() % (65 - length));
    const auto order = (rng() & 1) ? ByteOrder::kBig : ByteOrder::kLittle;
    const CanField f = field(start, length, order);
    Payload p{};
    for (auto& b : p) b = static_cast<std::uint8_t>(rng());
    const Payload before = p;
    const std::uint64_t raw = rng() & (length == 64 ? ~0ull : (1ull << length) - 1);
    f.insert_raw(p, raw);
    ASSERT_EQ(f.extract_raw(p), raw) << "start " << start << " length " << length;
    const std::uint64_t mask = f.occupied_mask();
    ASSERT_EQ(std::popcount(mask), static_cast<int>(length));
    for (int bit = 0; bit < 64; ++bit) {
      if (mask & (1ull << bit)) continue;
      ASSERT_EQ((p[bit / 8] >> (bit % 8)) & 1, (before[bit / 8] >> (bit % 8)) & 1)
          << "bit " << bit << " outside the field changed";
    }
  }
}

}  // namespace
}  // namespace calstand::drivers
