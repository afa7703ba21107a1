#include "store/sample_codec.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <vector>

#include "store/error.hpp"

namespace calstand::store {
namespace {

std::vector<core::ImuSample> ramp(std::size_t n, double t0 = 1000.0, double dt = 0.001) {
  std::vector<core::ImuSample> out;
  for (std::size_t i = 0; i < n; ++i) {
    core::ImuSample s;
    s.receive_time_s = t0 + dt * static_cast<double>(i) + 1e-7;
    s.device_time_s = 5.0 + dt * static_cast<double>(i);
    s.sequence = 4294967290u + static_cast<std::uint32_t>(i);  // wraps within the chunk
    s.gyro_dps = {0.1 + 1e-3 * static_cast<double>(i), -100.0 / 3.0, 15.0 / 3600.0};
    s.accel_mps2 = {1e-4, -9.79361234567, 0.333333333333};
    s.temperature_c = 25.0 + 0.01 * static_cast<double>(i);
    out.push_back(s);
  }
  return out;
}

TEST(SampleCodec, CompactSizeIsHeaderPlus38BytesPerSample) {
  const auto samples = ramp(100);
  const auto blob = encode_chunk(samples, SampleEncoding::kCompact);
  EXPECT_EQ(blob.size(), 32u + 38u * 100u);
  EXPECT_EQ(std::memcmp(blob.data(), "CSMP", 4), 0);
  EXPECT_LT(static_cast<double>(blob.size()) / 100.0, 40.0);
}

TEST(SampleCodec, ExactSizeIsHeaderPlus76BytesPerSample) {
  EXPECT_EQ(encode_chunk(ramp(10), SampleEncoding::kExact).size(), 32u + 76u * 10u);
}

TEST(SampleCodec, CompactRoundTripIsWithinFloat32Resolution) {
  const auto samples = ramp(4096);
  const auto decoded = decode_chunk(encode_chunk(samples, SampleEncoding::kCompact));
  ASSERT_EQ(decoded.size(), samples.size());
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const auto& a = samples[i];
    const auto& b = decoded[i];
    EXPECT_EQ(b.sequence, a.sequence) << i;
    EXPECT_NEAR(b.receive_time_s, a.receive_time_s, 1e-6) << i;  // offsets <= 4 s
    EXPECT_NEAR(b.device_time_s, a.device_time_s, 1e-6) << i;
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(b.gyro_dps[k], a.gyro_dps[k], 1e-6 * std::abs(a.gyro_dps[k]) + 1e-12);
      EXPECT_NEAR(b.accel_mps2[k], a.accel_mps2[k], 1e-6 * std::abs(a.accel_mps2[k]) + 1e-12);
    }
    EXPECT_NEAR(b.temperature_c, a.temperature_c, 1e-5);
  }
  // The first time stamps are stored exactly in the header.
  EXPECT_EQ(decoded.front().receive_time_s, samples.front().receive_time_s);
}

TEST(SampleCodec, ExactRoundTripIsBitExact) {
  auto samples = ramp(300);
  samples[7].gyro_dps.x() = 0.1 + 0.2;  // not representable in float32
  samples[8].sequence = 0;              // sequence jump, fine in exact
  const auto decoded = decode_chunk(encode_chunk(samples, SampleEncoding::kExact));
  ASSERT_EQ(decoded.size(), samples.size());
  for (std::size_t i = 0; i < samples.size(); ++i) {
    EXPECT_EQ(decoded[i].receive_time_s, samples[i].receive_time_s);
    EXPECT_EQ(decoded[i].device_time_s, samples[i].device_time_s);
    EXPECT_EQ(decoded[i].sequence, samples[i].sequence);
    EXPECT_EQ(decoded[i].gyro_dps, samples[i].gyro_dps);
    EXPECT_EQ(decoded[i].accel_mps2, samples[i].accel_mps2);
    EXPECT_EQ(decoded[i].temperature_c, samples[i].temperature_c);
  }
}

TEST(SampleCodec, EncoderClosesChunksAtTheLimits) {
  ChunkEncoder enc(SampleEncoding::kCompact, ChunkLimits{3, 10.0});
  auto s = ramp(4, 0.0, 1.0);
  EXPECT_TRUE(enc.fits(s[0]));
  enc.append(s[0]);
  enc.append(s[1]);
  enc.append(s[2]);
  EXPECT_FALSE(enc.fits(s[3])) << "max_samples";
  enc.clear();
  enc.append(s[0]);
  core::ImuSample late = s[1];
  late.receive_time_s = s[0].receive_time_s + 10.5;
  EXPECT_FALSE(enc.fits(late)) << "receive time span";
  core::ImuSample jump = s[1];
  jump.sequence = s[0].sequence + 70000;
  EXPECT_FALSE(enc.fits(jump)) << "sequence offset beyond u16";
  core::ImuSample device_jump = s[1];
  device_jump.device_time_s = -1e6;
  EXPECT_FALSE(enc.fits(device_jump)) << "device time span";
  EXPECT_TRUE(enc.fits(s[1]));
  EXPECT_THROW(enc.append(jump), std::logic_error);

  ChunkEncoder exact(SampleEncoding::kExact, ChunkLimits{3, 10.0});
  exact.append(s[0]);
  EXPECT_TRUE(exact.fits(jump)) << "exact chunks store absolute values";
}

TEST(SampleCodec, CorruptBlobsAreStoreErrors) {
  auto blob = encode_chunk(ramp(5), SampleEncoding::kCompact);
  auto truncated = blob;
  truncated.pop_back();
  EXPECT_THROW(decode_chunk(truncated), StoreError);
  auto bad_magic = blob;
  bad_magic[0] = 'X';
  EXPECT_THROW(decode_chunk(bad_magic), StoreError);
  auto bad_encoding = blob;
  bad_encoding[5] = 9;
  EXPECT_THROW(decode_chunk(bad_encoding), StoreError);
  EXPECT_THROW(decode_chunk(std::vector<std::uint8_t>(10, 0)), StoreError);
  EXPECT_EQ(read_chunk_header(blob).count, 5u);
}

TEST(SampleCodec, HeaderLayoutMatchesTheDocumentation) {
  const auto samples = ramp(2);
  const auto blob = encode_chunk(samples, SampleEncoding::kCompact);
  EXPECT_EQ(blob[4], 1);  // version
  EXPECT_EQ(blob[5], 1);  // encoding
  std::uint32_t count = 0;
  std::uint32_t seq = 0;
  double t0 = 0.0;
  std::memcpy(&count, blob.data() + 8, 4);
  std::memcpy(&seq, blob.data() + 12, 4);
  std::memcpy(&t0, blob.data() + 16, 8);
  EXPECT_EQ(count, 2u);
  EXPECT_EQ(seq, samples[0].sequence);
  EXPECT_EQ(t0, samples[0].receive_time_s);
  // Second sample: u16 sequence offset at byte 8 of the sample.
  std::uint16_t dseq = 0;
  std::memcpy(&dseq, blob.data() + 32 + 38 + 8, 2);
  EXPECT_EQ(dseq, 1);
}

}  // namespace
}  // namespace calstand::store
