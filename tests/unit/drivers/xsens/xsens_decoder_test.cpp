// The MTi stream decoder, fed MTData2 packets built here item by item from MT0101P's layout
// (XDI u16, size u8, big-endian data), not by the emulator.
#include "drivers/xsens_decoder.hpp"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <limits>
#include <numbers>

namespace calstand::drivers::xsens {
namespace {

using Bytes = std::vector<std::uint8_t>;

void be(Bytes& out, std::uint64_t v, int n) {
  for (int i = n - 1; i >= 0; --i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}

struct Packet {
  std::uint16_t counter = 0;
  std::uint32_t ticks = 0;
  std::array<double, 3> gyro_rps{0.1, -0.2, 0.3};
  std::array<double, 3> accel{0.5, -0.25, 9.75};
  std::optional<double> temperature = 25.5;
  bool with_counter = true;
};

// A float32 packet, written out by hand.
Bytes packet(const Packet& p) {
  Bytes d;
  if (p.with_counter) {
    be(d, 0x1020, 2);
    d.push_back(2);
    be(d, p.counter, 2);
  }
  be(d, 0x1060, 2);
  d.push_back(4);
  be(d, p.ticks, 4);
  be(d, 0x4020, 2);
  d.push_back(12);
  for (double v : p.accel) be(d, std::bit_cast<std::uint32_t>(static_cast<float>(v)), 4);
  be(d, 0x8020, 2);
  d.push_back(12);
  for (double v : p.gyro_rps) be(d, std::bit_cast<std::uint32_t>(static_cast<float>(v)), 4);
  if (p.temperature) {
    be(d, 0x0810, 2);
    d.push_back(4);
    be(d, std::bit_cast<std::uint32_t>(static_cast<float>(*p.temperature)), 4);
  }
  return encode_message(mid::kMtData2, d);
}

Bytes stream_of(std::uint16_t first, int count, std::uint32_t ticks0 = 1000,
                std::uint32_t step = 100) {
  Bytes out;
  for (int i = 0; i < count; ++i) {
    Packet p;
    p.counter = static_cast<std::uint16_t>(first + i);
    p.ticks = ticks0 + step * static_cast<std::uint32_t>(i);
    const Bytes b = packet(p);
    out.insert(out.end(), b.begin(), b.end());
  }
  return out;
}

void append(Bytes& a, const Bytes& b) { a.insert(a.end(), b.begin(), b.end()); }

TEST(XsensDecoder, DecodesAPacketInDegreesPerSecondAndItsDeviceTime) {
  XsensDecoder d;
  std::vector<core::ImuSample> out;
  Packet p;
  p.counter = 7;
  p.ticks = 123456;
  ASSERT_EQ(d.feed(packet(p), out), 1u);
  const auto& s = out[0];
  EXPECT_EQ(s.sequence, 7u);
  EXPECT_DOUBLE_EQ(s.device_time_s, 12.3456);
  EXPECT_NEAR(s.gyro_dps.x(), 0.1 * 180.0 / std::numbers::pi, 1e-5);
  EXPECT_NEAR(s.gyro_dps.y(), -0.2 * 180.0 / std::numbers::pi, 1e-5);
  EXPECT_NEAR(s.gyro_dps.z(), 0.3 * 180.0 / std::numbers::pi, 1e-5);
  EXPECT_DOUBLE_EQ(s.accel_mps2.z(), 9.75);
  EXPECT_DOUBLE_EQ(s.accel_mps2.y(), -0.25);
  EXPECT_DOUBLE_EQ(s.temperature_c, 25.5);
  EXPECT_EQ(s.receive_time_s, 0.0);
}

TEST(XsensDecoder, AnySplitGivesTheSameSamples) {
  const Bytes bytes = stream_of(0, 20);
  XsensDecoder whole;
  std::vector<core::ImuSample> a;
  whole.feed(bytes, a);
  for (std::size_t chunk : {1u, 2u, 3u, 7u, 64u}) {
    XsensDecoder split;
    std::vector<core::ImuSample> b;
    for (std::size_t at = 0; at < bytes.size(); at += chunk) {
      split.feed(std::span(bytes).subspan(at, std::min(chunk, bytes.size() - at)), b);
    }
    ASSERT_EQ(b.size(), 20u) << chunk;
    for (std::size_t i = 0; i < b.size(); ++i) {
      EXPECT_EQ(b[i].sequence, a[i].sequence);
      EXPECT_EQ(b[i].device_time_s, a[i].device_time_s);
    }
    EXPECT_EQ(split.stats().garbage_bytes, 0u);
  }
}

TEST(XsensDecoder, CountsADroppedPacketAsASequenceGapButNotTheCountersWrap) {
  Bytes bytes = stream_of(65533, 3);     // 65533, 65534, 65535
  append(bytes, stream_of(0, 2, 1300));  // wraps to 0: no gap
  append(bytes, stream_of(3, 1, 1500));  // 2 lost
  XsensDecoder d;
  std::vector<core::ImuSample> out;
  EXPECT_EQ(d.feed(bytes, out), 6u);
  EXPECT_EQ(d.stats().sequence_gaps, 1u);
}

TEST(XsensDecoder, ABadChecksumCostsOneByteAndTheNextPacketIsKept) {
  Bytes bad = packet(Packet{});
  bad[10] ^= 0x40;
  Bytes bytes = {0x01, 0x02, 0x03};  // garbage first
  append(bytes, bad);
  append(bytes, stream_of(1, 2));
  XsensDecoder d;
  std::vector<core::ImuSample> out;
  EXPECT_EQ(d.feed(bytes, out), 2u);
  EXPECT_EQ(d.stats().crc_errors, 1u);
  EXPECT_EQ(d.stats().garbage_bytes, 3u + bad.size());
  EXPECT_EQ(d.stats().resyncs, 1u);
  EXPECT_EQ(d.counters().at("crc_errors"), 1u);
  EXPECT_EQ(d.stats().bytes_fed, d.stats().message_bytes + d.stats().garbage_bytes +
                                     d.stats().start_bytes + d.buffered());
}

TEST(XsensDecoder, APacketStartingInsideABadCandidateIsFound) {
  // A preamble and BID whose length swallows the following real packet: its checksum fails,
  // and the real packet inside must still come out.
  Bytes bytes = {0xFA, 0xFF, 0x36, 0x10};
  append(bytes, stream_of(5, 1));
  bytes.resize(bytes.size() + 20, 0x00);
  XsensDecoder d;
  std::vector<core::ImuSample> out;
  d.feed(bytes, out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].sequence, 5u);
  EXPECT_EQ(d.stats().crc_errors, 1u);
}

TEST(XsensDecoder, AnImpossibleExtendedLengthIsALengthErrorAndDoesNotStall) {
  Bytes bytes = {0xFA, 0xFF, 0x36, 0xFF, 0xFF, 0xFF};  // 65535 bytes announced
  append(bytes, stream_of(0, 1));
  XsensDecoder d;
  std::vector<core::ImuSample> out;
  EXPECT_EQ(d.feed(bytes, out), 1u);
  EXPECT_EQ(d.stats().length_errors, 1u);
}

TEST(XsensDecoder, UnwrapsSampleTimeFineAcrossItsWrap) {
  Bytes bytes = stream_of(0, 1, 4294967000u);
  append(bytes, stream_of(1, 1, 200u));  // 496 ticks later, across 2^32
  XsensDecoder d;
  std::vector<core::ImuSample> out;
  d.feed(bytes, out);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_NEAR(out[1].device_time_s - out[0].device_time_s, 0.0496, 1e-9);
  EXPECT_TRUE(d.take_device_reports().empty());
}

TEST(XsensDecoder, ADeviceRestartShowsAsTimeGoingBackAndIsReported) {
  Bytes bytes = stream_of(100, 3, 5000000);
  append(bytes, stream_of(0, 2, 0));  // counter and time back to 0
  XsensDecoder d;
  std::vector<core::ImuSample> out;
  d.feed(bytes, out);
  ASSERT_EQ(out.size(), 5u);
  EXPECT_LT(out[3].device_time_s, out[2].device_time_s);
  EXPECT_DOUBLE_EQ(out[3].device_time_s, 0.0);
  EXPECT_EQ(d.stats().sequence_gaps, 0u);  // a new run of the counter
  const auto reports = d.take_device_reports();
  ASSERT_EQ(reports.size(), 1u);
  EXPECT_NE(reports[0].find("restarted"), std::string::npos);
  EXPECT_TRUE(d.take_device_reports().empty());
}

TEST(XsensDecoder, WakeUpAndErrorMessagesAreReportedInTheDevicesWords) {
  Bytes bytes = encode_message(mid::kWakeUp);
  const Bytes code{0x29};
  append(bytes, encode_message(mid::kError, code));
  append(bytes, encode_message(mid::kGoToMeasurementAck));
  append(bytes, stream_of(0, 1));
  XsensDecoder d;
  std::vector<core::ImuSample> out;
  EXPECT_EQ(d.feed(bytes, out), 1u);
  const auto reports = d.take_device_reports();
  ASSERT_EQ(reports.size(), 2u);
  EXPECT_NE(reports[0].find("WakeUp"), std::string::npos);
  EXPECT_EQ(reports[1], "Error 0x29: data overflow (more data than the baud rate carries)");
  EXPECT_EQ(d.stats().messages, 3u);
  EXPECT_EQ(d.stats().device_errors, 1u);
  EXPECT_EQ(d.stats().garbage_bytes, 0u);
}

TEST(XsensDecoder, EachSampleCarriesTheLatestTemperature) {
  Bytes bytes;
  Packet p;
  p.temperature.reset();
  append(bytes, packet(p));  // none yet: held back, not delivered with a NaN
  p.counter = 1;
  p.temperature = 30.25;
  append(bytes, packet(p));
  p.counter = 2;
  p.temperature.reset();
  append(bytes, packet(p));
  XsensDecoder d;
  std::vector<core::ImuSample> out;
  d.feed(bytes, out);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[0].sequence, 1u);
  EXPECT_DOUBLE_EQ(out[0].temperature_c, 30.25);
  EXPECT_EQ(out[1].sequence, 2u);
  EXPECT_DOUBLE_EQ(out[1].temperature_c, 30.25);
  EXPECT_EQ(d.stats().awaiting_temperature, 1u);
  EXPECT_EQ(d.stats().sequence_gaps, 0u);
  // A reader restart keeps the temperature: the next packet without one still has a sample.
  d.restart();
  p.counter = 9;
  d.feed(packet(p), out);
  ASSERT_EQ(out.size(), 3u);
  EXPECT_DOUBLE_EQ(out[2].temperature_c, 30.25);
}

TEST(XsensDecoder, APacketWithoutItsCounterGivesNoSample) {
  Packet p;
  p.with_counter = false;
  XsensDecoder d;
  std::vector<core::ImuSample> out;
  EXPECT_EQ(d.feed(packet(p), out), 0u);
  EXPECT_EQ(d.stats().incomplete_packets, 1u);
  // An item overrunning its packet.
  Bytes data{0x10, 0x20, 0x09, 0x00};
  EXPECT_EQ(d.feed(encode_message(mid::kMtData2, data), out), 0u);
  EXPECT_EQ(d.stats().packet_errors, 1u);
}

TEST(XsensDecoder, APacketWithANonFiniteValueIsDropped) {
  Packet p;
  p.gyro_rps[1] = std::numeric_limits<double>::quiet_NaN();
  Bytes bytes = packet(p);
  append(bytes, stream_of(1, 1));
  XsensDecoder d;
  std::vector<core::ImuSample> out;
  EXPECT_EQ(d.feed(bytes, out), 1u);
  EXPECT_EQ(out[0].sequence, 1u);
  EXPECT_EQ(d.stats().invalid_samples, 1u);
}

TEST(XsensDecoder, ReadsEachItemInItsOwnPrecision) {
  for (const int precision_bits : {0, 1, 2, 3}) {
    const auto precision = static_cast<std::uint16_t>(precision_bits);
    Bytes d;
    be(d, 0x1020, 2);
    d.push_back(2);
    be(d, 9, 2);
    be(d, 0x1060, 2);
    d.push_back(4);
    be(d, 10000, 4);
    const auto p = static_cast<Precision>(precision);
    for (std::uint16_t id :
         {std::uint16_t(0x4020 | precision | 0x4), std::uint16_t(0x8020 | precision | 0x4)}) {
      be(d, id, 2);
      d.push_back(static_cast<std::uint8_t>(3 * value_size(p)));
      for (double v : {1.5, -0.75, 0.125}) put_value(d, v, p);
    }
    be(d, 0x0810 | precision, 2);
    d.push_back(static_cast<std::uint8_t>(value_size(p)));
    put_value(d, -12.5, p);
    XsensDecoder dec;
    std::vector<core::ImuSample> out;
    ASSERT_EQ(dec.feed(encode_message(mid::kMtData2, d), out), 1u) << precision;
    EXPECT_DOUBLE_EQ(out[0].accel_mps2.x(), 1.5);
    EXPECT_DOUBLE_EQ(out[0].accel_mps2.y(), -0.75);  // as sent: no axis conversion
    EXPECT_NEAR(out[0].gyro_dps.z(), 0.125 * 180.0 / std::numbers::pi, 1e-12);
    EXPECT_DOUBLE_EQ(out[0].temperature_c, -12.5);
    EXPECT_DOUBLE_EQ(out[0].device_time_s, 1.0);
  }
}

TEST(XsensDecoder, AfterRestartTheCutPacketsTailIsStartBytesNotGarbage) {
  XsensDecoder d;
  std::vector<core::ImuSample> out;
  const Bytes first = stream_of(0, 2);
  d.feed(first, out);
  d.restart();
  const Bytes cut = packet(Packet{});
  Bytes bytes(cut.begin() + 5, cut.end());  // the flush cut a packet
  append(bytes, stream_of(40, 2, 9000));    // no gap against 1: a fresh start
  d.feed(bytes, out);
  EXPECT_EQ(out.size(), 4u);
  EXPECT_EQ(d.stats().start_bytes, cut.size() - 5);
  EXPECT_EQ(d.stats().garbage_bytes, 0u);
  EXPECT_EQ(d.stats().resyncs, 0u);
  EXPECT_EQ(d.stats().sequence_gaps, 0u);
  // Later garbage counts again.
  const Bytes junk{0x00, 0x11};
  d.feed(junk, out);
  EXPECT_EQ(d.stats().garbage_bytes, 2u);
}

}  // namespace
}  // namespace calstand::drivers::xsens
