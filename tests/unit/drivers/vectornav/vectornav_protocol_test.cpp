// The VectorNav codec against the manual's own printed examples (VN-100 User Manual UM001
// v2.22; VN-200 User Manual UM004 for the same command set).
#include "drivers/vectornav_protocol.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "core/error.hpp"

namespace calstand::drivers::vectornav {
namespace {

std::span<const std::uint8_t> vn_bytes(const std::string& s) {
  return {reinterpret_cast<const std::uint8_t*>(s.data()), s.size()};
}

TEST(VectornavChecksum, MatchesTheManualsPrintedCommands) {
  // UM001 §5.1.1/§5.1.2 examples, UM004 §3.1 and §5.11.7.
  EXPECT_EQ(ascii_message("VNRRG,5"), "$VNRRG,5*46\r\n");
  EXPECT_EQ(ascii_message("VNRRG,5,9600"), "$VNRRG,5,9600*65\r\n");
  EXPECT_EQ(ascii_message("VNWRG,5,9600"), "$VNWRG,5,9600*60\r\n");
  EXPECT_EQ(ascii_message("VNRRG,11"), "$VNRRG,11*73\r\n");
  EXPECT_EQ(ascii_message("VNERR,03"), "$VNERR,03*72\r\n");
  EXPECT_EQ(ascii_message("VNRRG,06,0"), "$VNRRG,06,0*69\r\n");  // UM004 §5.7
}

TEST(VectornavChecksum, ParsesAReplyAndRefusesABadChecksumUnlessBypassed) {
  AsciiMessage m;
  ASSERT_EQ(parse_ascii(vn_bytes("$VNRRG,5,9600*65\r\n"), false, m), Scan::kOk);
  EXPECT_EQ(m.size, 18u);
  ASSERT_EQ(m.fields.size(), 3u);
  EXPECT_EQ(m.fields[0], "VNRRG");
  EXPECT_EQ(m.fields[2], "9600");
  EXPECT_EQ(parse_ascii(vn_bytes("$VNRRG,5,9600*66\r\n"), false, m), Scan::kInvalid);
  EXPECT_EQ(parse_ascii(vn_bytes("$VNRRG,5,9600*6"), false, m), Scan::kIncomplete);
  // UM001 §3.8.1: "$VNRRG,1*XX" bypasses the check (for the device, not for us reading it).
  EXPECT_EQ(parse_ascii(vn_bytes("$VNRRG,1*XX\r\n"), false, m), Scan::kInvalid);
  ASSERT_EQ(parse_ascii(vn_bytes("$VNRRG,1*XX\r\n"), true, m), Scan::kOk);
  EXPECT_TRUE(m.checksum_bypassed);
  EXPECT_EQ(parse_ascii(vn_bytes("$VNRRG,\x01*XX\r\n"), true, m), Scan::kInvalid);
}

TEST(VectornavCrc, IsTheXmodemFormWithItsCheckValue) {
  EXPECT_EQ(crc16(vn_bytes("123456789")), 0x31C3);
  EXPECT_EQ(crc16({}), 0x0000);
}

TEST(VectornavBinary, MeasuresTheManualsExampleConfiguration) {
  // UM001 p. 35: "$VNWRG,75,1,16,15,0001,000C,0014*XX" selects Common TimeStartup, IMU
  // UncompAccel + UncompGyro, Attitude Quaternion + MagNed: 8 + 24 + 28 payload bytes.
  const std::vector<std::uint8_t> header{kSync, 0x15, 0x01, 0x00, 0x0C, 0x00, 0x14, 0x00};
  BinaryHeader h;
  ASSERT_EQ(parse_binary_header(header, h), Scan::kOk);
  EXPECT_EQ(h.header_bytes, 8u);
  EXPECT_EQ(h.payload_bytes, 8u + 12u + 12u + 16u + 12u);
  EXPECT_EQ(h.message_bytes(), 8u + 60u + 2u);
  EXPECT_EQ(parse_binary_header(std::span(header).first(5), h), Scan::kIncomplete);
}

TEST(VectornavBinary, RefusesHeadersItCannotMeasure) {
  BinaryHeader h;
  const std::vector<std::uint8_t> extension{kSync, 0x81, 0x01, 0x00};  // group byte extended
  EXPECT_EQ(parse_binary_header(extension, h), Scan::kInvalid);
  const std::vector<std::uint8_t> unused{kSync, 0x08, 0x01, 0x00};  // group 4: unused
  EXPECT_EQ(parse_binary_header(unused, h), Scan::kInvalid);
  const std::vector<std::uint8_t> reserved{kSync, 0x01, 0x02, 0x00};  // Common bit 1: reserved
  EXPECT_EQ(parse_binary_header(reserved, h), Scan::kInvalid);
  const std::vector<std::uint8_t> word_ext{kSync, 0x01, 0x01, 0x80};
  EXPECT_EQ(parse_binary_header(word_ext, h), Scan::kInvalid);
  const std::vector<std::uint8_t> none{kSync, 0x00};
  EXPECT_EQ(parse_binary_header(none, h), Scan::kInvalid);
}

TEST(VectornavBinary, EncodesAMessageWhoseWholeCrcIsZeroAndParsesItBack) {
  core::ImuSample s;
  s.device_time_s = 12.345678901;
  s.gyro_dps = {10.0, -20.0, 0.5};
  s.accel_mps2 = {0.25, -9.80665, 3.0};
  s.temperature_c = 31.25;
  const auto m =
      encode_binary_message(s, kCommonTimeStartup, kImuUncompAccel | kImuUncompGyro | kImuTemp);
  ASSERT_EQ(m.size(), 1u + 1u + 4u + 8u + 12u + 12u + 4u + 2u);
  EXPECT_EQ(m[0], 0xFA);
  EXPECT_EQ(m[1], 0x05);
  EXPECT_EQ(crc16(std::span(m).subspan(1)), 0);
  // Little-endian TimeStartup in ns right after the two field words.
  std::uint64_t ns = 0;
  for (int i = 7; i >= 0; --i) ns = (ns << 8) | m[6 + static_cast<std::size_t>(i)];
  EXPECT_EQ(ns, 12345678901u);
  BinaryHeader h;
  ASSERT_EQ(parse_binary_header(m, h), Scan::kOk);
  ASSERT_EQ(h.message_bytes(), m.size());
  const auto f = parse_binary_payload(m, h);
  ASSERT_TRUE(f.time_startup_ns && f.uncomp_gyro_rps && f.uncomp_accel_mps2 && f.temperature_c);
  EXPECT_FALSE(f.gyro_rps);
  EXPECT_NEAR((*f.uncomp_gyro_rps)[1], -20.0 * M_PI / 180.0, 1e-6);
  EXPECT_FLOAT_EQ((*f.uncomp_accel_mps2)[2], 3.0f);
  EXPECT_FLOAT_EQ(*f.temperature_c, 31.25f);
  EXPECT_THROW(encode_binary_message(s, 0x0002, 0), std::invalid_argument);
}

WireFormatSettings vn_settings(nlohmann::json options) {
  WireFormatSettings s;
  s.sample_rate_hz = 100;
  s.options = std::move(options);
  s.where = "imus[0].connection.vectornav";
  return s;
}

TEST(VectornavOptions, DefaultsToUncompensatedOnPort1At800Hz) {
  const auto o = parse_options(vn_settings(nlohmann::json::object()));
  EXPECT_FALSE(o.compensated);
  EXPECT_EQ(o.port, 1);
  EXPECT_EQ(o.imu_rate_hz, 800.0);
  EXPECT_EQ(imu_fields(o), kImuUncompAccel | kImuUncompGyro | kImuTemp);
  EXPECT_EQ(binary_output_body(o, 8), "VNWRG,75,1,8,05,0001,001C");
  const auto c = parse_options(vn_settings({{"outputs", "compensated"}, {"port", 2}}));
  EXPECT_TRUE(c.compensated);
  EXPECT_EQ(binary_output_body(c, 1), "VNWRG,75,2,1,05,0001,0610");
}

TEST(VectornavOptions, NamesTheKeyItRefuses) {
  for (const auto& [bad, key] :
       std::vector<std::pair<nlohmann::json, std::string>>{{{{"outputs", "raw"}}, "outputs"},
                                                           {{{"port", 3}}, "port"},
                                                           {{{"imu_rate_hz", -1}}, "imu_rate_hz"},
                                                           {{{"baud", 1}}, "baud"}}) {
    try {
      parse_options(vn_settings(bad));
      ADD_FAILURE() << key;
    } catch (const core::InputError& e) {
      EXPECT_EQ(e.where(), "imus[0].connection.vectornav." + key);
    }
  }
}

TEST(VectornavOptions, RateDivisorOfTheImuRateOrARefusalNamingTheRates) {
  Options o;
  EXPECT_EQ(rate_divisor(o, 800), 1);
  EXPECT_EQ(rate_divisor(o, 100), 8);
  EXPECT_EQ(rate_divisor(o, 50), 16);  // UM001 p. 35: "800 / 16 = 50 Hz"
  try {
    rate_divisor(o, 300);
    ADD_FAILURE();
  } catch (const DeviceConfigError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("300 Hz"), std::string::npos) << what;
    EXPECT_NE(what.find("800, 400, 200, 160, 100"), std::string::npos) << what;
  }
  EXPECT_THROW(rate_divisor(o, 1600), DeviceConfigError);
  o.imu_rate_hz = 400;
  EXPECT_EQ(rate_divisor(o, 100), 4);
}

TEST(VectornavErrors, NameTheManualsCodes) {
  EXPECT_EQ(error_text("03"), "$VNERR,03: Invalid Checksum");
  EXPECT_EQ(error_text("08"), "$VNERR,08: Invalid Register");
  EXPECT_EQ(error_text("10"), "$VNERR,10: Watchdog Reset");
  EXPECT_EQ(error_text("xx"), "$VNERR,xx: unknown error code");
}

}  // namespace
}  // namespace calstand::drivers::vectornav
