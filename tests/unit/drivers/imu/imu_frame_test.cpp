#include "drivers/imu_frame.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

namespace calstand::drivers {
namespace {

using Bytes = std::vector<std::uint8_t>;
using imu_frame::kFrameSize;

core::ImuSample make_sample(std::uint32_t sequence) {
  core::ImuSample s;
  s.sequence = sequence;
  s.device_time_s = 1000.0 + 0.005 * sequence;
  // Values exactly representable in f32, so the round trip can be compared for equality.
  s.gyro_dps = {0.5 * sequence, -1.25, 300.0};
  s.accel_mps2 = {9.75, -0.125, 0.0625 * (sequence % 64)};
  s.temperature_c = 25.5;
  return s;
}

Bytes frames(std::uint32_t first, std::uint32_t count) {
  Bytes out;
  for (std::uint32_t i = 0; i < count; ++i) {
    const Bytes f = encode_imu_frame(make_sample(first + i));
    out.insert(out.end(), f.begin(), f.end());
  }
  return out;
}

std::vector<core::ImuSample> decode_all(CalstandFrameDecoder& d, const Bytes& bytes) {
  std::vector<core::ImuSample> out;
  d.feed(bytes, out);
  return out;
}

void expect_same(const core::ImuSample& a, const core::ImuSample& b) {
  EXPECT_EQ(a.sequence, b.sequence);
  EXPECT_EQ(a.device_time_s, b.device_time_s);
  EXPECT_EQ(a.gyro_dps, b.gyro_dps);
  EXPECT_EQ(a.accel_mps2, b.accel_mps2);
  EXPECT_EQ(a.temperature_c, b.temperature_c);
}

void expect_bytes_accounted(const CalstandFrameDecoder& d) {
  const auto& c = d.stats();
  EXPECT_EQ(c.bytes_fed, c.frames * kFrameSize + c.garbage_bytes + d.buffered());
}

TEST(Crc16CcittFalse, MatchesTheStandardCheckValue) {
  const std::string check = "123456789";
  const Bytes bytes(check.begin(), check.end());
  EXPECT_EQ(crc16_ccitt_false(bytes), 0x29B1);
  EXPECT_EQ(crc16_ccitt_false({}), 0xFFFF);  // init value, no final XOR
}

TEST(EncodeImuFrame, LayoutIsAsDocumented) {
  const Bytes f = encode_imu_frame(make_sample(0x01020304));
  ASSERT_EQ(f.size(), 45u);
  EXPECT_EQ(f[0], 0xA5);
  EXPECT_EQ(f[1], 0x5A);
  EXPECT_EQ(f[2], 40);
  // Little-endian sequence counter.
  EXPECT_EQ(f[3], 0x04);
  EXPECT_EQ(f[6], 0x01);
  const std::uint16_t crc = crc16_ccitt_false(std::span(f).subspan(2, 41));
  EXPECT_EQ(f[43], crc & 0xFF);
  EXPECT_EQ(f[44], crc >> 8);
}

TEST(CalstandFrameDecoder, RoundTrip) {
  CalstandFrameDecoder d;
  const auto out = decode_all(d, frames(7, 3));
  ASSERT_EQ(out.size(), 3u);
  for (std::uint32_t i = 0; i < 3; ++i) expect_same(out[i], make_sample(7 + i));
  EXPECT_EQ(out[0].receive_time_s, 0.0);  // the caller stamps it
  EXPECT_EQ(d.stats().frames, 3u);
  EXPECT_EQ(d.stats().garbage_bytes, 0u);
  EXPECT_EQ(d.stats().resyncs, 0u);
  EXPECT_EQ(d.stats().sequence_gaps, 0u);
  EXPECT_EQ(d.counters().at("frames"), 3u);
  EXPECT_EQ(d.buffered(), 0u);
}

TEST(CalstandFrameDecoder, NarrowsToF32AsTheDeviceSends) {
  core::ImuSample s = make_sample(1);
  s.gyro_dps.x() = 0.1;
  CalstandFrameDecoder d;
  const auto out = decode_all(d, encode_imu_frame(s));
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].gyro_dps.x(), static_cast<double>(0.1f));
}

TEST(CalstandFrameDecoder, SkipsGarbageBeforeAndBetweenFrames) {
  // Garbage that includes sync look-alikes: a lone 0xA5, a full sync with an impossible
  // length, and a sync + valid length that runs into the next frame (CRC fails).
  const Bytes junk1{0x00, 0xA5, 0x13, 0xA5, 0x5A, 0xFF, 0x42};
  const Bytes junk2{0xA5, 0x5A, 40, 0x01, 0x02};
  Bytes stream = junk1;
  for (std::uint32_t i = 0; i < 3; ++i) {
    const Bytes f = encode_imu_frame(make_sample(i));
    stream.insert(stream.end(), f.begin(), f.end());
    if (i == 0) stream.insert(stream.end(), junk2.begin(), junk2.end());
  }
  CalstandFrameDecoder d;
  const auto out = decode_all(d, stream);
  ASSERT_EQ(out.size(), 3u);
  for (std::uint32_t i = 0; i < 3; ++i) expect_same(out[i], make_sample(i));
  EXPECT_EQ(d.stats().garbage_bytes, junk1.size() + junk2.size());
  EXPECT_EQ(d.stats().resyncs, 2u);
  EXPECT_EQ(d.stats().length_errors, 1u);
  EXPECT_EQ(d.stats().crc_errors, 1u);
  EXPECT_EQ(d.stats().sequence_gaps, 0u);
  expect_bytes_accounted(d);
}

TEST(CalstandFrameDecoder, CorruptedByteCostsOneFrameOnly) {
  Bytes stream = frames(10, 3);
  stream[kFrameSize + 20] ^= 0x10;  // inside the second frame's payload
  CalstandFrameDecoder d;
  const auto out = decode_all(d, stream);
  ASSERT_EQ(out.size(), 2u);
  expect_same(out[0], make_sample(10));
  expect_same(out[1], make_sample(12));
  EXPECT_EQ(d.stats().crc_errors, 1u);
  EXPECT_EQ(d.stats().garbage_bytes, kFrameSize);
  EXPECT_EQ(d.stats().sequence_gaps, 1u);
  expect_bytes_accounted(d);
}

TEST(CalstandFrameDecoder, CorruptedCrcOrLengthIsCounted) {
  Bytes stream = frames(0, 2);
  stream[kFrameSize - 1] ^= 0x01;  // first frame's CRC
  Bytes bad_length = frames(2, 1);
  bad_length[2] = 41;
  stream.insert(stream.end(), bad_length.begin(), bad_length.end());
  const Bytes tail = frames(3, 1);
  stream.insert(stream.end(), tail.begin(), tail.end());
  CalstandFrameDecoder d;
  const auto out = decode_all(d, stream);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[0].sequence, 1u);
  EXPECT_EQ(out[1].sequence, 3u);
  EXPECT_EQ(d.stats().crc_errors, 1u);
  EXPECT_EQ(d.stats().length_errors, 1u);
  expect_bytes_accounted(d);
}

TEST(CalstandFrameDecoder, TruncatedFrameCompletedByTheNextFeed) {
  const Bytes stream = frames(0, 2);
  CalstandFrameDecoder d;
  std::vector<core::ImuSample> out;
  for (std::size_t cut : {1u, 2u, 3u, 44u}) {
    SCOPED_TRACE(cut);
    out.clear();
    CalstandFrameDecoder fresh;
    EXPECT_EQ(fresh.feed(std::span(stream).first(kFrameSize + cut), out), 1u);
    EXPECT_EQ(fresh.buffered(), cut);
    EXPECT_EQ(fresh.feed(std::span(stream).subspan(kFrameSize + cut), out), 1u);
    ASSERT_EQ(out.size(), 2u);
    expect_same(out[1], make_sample(1));
    EXPECT_EQ(fresh.stats().garbage_bytes, 0u);
    expect_bytes_accounted(fresh);
  }
}

TEST(CalstandFrameDecoder, TruncatedFrameFollowedByAGoodOneLosesOnlyTheTruncated) {
  Bytes stream = frames(0, 1);
  stream.resize(30);  // the device reset mid-frame
  const Bytes rest = frames(1, 2);
  stream.insert(stream.end(), rest.begin(), rest.end());
  CalstandFrameDecoder d;
  const auto out = decode_all(d, stream);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[0].sequence, 1u);
  EXPECT_EQ(out[1].sequence, 2u);
  EXPECT_EQ(d.stats().garbage_bytes, 30u);
  expect_bytes_accounted(d);
}

TEST(CalstandFrameDecoder, ByteAtATime) {
  Bytes stream{0x11, 0xA5};
  const Bytes good = frames(100, 5);
  stream.insert(stream.end(), good.begin(), good.end());
  CalstandFrameDecoder d;
  std::vector<core::ImuSample> out;
  for (std::uint8_t b : stream) d.feed(std::span(&b, 1), out);
  ASSERT_EQ(out.size(), 5u);
  for (std::uint32_t i = 0; i < 5; ++i) expect_same(out[i], make_sample(100 + i));
  EXPECT_EQ(d.stats().garbage_bytes, 2u);
  expect_bytes_accounted(d);
}

TEST(CalstandFrameDecoder, SequenceGapIsCounted) {
  Bytes stream = frames(0, 3);
  const Bytes later = frames(10, 2);  // 3..9 lost on the wire
  stream.insert(stream.end(), later.begin(), later.end());
  CalstandFrameDecoder d;
  EXPECT_EQ(decode_all(d, stream).size(), 5u);
  EXPECT_EQ(d.stats().sequence_gaps, 1u);
  EXPECT_EQ(d.counters().at("sequence_gaps"), 1u);
}

TEST(CalstandFrameDecoder, SequenceWrapIsNotAGap) {
  CalstandFrameDecoder full_range;
  EXPECT_EQ(decode_all(full_range, frames(0xFFFFFFFEu, 4)).size(), 4u);  // ..FE, FF, 0, 1
  EXPECT_EQ(full_range.stats().sequence_gaps, 0u);

  // A device whose counter wraps at 1000: 999 -> 0 is fine, 999 -> 1000 is not what it sends.
  CalstandFrameDecoder mod1000(1000);
  Bytes stream = frames(998, 2);
  const Bytes wrapped = frames(0, 2);
  stream.insert(stream.end(), wrapped.begin(), wrapped.end());
  EXPECT_EQ(decode_all(mod1000, stream).size(), 4u);
  EXPECT_EQ(mod1000.stats().sequence_gaps, 0u);
  decode_all(mod1000, frames(5, 1));  // 1 -> 5
  EXPECT_EQ(mod1000.stats().sequence_gaps, 1u);
}

// Random garbage, bit flips and truncations of a valid stream, fed in random chunks. The
// decoder must not crash, must never produce a sample that was not sent, must recover every
// frame the damage did not touch, and its byte accounting must balance.
TEST(CalstandFrameDecoder, RandomisedCorpus) {
  for (std::uint32_t seed = 1; seed <= 40; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    std::mt19937 rng(seed);
    auto uniform = [&](int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); };

    std::map<std::uint32_t, Bytes> sent;  // sequence -> the frame as encoded
    std::set<std::uint32_t> intact;       // frames that reached the stream undamaged
    Bytes stream;
    // Any start: the decoder must assume nothing about the first sequence it sees.
    const auto first = static_cast<std::uint32_t>(rng());
    for (std::uint32_t i = 0; i < 300; ++i) {
      const std::uint32_t seq = first + i;
      Bytes f = encode_imu_frame(make_sample(seq));
      sent[seq] = f;
      bool damaged = false;
      switch (uniform(0, 9)) {
        case 0: {  // bit flips
          for (int k = uniform(1, 3); k > 0; --k) {
            f[static_cast<std::size_t>(uniform(0, kFrameSize - 1))] ^=
                static_cast<std::uint8_t>(1u << uniform(0, 7));
          }
          damaged = f != sent[seq];
          break;
        }
        case 1:  // truncated
          f.resize(static_cast<std::size_t>(uniform(0, kFrameSize - 1)));
          damaged = true;
          break;
        case 2: {  // garbage before the frame, biased towards sync look-alikes
          Bytes junk;
          for (int k = uniform(1, 60); k > 0; --k) {
            const int pick = uniform(0, 9);
            junk.push_back(pick == 0   ? 0xA5
                           : pick == 1 ? 0x5A
                           : pick == 2 ? 40
                                       : static_cast<std::uint8_t>(rng()));
          }
          stream.insert(stream.end(), junk.begin(), junk.end());
          break;
        }
        default:
          break;
      }
      if (!damaged) intact.insert(seq);
      stream.insert(stream.end(), f.begin(), f.end());
    }

    CalstandFrameDecoder d;
    std::vector<core::ImuSample> out;
    for (std::size_t pos = 0; pos < stream.size();) {
      const std::size_t n = std::min<std::size_t>(uniform(0, 100), stream.size() - pos);
      d.feed(std::span(stream).subspan(pos, n), out);
      pos += n;
    }

    std::set<std::uint32_t> seen;
    for (const auto& s : out) {
      const auto it = sent.find(s.sequence);
      ASSERT_NE(it, sent.end()) << "invented sequence " << s.sequence;
      EXPECT_EQ(encode_imu_frame(s), it->second) << "sample " << s.sequence << " was altered";
      EXPECT_TRUE(seen.insert(s.sequence).second) << "sample " << s.sequence << " twice";
    }
    for (std::uint32_t seq : intact) {
      EXPECT_TRUE(seen.count(seq)) << "intact frame " << seq << " lost";
    }
    const auto& c = d.stats();
    EXPECT_EQ(c.frames, out.size());
    EXPECT_EQ(c.bytes_fed, stream.size());
    expect_bytes_accounted(d);
    EXPECT_LT(d.buffered(), kFrameSize);
    EXPECT_LE(c.sequence_gaps, c.frames);
    // Every frame lost on the way shows up as at least one sequence gap or fault.
    if (intact.size() < sent.size()) {
      EXPECT_GT(c.sequence_gaps + c.crc_errors + c.garbage_bytes, 0u);
    }
  }
}

}  // namespace
}  // namespace calstand::drivers
