#include "drivers/stim300_decoder.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace calstand::drivers::stim300 {
namespace {

constexpr double kG = 9.80665;

// A datagram 0xA7 whose fields are a known function of k (counts, not via the encoder's scale).
Datagram datagram_k(int k, std::uint8_t id = kRateAccInclTemp) {
  Datagram d;
  d.id = id;
  d.counter = static_cast<std::uint8_t>(k & 0xFF);
  d.latency_us = 250;
  d.value[0] = {16384 * k, -8192, 1};            // gyro [2^-14 deg/s]
  d.value[1] = {524288, -262144 * (k % 16), 0};  // acc, 10 g [2^-19 g]
  d.value[2] = {4194304, 0, -4194304};           // incl [2^-22 g]
  d.temp[0] = {25 * 256, 26 * 256, 27 * 256};    // [2^-8 degC]
  return d;
}

std::vector<std::uint8_t> stream(int from, int to, bool termination = true) {
  std::vector<std::uint8_t> out;
  for (int k = from; k < to; ++k) {
    const auto b = encode_datagram(datagram_k(k), termination);
    out.insert(out.end(), b.begin(), b.end());
  }
  return out;
}

Stim300Options terminated() {
  Stim300Options o;
  o.termination = true;
  return o;
}

TEST(Stim300Decoder, DecodesEverySplitToTheSheetsScales) {
  const auto bytes = stream(0, 40);
  for (std::size_t chunk : {1u, 2u, 7u, 61u, 1000u}) {
    Stim300Decoder decoder(terminated(), 500.0);
    std::vector<core::ImuSample> out;
    for (std::size_t at = 0; at < bytes.size(); at += chunk) {
      decoder.feed(std::span(bytes).subspan(at, std::min(chunk, bytes.size() - at)), out);
    }
    ASSERT_EQ(out.size(), 40u) << chunk;
    for (int k = 0; k < 40; ++k) {
      const auto& s = out[static_cast<std::size_t>(k)];
      EXPECT_DOUBLE_EQ(s.gyro_dps.x(), k);
      EXPECT_DOUBLE_EQ(s.gyro_dps.y(), -0.5);
      EXPECT_DOUBLE_EQ(s.gyro_dps.z(), 1.0 / 16384.0);
      EXPECT_DOUBLE_EQ(s.accel_mps2.x(), kG);
      EXPECT_DOUBLE_EQ(s.accel_mps2.y(), -0.5 * (k % 16) * kG);
      EXPECT_DOUBLE_EQ(s.temperature_c, 26.0);
      EXPECT_EQ(s.sequence, static_cast<std::uint32_t>(k));
      EXPECT_NEAR(s.device_time_s, k / 500.0 - 250e-6, 1e-12);
    }
    EXPECT_EQ(decoder.stats().frames, 40u);
    EXPECT_EQ(decoder.stats().garbage_bytes, 0u);
    EXPECT_EQ(decoder.stats().bytes_fed, decoder.stats().frame_bytes + decoder.buffered());
    EXPECT_EQ(decoder.datagram_id(), kRateAccInclTemp);
  }
}

TEST(Stim300Decoder, UnwrapsTheCounterAcrossItsWrapAndCountsGaps) {
  Stim300Decoder decoder(terminated(), 2000.0);
  std::vector<core::ImuSample> out;
  auto bytes = stream(250, 262);  // counter 250..255, 0..5
  decoder.feed(bytes, out);
  auto more = stream(265, 267);  // 262..264 lost
  decoder.feed(more, out);
  ASSERT_EQ(out.size(), 14u);
  EXPECT_EQ(out[5].sequence, 255u);
  EXPECT_EQ(out[6].sequence, 256u);
  EXPECT_EQ(out[11].sequence, 261u);
  EXPECT_EQ(out[12].sequence, 265u);
  EXPECT_GT(out[6].device_time_s, out[5].device_time_s);
  EXPECT_EQ(decoder.stats().sequence_gaps, 1u);
}

TEST(Stim300Decoder, ABadCrcCostsOneByteAndTheNextDatagramIsKept) {
  Stim300Decoder decoder(terminated(), 2000.0);
  std::vector<core::ImuSample> out;
  auto bytes = stream(0, 3);
  bytes[61 + 10] ^= 0x40;  // second datagram's gyro status byte
  decoder.feed(bytes, out);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[1].sequence, 2u);
  EXPECT_EQ(decoder.stats().crc_errors, 1u);
  EXPECT_EQ(decoder.stats().sequence_gaps, 1u);
  EXPECT_EQ(decoder.stats().garbage_bytes, 61u);
  EXPECT_EQ(decoder.stats().resyncs, 1u);
}

TEST(Stim300Decoder, GarbageBetweenDatagramsIsCountedAndSkipped) {
  Stim300Decoder decoder(terminated(), 2000.0);
  std::vector<core::ImuSample> out;
  std::vector<std::uint8_t> bytes{0x00, 0xA7, 0x13, 0x93};  // 0xA7 starts a false candidate
  const auto good = stream(0, 2);
  bytes.insert(bytes.end(), good.begin(), good.end());
  bytes.push_back(0x55);
  bytes.insert(bytes.end(), good.begin(), good.end());
  decoder.feed(bytes, out);
  // Feeding stops at the last datagram; nothing is held back once it is complete.
  ASSERT_EQ(out.size(), 4u);
  EXPECT_EQ(decoder.stats().garbage_bytes, 5u);
  EXPECT_EQ(decoder.stats().resyncs, 2u);
  EXPECT_EQ(decoder.stats().crc_errors, 2u);  // the 0xA7 and 0x93 candidates (not yet locked)
  EXPECT_EQ(decoder.buffered(), 0u);
  EXPECT_EQ(decoder.stats().bytes_fed,
            decoder.stats().frame_bytes + decoder.stats().garbage_bytes + decoder.buffered());
}

TEST(Stim300Decoder, AMissingConfiguredTerminationIsALengthError) {
  Stim300Decoder decoder(terminated(), 2000.0);
  std::vector<core::ImuSample> out;
  auto bytes = stream(0, 1, false);
  const auto rest = stream(1, 3);
  bytes.insert(bytes.end(), rest.begin(), rest.end());
  decoder.feed(bytes, out);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(decoder.stats().length_errors, 1u);
}

TEST(Stim300Decoder, ATerminationLeftOpenAcceptsBothAndLocksOntoTheFirstIdentifier) {
  Stim300Decoder decoder(Stim300Options{}, 2000.0);
  std::vector<core::ImuSample> out;
  auto bytes = stream(0, 2, false);
  const auto crlf = stream(2, 4, true);
  bytes.insert(bytes.end(), crlf.begin(), crlf.end());
  // A valid datagram of another identifier after the lock is not this stream's.
  const auto other = encode_datagram(datagram_k(4, kRateAcc), false);
  bytes.insert(bytes.end(), other.begin(), other.end());
  decoder.feed(bytes, out);
  EXPECT_EQ(out.size(), 4u);
  EXPECT_EQ(decoder.stats().garbage_bytes, other.size());
  EXPECT_EQ(decoder.datagram_id(), kRateAccInclTemp);
}

TEST(Stim300Decoder, AConfiguredIdentifierIgnoresOthers) {
  Stim300Options o = terminated();
  o.datagram = kRateAcc;
  Stim300Decoder decoder(o, 2000.0);
  std::vector<core::ImuSample> out;
  auto bytes = stream(0, 2);
  const auto mine = encode_datagram(datagram_k(7, kRateAcc), true);
  bytes.insert(bytes.end(), mine.begin(), mine.end());
  decoder.feed(bytes, out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].sequence, 7u);
  EXPECT_DOUBLE_EQ(out[0].temperature_c, 0.0);  // 0x91 carries no temperatures
}

TEST(Stim300Decoder, IncrementsBecomeRatesAtTheSampleRate) {
  Stim300Options o = terminated();
  o.gyro_output = GyroOutput::kIncrement;
  o.accel_output = AccelOutput::kIncrement;
  o.accel_range_g = 5;
  Stim300Decoder decoder(o, 1000.0);
  Datagram d = datagram_k(1);
  d.value[0] = {2097, 0, 0};  // [2^-21 deg]
  d.value[1] = {8388, 0, 0};  // [2^-23 m/s]
  std::vector<core::ImuSample> out;
  decoder.feed(encode_datagram(d, true), out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_DOUBLE_EQ(out[0].gyro_dps.x(), 2097.0 / 2097152.0 * 1000.0);
  EXPECT_DOUBLE_EQ(out[0].accel_mps2.x(), 8388.0 / 8388608.0 * 1000.0);
}

TEST(Stim300Decoder, TheStartUpDatagramsAreARestartAndDeviceTimeGoesBack) {
  Stim300Decoder decoder(terminated(), 2000.0);
  std::vector<core::ImuSample> out;
  auto bytes = stream(100, 110);
  const auto part = encode_digits_datagram(kPartNumber, "84167-2500-301", true);
  const auto serial = encode_digits_datagram(kSerialNumber, "N25581234", true);
  const auto config = encode_configuration(std::array<std::uint8_t, kConfigurationBytes>{}, true);
  for (const auto* b : {&part, &serial, &config}) bytes.insert(bytes.end(), b->begin(), b->end());
  const auto after = stream(0, 3);
  bytes.insert(bytes.end(), after.begin(), after.end());
  decoder.feed(bytes, out);
  ASSERT_EQ(out.size(), 13u);
  EXPECT_LT(out[10].device_time_s, out[9].device_time_s);
  EXPECT_EQ(out[10].sequence, 0u);
  EXPECT_EQ(decoder.stats().sequence_gaps, 0u);
  EXPECT_EQ(decoder.stats().startup_datagrams, 3u);
  EXPECT_EQ(decoder.stats().garbage_bytes, 0u);
  const auto reports = decoder.take_device_reports();
  ASSERT_GE(reports.size(), 1u);
  EXPECT_EQ(reports[0], "restart: the unit sent its part number datagram (841672500301)");
  EXPECT_TRUE(decoder.take_device_reports().empty());
}

TEST(Stim300Decoder, StatusBitsAreReportedInTheUnitsWordsWhenTheyChange) {
  Stim300Decoder decoder(terminated(), 2000.0);
  std::vector<core::ImuSample> out;
  std::vector<std::uint8_t> bytes;
  for (int k = 0; k < 4; ++k) {
    Datagram d = datagram_k(k);
    if (k == 1 || k == 2) d.status[0] = 0x24;  // gyro z: outside operating conditions
    const auto b = encode_datagram(d, true);
    bytes.insert(bytes.end(), b.begin(), b.end());
  }
  decoder.feed(bytes, out);
  const auto reports = decoder.take_device_reports();
  ASSERT_EQ(reports.size(), 2u);
  EXPECT_EQ(reports[0], "gyro z: outside operating conditions");
  EXPECT_EQ(reports[1], "gyro: status clear");
  EXPECT_EQ(decoder.stats().status_flags, 2u);
}

TEST(Stim300Decoder, AfterRestartTheCutDatagramIsStartBytesAndNoGap) {
  Stim300Decoder decoder(terminated(), 2000.0);
  std::vector<core::ImuSample> out;
  decoder.feed(stream(0, 2), out);
  decoder.restart();
  const auto bytes = stream(5, 8);
  decoder.feed(std::span(bytes).subspan(20), out);  // the flush cut datagram 5
  ASSERT_EQ(out.size(), 4u);
  EXPECT_EQ(decoder.stats().start_bytes, 61u - 20u);
  EXPECT_EQ(decoder.stats().garbage_bytes, 0u);
  EXPECT_EQ(decoder.stats().crc_errors, 0u);
  EXPECT_EQ(decoder.stats().sequence_gaps, 0u);
  EXPECT_EQ(out[2].sequence, 6u);
  EXPECT_GT(out[2].device_time_s, out[1].device_time_s);
}

TEST(Stim300Decoder, RandomBytesNeverBreakTheAccounting) {
  std::mt19937 rng(29);
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<std::uint8_t> bytes = stream(0, 3);
    std::uniform_int_distribution<int> byte(0, 255);
    for (int i = 0; i < 64; ++i) {
      bytes[static_cast<std::size_t>(byte(rng)) % bytes.size()] =
          static_cast<std::uint8_t>(byte(rng));
    }
    Stim300Decoder decoder(Stim300Options{}, 2000.0);
    std::vector<core::ImuSample> out;
    decoder.feed(bytes, out);
    const auto& s = decoder.stats();
    EXPECT_EQ(s.bytes_fed, s.frame_bytes + s.garbage_bytes + s.start_bytes + decoder.buffered());
    EXPECT_EQ(out.size(), s.frames);
  }
}

}  // namespace
}  // namespace calstand::drivers::stim300
