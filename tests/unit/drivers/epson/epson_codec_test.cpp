#include <gtest/gtest.h>

#include <cmath>

#include "core/error.hpp"
#include "drivers/epson_wire.hpp"

namespace calstand::drivers::epson {
namespace {

using Bytes = std::vector<std::uint8_t>;

WireFormatSettings epson_settings(double rate_hz, nlohmann::json options) {
  WireFormatSettings s;
  s.sample_rate_hz = rate_hz;
  s.options = std::move(options);
  s.where = "imus[0].connection.epson";
  return s;
}

TEST(EpsonCodec, CommandsAreAddressDataDelimiter) {
  // M-G362PDC1 Table 6.10: read = 0 A[6:0], don't care, 0x0D; write sets bit 7 of the address.
  EXPECT_EQ(read_command(0x02), (Bytes{0x02, 0x00, 0x0D}));
  EXPECT_EQ(write_command(0x7E, 0x01), (Bytes{0xFE, 0x01, 0x0D}));
  EXPECT_EQ(write_command(0x03, 0x02), (Bytes{0x83, 0x02, 0x0D}));
}

TEST(EpsonCodec, ReadReplyIsFoundOnlyAtTheEndOfWhatArrived) {
  // Table 6.11: address, data hi, data lo, 0x0D.
  EXPECT_EQ(find_read_reply(Bytes{0x02, 0x04, 0x00, 0x0D}, 0x02), 0x0400);
  EXPECT_EQ(find_read_reply(Bytes{0x55, 0x6A, 0x47, 0x33, 0x0D}, 0x6A), 0x4733);
  EXPECT_FALSE(find_read_reply(Bytes{0x02, 0x04, 0x00}, 0x02));
  EXPECT_FALSE(find_read_reply(Bytes{0x04, 0x04, 0x00, 0x0D}, 0x02));
  EXPECT_FALSE(find_read_reply(Bytes{0x02, 0x04, 0x00, 0x0C}, 0x02));
}

TEST(EpsonCodec, BurstChecksumIsTheSumOfTheBigEndianWords) {
  // Worked by hand: 0x1234 + 0xFFFF + 0x0001 = 0x11234 -> 0x1234 (16 bits).
  EXPECT_EQ(burst_checksum(Bytes{0x12, 0x34, 0xFF, 0xFF, 0x00, 0x01}), 0x1234);
  EXPECT_EQ(burst_checksum(Bytes{}), 0);
}

TEST(EpsonCodec, SixteenBitFrameByteForByte) {
  BurstFields f;
  f.flags = 0xFE00;
  f.temperature = 0x0102;
  f.gyro[0] = 66;  // 1 deg/s on a G366PDG0
  f.gyro[1] = -1;
  f.gyro[2] = 0;
  f.accel[0] = 4000;  // 1000 mG
  f.accel[1] = 0;
  f.accel[2] = -4000;
  f.count = 0x0010;
  const Bytes frame = encode_burst(f, 16);
  // Layout of M-G362PDC1 Table 6.14 (without GPIO): header, ND/EA, TEMP, gyro x/y/z,
  // accel x/y/z, COUNT, CHECKSUM, CR.
  const Bytes want{0x80, 0xFE, 0x00, 0x01, 0x02, 0x00, 0x42, 0xFF, 0xFF, 0x00, 0x00, 0x0F, 0xA0,
                   0x00, 0x00, 0xF0, 0x60, 0x00, 0x10,
                   // 0xFE00+0x0102+0x0042+0xFFFF+0x0000+0x0FA0+0x0000+0xF060+0x0010 = 0x2FF53
                   0xFF, 0x53, 0x0D};
  EXPECT_EQ(frame, want);
  ASSERT_EQ(frame.size(), burst_size(16));
  const auto back = parse_burst(frame, 16);
  ASSERT_TRUE(back);
  EXPECT_EQ(back->gyro[1], -1);
  EXPECT_EQ(back->accel[2], -4000);
  EXPECT_EQ(back->count, 0x0010);
}

TEST(EpsonCodec, ThirtyTwoBitFrameCarriesHighThenLowWord) {
  BurstFields f;
  f.gyro[0] = -65536 * 66 - 1;
  f.count = 0xFFFF;
  const Bytes frame = encode_burst(f, 32);
  ASSERT_EQ(frame.size(), 36u);
  // Header (1), flags (2), temperature (4), then gyro x, big endian: 0xFFBD_FFFF.
  EXPECT_EQ(frame[7], 0xFF);
  EXPECT_EQ(frame[8], 0xBD);
  EXPECT_EQ(frame[9], 0xFF);
  EXPECT_EQ(frame[10], 0xFF);
  const auto back = parse_burst(frame, 32);
  ASSERT_TRUE(back);
  EXPECT_EQ(back->gyro[0], -65536 * 66 - 1);
  Bytes bad = frame;
  bad[10] ^= 0x01;
  EXPECT_FALSE(parse_burst(bad, 32));
  EXPECT_FALSE(parse_burst(frame, 16));
}

TEST(EpsonScale, UnitsFollowTheModelRow) {
  const ModelScale* g366 = find_model("G366PDG0");
  const ModelScale* g365 = find_model("G365PDF1");
  const ModelScale* g354 = find_model("G354PDH0");
  ASSERT_TRUE(g366 && g365 && g354);
  EXPECT_NEAR(gyro_dps(*g366, 66, 16), 1.0, 1e-12);
  EXPECT_NEAR(gyro_dps(*g366, 66 * 65536, 32), 1.0, 1e-12);
  EXPECT_NEAR(gyro_dps(*g354, 625, 16), 10.0, 1e-12);
  EXPECT_NEAR(accel_mps2(*g366, 4000, 16), 9.80665, 1e-12);
  EXPECT_NEAR(accel_mps2(*g365, 2500, 16), 9.80665, 1e-12);
  EXPECT_NEAR(temperature_c(*g366, 0, 16), 25.0, 1e-12);
  EXPECT_NEAR(temperature_c(*g366, 256, 16), 26.0, 1e-12);
  EXPECT_NEAR(temperature_c(*g365, 2364, 16), 25.0, 1e-12);
  EXPECT_NEAR(temperature_c(*g365, 2364 - 1000, 16), 25.0 + 3.7918, 1e-9);
  EXPECT_EQ(gyro_raw(*g366, 1.0, 16), 66);
  EXPECT_EQ(gyro_raw(*g366, 1e6, 16), 32767);  // saturates as the register does
  EXPECT_EQ(temperature_raw(*g365, 25.0, 32), 2364 * 65536);
}

TEST(EpsonOptions, DefaultsAndTheSheetsRecommendedFilter) {
  const auto o = Options::from_settings(epson_settings(100, nlohmann::json::object()));
  EXPECT_EQ(o.width_bits, 32);
  EXPECT_TRUE(o.model.empty());
  ASSERT_NE(o.rate, nullptr);
  EXPECT_EQ(o.rate->dout_code, 0x0A);
  EXPECT_EQ(o.filter_code, moving_average_code(32));
  EXPECT_EQ(moving_average_code(32), 0x05);
  EXPECT_EQ(filter_code("kaiser_64_fc200"), 0x0E);
  EXPECT_EQ(filter_code("moving_average_0"), 0x00);
  EXPECT_FALSE(filter_code("moving_average_3"));
}

TEST(EpsonOptions, EveryMistakeNamesItsKey) {
  auto where_of = [](double rate, nlohmann::json j) {
    try {
      Options::from_settings(epson_settings(rate, std::move(j)));
    } catch (const core::InputError& e) {
      return e.where() + " | " + e.what();
    }
    return std::string("accepted");
  };
  EXPECT_NE(where_of(300, nlohmann::json::object()).find("epson.sample_rate_hz"),
            std::string::npos);
  EXPECT_NE(where_of(300, nlohmann::json::object()).find("2000, 1000, 500"), std::string::npos);
  EXPECT_NE(where_of(100, {{"model", "G999"}}).find("epson.model"), std::string::npos);
  EXPECT_NE(where_of(100, {{"width_bits", 24}}).find("epson.width_bits"), std::string::npos);
  EXPECT_NE(where_of(100, {{"filter", "moving_average_3"}}).find("epson.filter"),
            std::string::npos);
  EXPECT_NE(where_of(100, {{"count_step", "x"}}).find("epson.count_step"), std::string::npos);
  EXPECT_EQ(where_of(62.5, {{"model", "G370PDF1"}, {"width_bits", 16}, {"filter", "recommended"}}),
            "accepted");
}

}  // namespace
}  // namespace calstand::drivers::epson
