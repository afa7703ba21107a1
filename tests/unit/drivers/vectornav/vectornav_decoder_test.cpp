// The VN-100 binary stream decoder: splits, gaps, checksums, garbage, ASCII errors, restarts.
#include "drivers/vectornav_decoder.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>

namespace calstand::drivers::vectornav {
namespace {

constexpr std::uint16_t kVnUncomp = kImuUncompAccel | kImuUncompGyro | kImuTemp;

core::ImuSample vn_sample(std::uint32_t k, double rate_hz = 100.0, double t0 = 5.0) {
  core::ImuSample s;
  s.device_time_s = t0 + k / rate_hz;
  s.gyro_dps = {std::sin(k / 10.0), -2.0 + 0.01 * k, 0.25};
  s.accel_mps2 = {0.1 * k, -9.81, std::cos(k / 7.0)};
  s.temperature_c = 20.0 + 0.5 * k;
  return s;
}

std::vector<std::uint8_t> vn_message(std::uint32_t k, double rate_hz = 100.0, double t0 = 5.0) {
  return encode_binary_message(vn_sample(k, rate_hz, t0), kCommonTimeStartup, kVnUncomp);
}

void vn_append(std::vector<std::uint8_t>& out, const std::vector<std::uint8_t>& m) {
  out.insert(out.end(), m.begin(), m.end());
}

void vn_append(std::vector<std::uint8_t>& out, const std::string& s) {
  out.insert(out.end(), s.begin(), s.end());
}

void vn_expect_accounted(const VectornavDecoder& d) {
  const auto& s = d.stats();
  EXPECT_EQ(s.bytes_fed,
            s.frame_bytes + s.ascii_bytes + s.garbage_bytes + s.start_bytes + d.buffered());
}

TEST(VectornavDecoder, DecodesSamplesWithDerivedSequenceAndDeviceTime) {
  VectornavDecoder d(100.0, false);
  std::vector<std::uint8_t> stream;
  for (std::uint32_t k = 0; k < 5; ++k) vn_append(stream, vn_message(k));
  std::vector<core::ImuSample> out;
  EXPECT_EQ(d.feed(stream, out), 5u);
  ASSERT_EQ(out.size(), 5u);
  for (std::uint32_t k = 0; k < 5; ++k) {
    const auto want = vn_sample(k);
    EXPECT_NEAR(out[k].device_time_s, want.device_time_s, 1e-9);
    EXPECT_EQ(out[k].sequence, 500u + k);  // round(TimeStartup * 100 Hz)
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(out[k].gyro_dps[i], want.gyro_dps[i], 1e-5);
      EXPECT_NEAR(out[k].accel_mps2[i], want.accel_mps2[i], 1e-5);
    }
    EXPECT_NEAR(out[k].temperature_c, want.temperature_c, 1e-5);
    EXPECT_EQ(out[k].receive_time_s, 0.0);
  }
  EXPECT_EQ(d.counters().at("frames"), 5u);
  EXPECT_EQ(d.counters().at("sequence_gaps"), 0u);
  EXPECT_EQ(d.counters().at("garbage_bytes"), 0u);
  vn_expect_accounted(d);
}

TEST(VectornavDecoder, AnySplitGivesTheSameSamples) {
  std::vector<std::uint8_t> stream;
  for (std::uint32_t k = 0; k < 4; ++k) vn_append(stream, vn_message(k));
  for (std::size_t chunk = 1; chunk <= stream.size(); ++chunk) {
    VectornavDecoder d(100.0, false);
    std::vector<core::ImuSample> out;
    for (std::size_t at = 0; at < stream.size(); at += chunk) {
      d.feed(std::span(stream).subspan(at, std::min(chunk, stream.size() - at)), out);
    }
    ASSERT_EQ(out.size(), 4u) << chunk;
    EXPECT_EQ(out[3].sequence, 503u);
    EXPECT_EQ(d.stats().garbage_bytes, 0u);
    vn_expect_accounted(d);
  }
}

TEST(VectornavDecoder, CountsADroppedMessageAsASequenceGap) {
  VectornavDecoder d(100.0, false);
  std::vector<std::uint8_t> stream;
  for (std::uint32_t k : {0u, 1u, 3u, 4u, 7u}) vn_append(stream, vn_message(k));
  std::vector<core::ImuSample> out;
  d.feed(stream, out);
  ASSERT_EQ(out.size(), 5u);
  EXPECT_EQ(d.stats().sequence_gaps, 2u);
  EXPECT_EQ(out[2].sequence, 503u);
}

TEST(VectornavDecoder, ABadCrcCostsOneByteAndTheNextMessageStillDecodes) {
  VectornavDecoder d(100.0, false);
  std::vector<std::uint8_t> stream;
  auto bad = vn_message(0);
  bad[10] ^= 0x40;
  vn_append(stream, bad);
  vn_append(stream, vn_message(1));
  std::vector<core::ImuSample> out;
  d.feed(stream, out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].sequence, 501u);
  EXPECT_EQ(d.stats().crc_errors, 1u);
  EXPECT_EQ(d.stats().garbage_bytes, bad.size());
  EXPECT_EQ(d.stats().resyncs, 1u);
  vn_expect_accounted(d);
}

TEST(VectornavDecoder, AMessageStartingInsideABadCandidateIsNotSkipped) {
  VectornavDecoder d(100.0, false);
  // A sync byte and a plausible header, cut short by a real message.
  std::vector<std::uint8_t> stream{kSync, 0x05, 0x01, 0x00, 0x1C, 0x00, 0x11, 0x22};
  vn_append(stream, vn_message(2));
  std::vector<core::ImuSample> out;
  d.feed(stream, out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].sequence, 502u);
  EXPECT_EQ(d.stats().crc_errors, 1u);
  EXPECT_EQ(d.stats().garbage_bytes, 8u);
}

TEST(VectornavDecoder, CountsGarbageAndUnmeasurableHeaders) {
  VectornavDecoder d(100.0, false);
  std::vector<std::uint8_t> stream{0x00, 0x11, kSync, 0x08, 0x33};
  vn_append(stream, vn_message(0));
  vn_append(stream, std::vector<std::uint8_t>{0x44, 0x55});
  vn_append(stream, vn_message(1));
  std::vector<core::ImuSample> out;
  d.feed(stream, out);
  EXPECT_EQ(out.size(), 2u);
  EXPECT_EQ(d.stats().garbage_bytes, 7u);
  EXPECT_EQ(d.stats().length_errors, 1u);
  EXPECT_EQ(d.stats().resyncs, 2u);
  EXPECT_EQ(d.stats().sequence_gaps, 0u);
  vn_expect_accounted(d);
}

TEST(VectornavDecoder, ReportsVnerrInTheDevicesWordsAndSkipsOtherAsciiOutput) {
  VectornavDecoder d(100.0, false);
  std::vector<std::uint8_t> stream;
  vn_append(stream, vn_message(0));
  vn_append(stream, ascii_message("VNERR,12"));
  vn_append(stream, ascii_message("VNWRG,06,0"));
  vn_append(stream, vn_message(1));
  std::vector<core::ImuSample> out;
  d.feed(stream, out);
  EXPECT_EQ(out.size(), 2u);
  EXPECT_EQ(d.stats().ascii_messages, 2u);
  EXPECT_EQ(d.stats().device_errors, 1u);
  EXPECT_EQ(d.stats().garbage_bytes, 0u);
  const auto reports = d.take_device_reports();
  ASSERT_EQ(reports.size(), 1u);
  EXPECT_EQ(reports[0], "$VNERR,12: Insufficient Baud Rate");
  EXPECT_TRUE(d.take_device_reports().empty());
  vn_expect_accounted(d);
}

TEST(VectornavDecoder, TimeStartupGoingBackIsARestartNotAGap) {
  VectornavDecoder d(100.0, false);
  std::vector<std::uint8_t> stream;
  vn_append(stream, vn_message(0));
  vn_append(stream, vn_message(1));
  vn_append(stream, vn_message(0, 100.0, 0.0));  // the unit started again: TimeStartup 0
  vn_append(stream, vn_message(1, 100.0, 0.0));
  std::vector<core::ImuSample> out;
  d.feed(stream, out);
  ASSERT_EQ(out.size(), 4u);
  EXPECT_LT(out[2].device_time_s, out[1].device_time_s);
  EXPECT_EQ(out[2].sequence, 0u);
  EXPECT_EQ(d.stats().device_restarts, 1u);
  EXPECT_EQ(d.stats().sequence_gaps, 0u);
  const auto reports = d.take_device_reports();
  ASSERT_EQ(reports.size(), 1u);
  EXPECT_NE(reports[0].find("device restarted"), std::string::npos) << reports[0];
}

TEST(VectornavDecoder, AfterRestartTheCutTailIsStartBytesAndNoGap) {
  VectornavDecoder d(100.0, false);
  std::vector<core::ImuSample> out;
  d.feed(vn_message(0), out);
  d.restart();
  const auto cut = vn_message(1);
  std::vector<std::uint8_t> stream(cut.begin() + 9, cut.end());  // the flush cut it
  vn_append(stream, vn_message(9));
  d.feed(stream, out);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(d.stats().start_bytes, cut.size() - 9);
  EXPECT_EQ(d.stats().garbage_bytes, 0u);
  EXPECT_EQ(d.stats().sequence_gaps, 0u);
  // Garbage after the first good message counts again.
  d.feed(std::vector<std::uint8_t>{0x01, 0x02}, out);
  EXPECT_EQ(d.stats().garbage_bytes, 2u);
  vn_expect_accounted(d);
}

TEST(VectornavDecoder, PrefersTheConfiguredOutputsWhenBothAreSent) {
  core::ImuSample s = vn_sample(3);
  const auto both = encode_binary_message(s, kCommonTimeStartup | kCommonAngularRate,
                                          kImuUncompGyro | kImuUncompAccel);
  std::vector<core::ImuSample> out;
  VectornavDecoder raw(100.0, false), comp(100.0, true);
  raw.feed(both, out);
  comp.feed(both, out);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_NEAR(out[0].gyro_dps.x(), s.gyro_dps.x(), 1e-5);
  EXPECT_NEAR(out[1].gyro_dps.x(), s.gyro_dps.x(), 1e-5);
  // A message without gyro is counted, not turned into a sample.
  VectornavDecoder d(100.0, false);
  d.feed(encode_binary_message(s, kCommonTimeStartup, kImuTemp), out);
  EXPECT_EQ(out.size(), 2u);
  EXPECT_EQ(d.stats().frames, 1u);
  EXPECT_EQ(d.stats().incomplete_frames, 1u);
}

TEST(VectornavDecoder, SeededRandomBytesKeepTheAccounting) {
  std::mt19937 rng(29);
  for (int run = 0; run < 200; ++run) {
    std::vector<std::uint8_t> stream;
    for (int i = 0; i < 6; ++i) {
      if (rng() % 2) vn_append(stream, vn_message(static_cast<std::uint32_t>(i)));
      const std::size_t junk = rng() % 12;
      for (std::size_t j = 0; j < junk; ++j) {
        const std::uint8_t pick[] = {kSync, '$',  0x05,
                                     0x00,  '\n', static_cast<std::uint8_t>(rng())};
        stream.push_back(pick[rng() % 6]);
      }
    }
    if (!stream.empty() && rng() % 2) stream[rng() % stream.size()] ^= 0x10;
    VectornavDecoder d(100.0, false);
    std::vector<core::ImuSample> out;
    for (std::size_t at = 0; at < stream.size();) {
      const std::size_t n = std::min<std::size_t>(1 + rng() % 30, stream.size() - at);
      d.feed(std::span(stream).subspan(at, n), out);
      at += n;
    }
    EXPECT_EQ(out.size() + d.stats().incomplete_frames, d.stats().frames);
    vn_expect_accounted(d);
  }
}

}  // namespace
}  // namespace calstand::drivers::vectornav
