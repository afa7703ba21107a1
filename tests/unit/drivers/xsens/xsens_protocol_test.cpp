// The Xbus codec against MT0101P's printed messages and the value formats' definitions.
#include "drivers/xsens_protocol.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.hpp"

namespace calstand::drivers::xsens {
namespace {

using Bytes = std::vector<std::uint8_t>;

TEST(XsensProtocol, EncodesTheManualsPrintedMessages) {
  // GoToConfig is the complete message MT0101P prints as its example; the other two follow
  // from the checksum rule (every byte after the preamble sums to 0).
  EXPECT_EQ(encode_message(mid::kGoToConfig), (Bytes{0xFA, 0xFF, 0x30, 0x00, 0xD1}));
  EXPECT_EQ(encode_message(mid::kGoToMeasurement), (Bytes{0xFA, 0xFF, 0x10, 0x00, 0xF1}));
  EXPECT_EQ(encode_message(mid::kReqDid), (Bytes{0xFA, 0xFF, 0x00, 0x00, 0x01}));
}

TEST(XsensProtocol, EveryByteAfterThePreambleSumsToZero) {
  for (std::size_t n : {0u, 1u, 17u, 254u, 255u, 300u, 2048u}) {
    Bytes data(n);
    for (std::size_t i = 0; i < n; ++i) data[i] = static_cast<std::uint8_t>(i * 7 + 3);
    const Bytes m = encode_message(mid::kMtData2, data);
    unsigned sum = 0;
    for (std::size_t i = 1; i < m.size(); ++i) sum += m[i];
    EXPECT_EQ(sum % 256, 0u) << n;
    const Scan scan = scan_message(m);
    ASSERT_EQ(scan.status, ScanStatus::kMessage) << n;
    EXPECT_EQ(scan.size, m.size());
    EXPECT_EQ(scan.message.mid, mid::kMtData2);
    EXPECT_EQ(scan.message.data, data);
  }
}

TEST(XsensProtocol, UsesTheExtendedLengthAbove254Bytes) {
  const Bytes m254 = encode_message(mid::kMtData2, Bytes(254));
  EXPECT_EQ(m254[3], 254);
  EXPECT_EQ(m254.size(), 4u + 254u + 1u);
  const Bytes m300 = encode_message(mid::kMtData2, Bytes(300));
  EXPECT_EQ(m300[3], 0xFF);
  EXPECT_EQ(m300[4], 0x01);  // 300 = 0x012C, big-endian
  EXPECT_EQ(m300[5], 0x2C);
  EXPECT_EQ(m300.size(), 6u + 300u + 1u);
}

TEST(XsensProtocol, ScanTellsIncompleteBadChecksumBadBusAndBadLength) {
  Bytes m = encode_message(mid::kGoToConfigAck);
  EXPECT_EQ(scan_message(std::span(m).first(3)).status, ScanStatus::kIncomplete);
  m[2] ^= 0x01;
  EXPECT_EQ(scan_message(m).status, ScanStatus::kBadChecksum);
  EXPECT_EQ(scan_message(Bytes{0xFA, 0x01, 0x30, 0x00, 0xCF}).status, ScanStatus::kBadBusId);
  // Extended length 0x0801 = 2049 > 2048: refused without waiting for 2049 bytes.
  EXPECT_EQ(scan_message(Bytes{0xFA, 0xFF, 0x36, 0xFF, 0x08, 0x01}).status, ScanStatus::kBadLength);
}

TEST(XsensProtocol, FindsMessagesAmongOtherBytes) {
  Bytes stream{0x00, 0xFA, 0x12};
  const Bytes a = encode_message(mid::kGoToConfigAck);
  const Bytes b = encode_message(mid::kDeviceId, Bytes{0x01, 0x23, 0x45, 0x67});
  stream.insert(stream.end(), a.begin(), a.end());
  stream.push_back(0xFA);
  stream.insert(stream.end(), b.begin(), b.end());
  const auto found = messages_in(stream);
  ASSERT_EQ(found.size(), 2u);
  EXPECT_EQ(found[0].mid, mid::kGoToConfigAck);
  EXPECT_EQ(found[1].mid, mid::kDeviceId);
  EXPECT_EQ(found[1].data, (Bytes{0x01, 0x23, 0x45, 0x67}));
}

Bytes bytes_of(double v, Precision p) {
  Bytes out;
  put_value(out, v, p);
  return out;
}

TEST(XsensProtocol, EncodesValuesInTheFourPrecisions) {
  EXPECT_EQ(bytes_of(1.0, Precision::kFloat32), (Bytes{0x3F, 0x80, 0x00, 0x00}));
  EXPECT_EQ(bytes_of(-2.0, Precision::kFloat64),
            (Bytes{0xC0, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00}));
  // 12.20: value * 2^20 in a signed 32-bit integer.
  EXPECT_EQ(bytes_of(1.0, Precision::kFp1220), (Bytes{0x00, 0x10, 0x00, 0x00}));
  EXPECT_EQ(bytes_of(-1.0, Precision::kFp1220), (Bytes{0xFF, 0xF0, 0x00, 0x00}));
  // 16.32: the 32 fractional bits, then the 16-bit integer part.
  EXPECT_EQ(bytes_of(1.0, Precision::kFp1632), (Bytes{0x00, 0x00, 0x00, 0x00, 0x00, 0x01}));
  EXPECT_EQ(bytes_of(-0.5, Precision::kFp1632), (Bytes{0x80, 0x00, 0x00, 0x00, 0xFF, 0xFF}));
  EXPECT_EQ(bytes_of(2.25, Precision::kFp1632), (Bytes{0x40, 0x00, 0x00, 0x00, 0x00, 0x02}));
}

TEST(XsensProtocol, ValuesComeBackToTheirFormatsResolution) {
  for (double v : {0.0, 1e-3, -0.123456789, 9.80665, -1234.5678, 2047.0}) {
    EXPECT_EQ(get_value(bytes_of(v, Precision::kFloat64).data(), Precision::kFloat64), v);
    EXPECT_EQ(get_value(bytes_of(v, Precision::kFloat32).data(), Precision::kFloat32),
              static_cast<double>(static_cast<float>(v)));
    EXPECT_NEAR(get_value(bytes_of(v, Precision::kFp1220).data(), Precision::kFp1220), v,
                0.5 / 1048576.0 + 1e-15);
    EXPECT_NEAR(get_value(bytes_of(v, Precision::kFp1632).data(), Precision::kFp1632), v,
                0.5 / 4294967296.0 + 1e-15);
  }
  // Outside 12.20's range (+-2048) the value saturates instead of wrapping round.
  EXPECT_NEAR(quantise(5000.0, Precision::kFp1220), 2048.0, 1e-5);
  EXPECT_DOUBLE_EQ(quantise(-5000.0, Precision::kFp1220), -2048.0);
}

TEST(XsensProtocol, NedTurnsTheSensorFrameAboutX) {
  const std::array<double, 3> v{1.0, 2.0, 3.0};
  EXPECT_EQ(to_coordinates(Coordinates::kEnu, v), v);
  EXPECT_EQ(to_coordinates(Coordinates::kNwu, v), v);
  EXPECT_EQ(to_coordinates(Coordinates::kNed, v), (std::array<double, 3>{1.0, -2.0, -3.0}));
}

TEST(XsensProtocol, ErrorTextNamesTheCode) {
  const Bytes invalid_parameter{0x21};
  EXPECT_EQ(error_text(invalid_parameter),
            "Error 0x21: invalid parameter (not valid or out of range)");
  EXPECT_NE(error_text(Bytes{0x04}).find("invalid message"), std::string::npos);
  EXPECT_NE(error_text(Bytes{0x28, 0x01, 0x02}).find("device error (details 01 02)"),
            std::string::npos);
  EXPECT_NE(error_text(Bytes{0x77}).find("0x77: unknown"), std::string::npos);
}

TEST(XsensProtocol, OutputConfigurationRoundTripsAndRejectsAPartialEntry) {
  const std::vector<OutputItem> items{{0x1020, 0xFFFF}, {0x8026, 400}};
  const Bytes data = encode_output_configuration(items);
  EXPECT_EQ(data, (Bytes{0x10, 0x20, 0xFF, 0xFF, 0x80, 0x26, 0x01, 0x90}));
  EXPECT_EQ(parse_output_configuration(data), items);
  EXPECT_FALSE(parse_output_configuration(std::span(data).first(6)).has_value());
}

WireFormatSettings xsens_settings(double rate, nlohmann::json options = nlohmann::json::object()) {
  WireFormatSettings s;
  s.sample_rate_hz = rate;
  s.options = std::move(options);
  s.where = "imus[0].connection.xsens";
  return s;
}

TEST(XsensProtocol, OptionsDefaultToFloat32EnuAndTheHighestTemperatureRate) {
  const Options o = parse_options(xsens_settings(2000));
  EXPECT_EQ(o.precision, Precision::kFloat32);
  EXPECT_EQ(o.coordinates, Coordinates::kEnu);
  EXPECT_EQ(o.temperature_rate_hz, 400);  // the cap
  EXPECT_EQ(parse_options(xsens_settings(100)).temperature_rate_hz, 100);
  EXPECT_EQ(parse_options(xsens_settings(1000)).temperature_rate_hz, 250);  // divides 1000
}

TEST(XsensProtocol, OptionsSetTheFormatBitsOfTheConfiguration) {
  const Options o = parse_options(xsens_settings(
      400, {{"float_format", "fp1632"}, {"coordinates", "ned"}, {"temperature_rate_hz", 50}}));
  const auto items = output_configuration(o, 400);
  ASSERT_EQ(items.size(), 5u);
  EXPECT_EQ(items[0], (OutputItem{0x1020, 0xFFFF}));
  EXPECT_EQ(items[1], (OutputItem{0x1060, 0xFFFF}));
  EXPECT_EQ(items[2], (OutputItem{0x4026, 400}));  // fp16.32 (0x2) | NED (0x4)
  EXPECT_EQ(items[3], (OutputItem{0x8026, 400}));
  EXPECT_EQ(items[4], (OutputItem{0x0812, 50}));
  const auto nwu = output_configuration(
      parse_options(xsens_settings(100, {{"float_format", "float64"}, {"coordinates", "nwu"}})),
      100);
  EXPECT_EQ(nwu[3].xdi, 0x802B);
}

TEST(XsensProtocol, OptionsTheSchemaCannotCheckNameTheirKey) {
  try {
    parse_options(xsens_settings(1000, {{"temperature_rate_hz", 300}}));
    FAIL() << "300 Hz does not divide 1000 Hz";
  } catch (const core::InputError& e) {
    EXPECT_EQ(e.where(), "imus[0].connection.xsens.temperature_rate_hz");
  }
  EXPECT_THROW(parse_options(xsens_settings(100, {{"temperature_rate_hz", 200}})),
               core::InputError);
  EXPECT_THROW(parse_options(xsens_settings(100, {{"temperature_rate_hz", 2.5}})),
               core::InputError);
  EXPECT_THROW(parse_options(xsens_settings(100, {{"float_format", "fp88"}})), core::InputError);
}

}  // namespace
}  // namespace calstand::drivers::xsens
