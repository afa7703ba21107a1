#include "drivers/stim300_protocol.hpp"

#include <gtest/gtest.h>

#include <string>

#include "core/error.hpp"
#include "drivers/stim300_options.hpp"

namespace calstand::drivers::stim300 {
namespace {

std::vector<std::uint8_t> bytes_of(const std::string& text) { return {text.begin(), text.end()}; }

TEST(Stim300Crc, HasTheCheckValueOfCrc32Mpeg2) {
  // Polynomial 0x04C11DB7, initial 0xFFFFFFFF, no reflection, no final XOR: the catalogued
  // check value over "123456789" is 0x0376E6E7.
  EXPECT_EQ(crc32(bytes_of("123456789")), 0x0376E6E7u);
  EXPECT_EQ(crc32({}), 0xFFFFFFFFu);
}

TEST(Stim300Crc, PadsTheBodyWithZeroDummyBytesToAMultipleOfFour) {
  const std::vector<std::uint8_t> body{0x93, 1, 2, 3, 4, 5};
  EXPECT_EQ(datagram_crc(body), crc32(std::vector<std::uint8_t>{0x93, 1, 2, 3, 4, 5, 0, 0}));
  EXPECT_NE(datagram_crc(body), crc32(body));
  const std::vector<std::uint8_t> four{1, 2, 3, 4};
  EXPECT_EQ(datagram_crc(four), crc32(four));
}

TEST(Stim300Layout, SizesAndDummyBytesFollowTheFieldsOfEachIdentifier) {
  struct Want {
    std::uint8_t id;
    std::size_t size, padding;
  };
  // Identifier, 3 x 24 bit + status per group, 3 x 16 bit + status per group with
  // temperatures, counter, latency, CRC.
  for (const Want w :
       {Want{0x90, 18, 2}, Want{0x91, 28, 0}, Want{0x92, 28, 0}, Want{0x93, 38, 2},
        Want{0x94, 25, 3}, Want{0xA5, 42, 2}, Want{0xA6, 42, 2}, Want{0xA7, 59, 1}}) {
    const auto layout = datagram_layout(w.id);
    ASSERT_TRUE(layout) << int(w.id);
    EXPECT_EQ(layout->size(), w.size) << int(w.id);
    EXPECT_EQ(layout->padding(), w.padding) << int(w.id);
    Datagram d;
    d.id = w.id;
    EXPECT_EQ(encode_datagram(d, false).size(), w.size);
    EXPECT_EQ(encode_datagram(d, true).size(), w.size + 2);
  }
  EXPECT_FALSE(datagram_layout(0x98));  // AUX: not read
  EXPECT_FALSE(datagram_layout(0xB1));
}

TEST(Stim300Datagram, FieldsAreBigEndianTwosComplementAtTheirPlaces) {
  Datagram d;
  d.id = kRateAccIncl;
  d.value[0] = {1, -1, 0x123456};
  d.value[1] = {-8388608, 8388607, 2};
  d.value[2] = {3, 4, -5};
  d.status = {0x00, 0x11, 0x22};
  d.counter = 0xAB;
  d.latency_us = 0x0203;
  const auto bytes = encode_datagram(d, true);
  ASSERT_EQ(bytes.size(), 40u);
  EXPECT_EQ(bytes[0], 0x93);
  EXPECT_EQ((std::vector<std::uint8_t>(bytes.begin() + 1, bytes.begin() + 10)),
            (std::vector<std::uint8_t>{0, 0, 1, 0xFF, 0xFF, 0xFF, 0x12, 0x34, 0x56}));
  EXPECT_EQ(bytes[10], 0x00);
  EXPECT_EQ(bytes[11], 0x80);  // -2^23
  EXPECT_EQ(bytes[20], 0x11);
  EXPECT_EQ(bytes[30], 0x22);
  EXPECT_EQ(bytes[31], 0xAB);
  EXPECT_EQ(bytes[32], 0x02);
  EXPECT_EQ(bytes[33], 0x03);
  EXPECT_EQ(bytes[38], 0x0D);
  EXPECT_EQ(bytes[39], 0x0A);
  EXPECT_TRUE(crc_matches(bytes, 38));
  const auto back = parse_datagram(bytes, *datagram_layout(0x93));
  EXPECT_EQ(back.value, d.value);
  EXPECT_EQ(back.status, d.status);
  EXPECT_EQ(back.counter, 0xAB);
  EXPECT_EQ(back.latency_us, 0x0203);
  auto bad = bytes;
  bad[5] ^= 0x01;
  EXPECT_FALSE(crc_matches(bad, 38));
}

TEST(Stim300Datagram, TemperaturesFollowAllInertialGroups) {
  Datagram d;
  d.id = kRateAccInclTemp;
  d.temp[0] = {256, -256, 1};
  d.temp_status[2] = 0x24;
  const auto bytes = encode_datagram(d, false);
  // id + 3 x 10 inertial bytes, then the gyro temperatures.
  EXPECT_EQ(bytes[31], 0x01);
  EXPECT_EQ(bytes[32], 0x00);
  EXPECT_EQ(bytes[33], 0xFF);
  EXPECT_EQ(bytes[34], 0x00);
  EXPECT_EQ(bytes[51], 0x24);
  const auto back = parse_datagram(bytes, *datagram_layout(0xA7));
  EXPECT_EQ(back.temp, d.temp);
  EXPECT_EQ(back.temp_status, d.temp_status);
}

TEST(Stim300Scale, CountsPerUnitOfEachOutputAndRange) {
  EXPECT_EQ(gyro_counts_per_unit(GyroOutput::kAngularRate), 16384.0);
  EXPECT_EQ(gyro_counts_per_unit(GyroOutput::kIncrement), 2097152.0);
  EXPECT_EQ(accel_counts_per_unit(5, AccelOutput::kAcceleration), 1048576.0);
  EXPECT_EQ(accel_counts_per_unit(10, AccelOutput::kAcceleration), 524288.0);
  EXPECT_EQ(accel_counts_per_unit(30, AccelOutput::kAcceleration), 262144.0);
  EXPECT_EQ(accel_counts_per_unit(80, AccelOutput::kAcceleration), 65536.0);
  EXPECT_EQ(accel_counts_per_unit(10, AccelOutput::kIncrement), 4194304.0);
  EXPECT_EQ(accel_counts_per_unit(80, AccelOutput::kIncrement), 524288.0);
  EXPECT_THROW(accel_counts_per_unit(2, AccelOutput::kAcceleration), std::invalid_argument);
  EXPECT_EQ(incl_counts_per_unit(AccelOutput::kAcceleration), 4194304.0);
}

TEST(Stim300Rates, OnlyTheUnitsRatesAreRates) {
  for (double r : {125.0, 250.0, 500.0, 1000.0, 2000.0}) EXPECT_TRUE(is_sample_rate(r)) << r;
  for (double r : {0.0, 100.0, 400.0, 2500.0}) EXPECT_FALSE(is_sample_rate(r)) << r;
}

TEST(Stim300Status, BitsReadAsTheUnitsConditionsPerChannel) {
  EXPECT_TRUE(status_text(Group::kGyro, false, 0).empty());
  const auto lines = status_text(Group::kGyro, false, 0x21);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_EQ(lines[0], "gyro x: outside operating conditions");
  const auto two = status_text(Group::kAcc, false, 0x16);
  ASSERT_EQ(two.size(), 1u);
  EXPECT_EQ(two[0], "accelerometer y,z: overload");
  const auto many = status_text(Group::kIncl, true, 0xC8);
  ASSERT_EQ(many.size(), 3u);
  EXPECT_EQ(many[0], "inclinometer temperature: error in measurement channel");
  EXPECT_EQ(many[1], "inclinometer temperature: start-up");
  EXPECT_EQ(many[2], "inclinometer temperature: system integrity error");
}

TEST(Stim300Names, IdentifiersAndNamesBothSelectADatagram) {
  EXPECT_EQ(datagram_id_from_name("0x93"), 0x93);
  EXPECT_EQ(datagram_id_from_name("0xa7"), 0xA7);
  EXPECT_EQ(datagram_id_from_name("rate_acc"), 0x91);
  EXPECT_FALSE(datagram_id_from_name("0x98"));
  EXPECT_EQ(datagram_name(0x93), "0x93 (rate_acc_incl)");
}

TEST(Stim300Replies, DigitsArePackedTwoToAByteAndALengthIsFoundByItsCrc) {
  const auto part = encode_digits_datagram(kPartNumber, "84167-2500-301", true);
  // Identifier with CR LF, 12 digit codes in 6 bytes, CRC, CR LF.
  ASSERT_EQ(part.size(), 1u + 6u + 4u + 2u);
  EXPECT_EQ(part[0], 0xB3);
  EXPECT_EQ(part[1], 0x84);
  EXPECT_EQ(part[6], 0x01);
  EXPECT_EQ(encode_digits_datagram(kSerialNumber, "N2558123", false)[0], 0xB5);
  Datagram d;
  d.id = kRateAccIncl;
  std::vector<std::uint8_t> line = encode_datagram(d, true);
  line.push_back(0xB1);  // a lone identifier byte: not a datagram
  line.insert(line.end(), part.begin(), part.end());
  const auto scan = find_reply(line, kPartNumber);
  ASSERT_EQ(scan.result, ScanResult::kFound);
  EXPECT_EQ(scan.offset, 41u);
  EXPECT_EQ(scan.size, part.size() - 2);
  EXPECT_EQ(digits_of(std::span(line).subspan(scan.offset, scan.size)), "841672500301");
  EXPECT_EQ(find_reply(line, kSerialNumber).result, ScanResult::kNone);
  // Cut short: the candidate may still complete.
  EXPECT_EQ(find_reply(std::span(part).first(8), kPartNumber).result, ScanResult::kNeedMore);
  // An odd count is padded with a 0 code; letters A..F are codes 10..15.
  EXPECT_EQ(digits_of(encode_digits_datagram(kPartNumber, "1A3", false)), "1A30");
}

TEST(Stim300Replies, TheConfigurationDatagramCarriesItsBytesUnderItsCrc) {
  const std::array<std::uint8_t, kConfigurationBytes> config{1, 2, 3};
  const auto plain = encode_configuration(config, false);
  ASSERT_EQ(plain.size(), 1 + kConfigurationBytes + kCrcSize);
  EXPECT_EQ(plain[0], 0xBC);
  EXPECT_TRUE(crc_matches(plain, plain.size()));
  const auto terminated = encode_configuration(config, true);
  EXPECT_EQ(terminated[0], 0xBD);
  EXPECT_EQ(terminated.back(), kLf);
  EXPECT_TRUE(is_startup_id(0xBD));
  EXPECT_TRUE(is_startup_id(0xB5));
  EXPECT_FALSE(is_startup_id(0xBE));
}

TEST(Stim300Options, DefaultsAndEveryMistakeNamesItsKey) {
  WireFormatSettings s;
  s.where = "imus[0].connection.stim300";
  const auto d = parse_stim300_options(s);
  EXPECT_FALSE(d.datagram);
  EXPECT_EQ(d.accel_range_g, 10);
  EXPECT_EQ(d.gyro_output, GyroOutput::kAngularRate);
  EXPECT_FALSE(d.termination);
  EXPECT_TRUE(d.rate_check);
  s.options = {{"datagram", "rate_acc"},
               {"accel_range_g", 80},
               {"gyro_output", "increment"},
               {"termination", true}};
  const auto o = parse_stim300_options(s);
  EXPECT_EQ(o.datagram, 0x91);
  EXPECT_EQ(o.accel_range_g, 80);
  EXPECT_EQ(o.gyro_output, GyroOutput::kIncrement);
  EXPECT_EQ(o.termination, true);
  for (const auto& [key, value] :
       std::vector<std::pair<std::string, nlohmann::json>>{{"datagram", "0x98"},
                                                           {"accel_range_g", 2},
                                                           {"gyro_output", "angle"},
                                                           {"termination", "yes"},
                                                           {"accel_output", "g"},
                                                           {"rate_check", 1},
                                                           {"baud", 9600}}) {
    s.options = {{key, value}};
    try {
      parse_stim300_options(s);
      ADD_FAILURE() << key;
    } catch (const core::InputError& e) {
      EXPECT_EQ(e.where(), "imus[0].connection.stim300." + key);
    }
  }
}

}  // namespace
}  // namespace calstand::drivers::stim300
