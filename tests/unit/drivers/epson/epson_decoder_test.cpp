#include <gtest/gtest.h>

#include <random>

#include "drivers/epson_wire.hpp"

namespace calstand::drivers::epson {
namespace {

using Bytes = std::vector<std::uint8_t>;

Options decoder_options(double rate_hz, int width_bits, CountStep step = CountStep::kBase) {
  WireFormatSettings s;
  s.sample_rate_hz = rate_hz;
  s.options = {{"model", "G366PDG0"}, {"width_bits", width_bits}};
  s.where = "test.epson";
  Options o = Options::from_settings(s);
  o.count_step = step;
  return o;
}

// Frame k of a stream at 100 Hz (COUNT steps 20 at the 2000 Sps base rate).
BurstFields frame_fields(int k, std::uint16_t count) {
  BurstFields f;
  f.flags = kFlagNdMask;
  f.temperature = 256 * k;
  f.gyro[0] = 66 * k * 65536;
  f.gyro[1] = -66 * 65536;
  f.gyro[2] = k;
  f.accel[0] = 0;
  f.accel[1] = 4000 * 65536;
  f.accel[2] = -k;
  f.count = count;
  return f;
}

Bytes stream(int first, int n, std::uint16_t count0, int step = 20) {
  Bytes out;
  for (int k = first; k < first + n; ++k) {
    const auto b =
        encode_burst(frame_fields(k, static_cast<std::uint16_t>(count0 + (k - first) * step)), 32);
    out.insert(out.end(), b.begin(), b.end());
  }
  return out;
}

std::vector<core::ImuSample> feed_split(Decoder& d, const Bytes& bytes, std::size_t chunk) {
  std::vector<core::ImuSample> out;
  for (std::size_t i = 0; i < bytes.size(); i += chunk) {
    d.feed(std::span(bytes).subspan(i, std::min(chunk, bytes.size() - i)), out);
  }
  return out;
}

TEST(EpsonDecoder, AnySplitGivesTheSameScaledSamples) {
  const Bytes bytes = stream(0, 30, 100);
  for (std::size_t chunk : {1u, 2u, 7u, 35u, 36u, 37u, 1000u}) {
    Decoder d(decoder_options(100, 32));
    const auto got = feed_split(d, bytes, chunk);
    ASSERT_EQ(got.size(), 30u) << chunk;
    for (int k = 0; k < 30; ++k) {
      const auto& s = got[static_cast<std::size_t>(k)];
      EXPECT_NEAR(s.gyro_dps.x(), k, 1e-9);
      EXPECT_NEAR(s.gyro_dps.y(), -1.0, 1e-12);
      EXPECT_NEAR(s.accel_mps2.y(), 9.80665, 1e-12);
      EXPECT_NEAR(s.temperature_c, 25.0 + k / 65536.0, 1e-12);
      EXPECT_NEAR(s.device_time_s, (100 + 20 * k) / 2000.0, 1e-12);
      EXPECT_EQ(s.sequence, static_cast<std::uint32_t>((100 + 20 * k) / 20));
      EXPECT_EQ(s.receive_time_s, 0.0);
    }
    EXPECT_EQ(d.counters().at("frames"), 30u);
    EXPECT_EQ(d.counters().at("sequence_gaps"), 0u);
    EXPECT_EQ(d.counters().at("garbage_bytes"), 0u);
  }
}

TEST(EpsonDecoder, CountWrapsIntoMonotonicDeviceTime) {
  Decoder d(decoder_options(100, 32));
  std::vector<core::ImuSample> out;
  d.feed(stream(0, 10, 65500), out);  // wraps between frames 1 and 2
  ASSERT_EQ(out.size(), 10u);
  for (std::size_t i = 1; i < out.size(); ++i) {
    EXPECT_NEAR(out[i].device_time_s - out[i - 1].device_time_s, 0.01, 1e-12);
    EXPECT_EQ(out[i].sequence, out[i - 1].sequence + 1);
  }
  EXPECT_EQ(d.counters().at("sequence_gaps"), 0u);
  EXPECT_TRUE(d.take_device_reports().empty());
}

TEST(EpsonDecoder, OutputCountStepCountsOnePerFrame) {
  Decoder d(decoder_options(100, 32, CountStep::kOutput));
  std::vector<core::ImuSample> out;
  d.feed(stream(0, 5, 7, 1), out);
  ASSERT_EQ(out.size(), 5u);
  EXPECT_NEAR(out[4].device_time_s - out[0].device_time_s, 0.04, 1e-12);
  EXPECT_EQ(d.counters().at("sequence_gaps"), 0u);
}

TEST(EpsonDecoder, ACounterSteppingTheOtherWayIsReportedOnce) {
  Decoder d(decoder_options(100, 32, CountStep::kBase));
  std::vector<core::ImuSample> out;
  d.feed(stream(0, 40, 0, 1), out);  // one count per frame at 100 Hz: an output-rate counter
  const auto reports = d.take_device_reports();
  ASSERT_EQ(reports.size(), 1u);
  EXPECT_NE(reports[0].find("COUNT steps by 1 per frame, not 20"), std::string::npos) << reports[0];
  Decoder right(decoder_options(100, 32, CountStep::kBase));
  right.feed(stream(0, 40, 0, 20), out);
  EXPECT_TRUE(right.take_device_reports().empty());
}

TEST(EpsonDecoder, DroppedFramesAreSequenceGaps) {
  Bytes bytes = stream(0, 3, 0);
  const Bytes later = stream(5, 3, 100);  // frames 3 and 4 lost
  bytes.insert(bytes.end(), later.begin(), later.end());
  Decoder d(decoder_options(100, 32));
  std::vector<core::ImuSample> out;
  d.feed(bytes, out);
  ASSERT_EQ(out.size(), 6u);
  EXPECT_EQ(d.counters().at("sequence_gaps"), 1u);
  EXPECT_EQ(out[3].sequence, out[2].sequence + 3);
  EXPECT_NEAR(out[3].device_time_s, 0.05, 1e-12);
}

TEST(EpsonDecoder, BadChecksumCostsOneByteAndTheNextFrameSurvives) {
  Bytes bytes = stream(0, 3, 0);
  bytes[36 + 9] ^= 0x40;  // corrupt frame 1's gyro
  Decoder d(decoder_options(100, 32));
  std::vector<core::ImuSample> out;
  d.feed(bytes, out);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(d.counters().at("crc_errors"), 1u);
  EXPECT_EQ(d.counters().at("sequence_gaps"), 1u);
  EXPECT_EQ(d.counters().at("garbage_bytes"), 36u);
  EXPECT_EQ(d.counters().at("resyncs"), 1u);
}

TEST(EpsonDecoder, GarbageAndAWrongLengthAreCountedNotDecoded) {
  Bytes bytes{0x00, 0x0D, 0x80, 0x01, 0x02};  // a header with no frame behind it
  const Bytes good = stream(0, 2, 0);
  bytes.insert(bytes.end(), good.begin(), good.end());
  Decoder d(decoder_options(100, 32));
  std::vector<core::ImuSample> out;
  d.feed(bytes, out);
  EXPECT_EQ(out.size(), 2u);
  EXPECT_EQ(d.counters().at("garbage_bytes"), 5u);
  EXPECT_GE(d.counters().at("length_errors"), 1u);

  // A 16-bit stream fed to a 32-bit decoder is all length errors, never a sample.
  Decoder wrong(decoder_options(100, 32));
  Bytes sixteen;
  for (int k = 0; k < 20; ++k) {
    const auto b = encode_burst(frame_fields(k, static_cast<std::uint16_t>(k * 20)), 16);
    sixteen.insert(sixteen.end(), b.begin(), b.end());
  }
  out.clear();
  wrong.feed(sixteen, out);
  EXPECT_TRUE(out.empty());
  EXPECT_GT(wrong.counters().at("length_errors") + wrong.counters().at("crc_errors"), 0u);
}

TEST(EpsonDecoder, CounterBackToZeroIsADeviceRestart) {
  Bytes bytes = stream(0, 5, 30000);
  const Bytes after = stream(0, 3, 0);
  bytes.insert(bytes.end(), after.begin(), after.end());
  Decoder d(decoder_options(100, 32));
  std::vector<core::ImuSample> out;
  d.feed(bytes, out);
  ASSERT_EQ(out.size(), 8u);
  EXPECT_LT(out[5].device_time_s, out[4].device_time_s);
  EXPECT_NEAR(out[5].device_time_s, 0.0, 1e-12);
  EXPECT_EQ(d.counters().at("device_restarts"), 1u);
  const auto reports = d.take_device_reports();
  ASSERT_EQ(reports.size(), 1u);
  EXPECT_NE(reports[0].find("COUNT went back from 30080 to 0"), std::string::npos);
}

TEST(EpsonDecoder, AfterRestartTheCutFrameIsStartBytesAndNoGap) {
  Decoder d(decoder_options(100, 32));
  std::vector<core::ImuSample> out;
  d.feed(stream(0, 2, 0), out);
  d.restart();
  const Bytes later = stream(10, 2, 200);
  Bytes cut(later.begin() + 1, later.end());  // the first frame lost its header to the flush
  d.feed(cut, out);
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(d.counters().at("start_bytes"), 35u);
  EXPECT_EQ(d.counters().at("garbage_bytes"), 0u);
  EXPECT_EQ(d.counters().at("sequence_gaps"), 0u);
  EXPECT_GT(out[2].device_time_s, out[1].device_time_s);
}

TEST(EpsonDecoder, ErrorFlagIsReportedOncePerRun) {
  Bytes bytes;
  for (int k = 0; k < 6; ++k) {
    BurstFields f = frame_fields(k, static_cast<std::uint16_t>(20 * k));
    if (k >= 1 && k <= 3) f.flags |= kFlagEa;
    const auto b = encode_burst(f, 32);
    bytes.insert(bytes.end(), b.begin(), b.end());
  }
  Decoder d(decoder_options(100, 32));
  std::vector<core::ImuSample> out;
  d.feed(bytes, out);
  EXPECT_EQ(out.size(), 6u);
  EXPECT_EQ(d.counters().at("error_flag_frames"), 3u);
  const auto reports = d.take_device_reports();
  ASSERT_EQ(reports.size(), 2u);
  EXPECT_NE(reports[0].find("EA (all error) flag set"), std::string::npos);
  EXPECT_NE(reports[1].find("cleared"), std::string::npos);
}

TEST(EpsonDecoder, WithoutAModelFramesAreCountedButNotScaled) {
  WireFormatSettings s;
  s.sample_rate_hz = 100;
  s.where = "x";
  Decoder d(Options::from_settings(s));
  std::vector<core::ImuSample> out;
  d.feed(stream(0, 2, 0), out);
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(d.counters().at("frames_without_model"), 2u);
  EXPECT_EQ(d.take_device_reports().size(), 1u);
  d.identified({"G366PDG0", "E0001234", "VERSION 0x0105"});
  d.feed(stream(2, 2, 40), out);
  EXPECT_EQ(out.size(), 2u);
}

TEST(EpsonDecoder, RandomBytesNeverMakeASampleAndEveryByteIsAccounted) {
  std::mt19937 rng(29);
  Decoder d(decoder_options(100, 16));
  Bytes noise(20000);
  for (auto& b : noise) b = static_cast<std::uint8_t>(rng());
  std::vector<core::ImuSample> out;
  feed_split(d, noise, 13);
  const auto c = d.counters();
  EXPECT_LE(c.at("frames"), 2u);  // a random 22-byte frame passes with odds ~2^-24 per header
  EXPECT_GE(c.at("garbage_bytes") + c.at("frames") * 22 + 21, 20000u);
}

}  // namespace
}  // namespace calstand::drivers::epson
