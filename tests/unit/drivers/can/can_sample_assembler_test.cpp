#include "drivers/can_sample_assembler.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "can_test_support.hpp"

namespace calstand::drivers {
namespace {

using Frames = std::vector<can_frame>;

class CanSampleAssemblerTest : public ::testing::Test {
 protected:
  CanSignalMap map_ = can_test::example_map();

  Frames frames_of(std::uint32_t sequence) const {
    return encode_sample(map_, can_test::sample(sequence, 10.0 + 0.005 * sequence));
  }
  /// Feeds `frames` and returns the sequences of the samples delivered.
  static std::vector<std::uint32_t> feed(CanSampleAssembler& a, const Frames& frames) {
    std::vector<core::ImuSample> out;
    for (const auto& f : frames) a.feed(f, out);
    std::vector<std::uint32_t> seqs;
    for (const auto& s : out) seqs.push_back(s.sequence);
    return seqs;
  }
  static void expect_frames_accounted(const CanSampleAssembler& a) {
    const auto& c = a.stats();
    EXPECT_EQ(c.frames, c.unknown_ids + c.bad_frames + c.bad_dlc + c.duplicate_frames +
                            c.late_frames + c.frames_used + c.frames_discarded +
                            a.pending_frames());
  }
};

TEST_F(CanSampleAssemblerTest, FramesOfASampleMayComeInAnyOrder) {
  CanSampleAssembler a(map_, 256, 200.0);
  Frames f = frames_of(5);
  std::swap(f[0], f[3]);
  std::swap(f[1], f[2]);
  EXPECT_EQ(feed(a, f), (std::vector<std::uint32_t>{5}));
  EXPECT_EQ(a.stats().samples, 1u);
  expect_frames_accounted(a);
}

TEST_F(CanSampleAssemblerTest, OtherIdsInterleavedAreIgnoredButCounted) {
  CanSampleAssembler a(map_, 256, 200.0);
  Frames stream;
  for (std::uint32_t seq = 0; seq < 3; ++seq) {
    for (const auto& f : frames_of(seq)) {
      stream.push_back(f);
      can_frame other{};
      other.can_id = 0x7DF;  // somebody else's traffic on the bus
      other.len = 8;
      stream.push_back(other);
    }
  }
  EXPECT_EQ(feed(a, stream), (std::vector<std::uint32_t>{0, 1, 2}));
  EXPECT_EQ(a.stats().unknown_ids, 12u);
  EXPECT_EQ(a.stats().sequence_gaps, 0u);
  expect_frames_accounted(a);
}

TEST_F(CanSampleAssemblerTest, AMissingFrameDropsThatSampleAndCountsAGap) {
  CanSampleAssembler a(map_, 256, 200.0);
  Frames stream = frames_of(0);
  Frames one = frames_of(1);
  one.erase(one.begin() + 2);  // 0x103 of sample 1 never comes
  stream.insert(stream.end(), one.begin(), one.end());
  const Frames two = frames_of(2);
  stream.insert(stream.end(), two.begin(), two.end());
  EXPECT_EQ(feed(a, stream), (std::vector<std::uint32_t>{0, 2}));
  EXPECT_EQ(a.stats().incomplete_samples, 1u);
  EXPECT_EQ(a.stats().frames_discarded, 3u);
  EXPECT_EQ(a.stats().sequence_gaps, 1u);
  expect_frames_accounted(a);
}

TEST_F(CanSampleAssemblerTest, DuplicatesAndLateFramesAreCountedNotUsed) {
  CanSampleAssembler a(map_, 256, 200.0);
  Frames f = frames_of(9);
  Frames stream{f[0], f[0], f[1], f[2], f[3], f[3]};  // one duplicate while pending, one late
  std::vector<core::ImuSample> out;
  for (const auto& fr : stream) a.feed(fr, out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(a.stats().duplicate_frames, 1u);
  EXPECT_EQ(a.stats().late_frames, 1u);
  // The first copy stands: values are those of sample 9.
  EXPECT_NEAR(out[0].gyro_dps.y(), can_test::sample(9, 0).gyro_dps.y(), 1e-5);
  expect_frames_accounted(a);
}

TEST_F(CanSampleAssemblerTest, ShortFramesAndRemoteOrErrorFramesAreRefused) {
  CanSampleAssembler a(map_, 256, 200.0);
  Frames f = frames_of(3);
  can_frame short_frame = f[1];
  short_frame.len = 7;  // the sequence byte is missing
  can_frame remote = f[1];
  remote.can_id |= CAN_RTR_FLAG;
  can_frame error = f[1];
  error.can_id |= CAN_ERR_FLAG;
  can_frame too_long = f[1];
  too_long.len = 9;
  can_frame bad_std_id = f[1];
  bad_std_id.can_id = 0x1000;  // more than 11 bits without CAN_EFF_FLAG
  Frames stream{f[0], short_frame, remote, error, too_long, bad_std_id};
  EXPECT_TRUE(feed(a, stream).empty());
  EXPECT_EQ(a.stats().bad_dlc, 1u);
  EXPECT_EQ(a.stats().bad_frames, 4u);
  // The sample still completes when the good frames come.
  EXPECT_EQ(feed(a, {f[1], f[2], f[3]}), (std::vector<std::uint32_t>{3}));
  expect_frames_accounted(a);
}

TEST_F(CanSampleAssemblerTest, ANewerSequenceDropsThePartialSampleAtDepthOne) {
  CanSampleAssembler a(map_, 256, 200.0);
  const Frames f4 = frames_of(4);
  const Frames f5 = frames_of(5);
  // A controller sending sample 5's first frame before sample 4's last (mailbox priority).
  const Frames stream{f4[0], f4[1], f4[2], f5[0], f4[3], f5[1], f5[2], f5[3]};
  EXPECT_EQ(feed(a, stream), (std::vector<std::uint32_t>{5}));
  EXPECT_EQ(a.stats().incomplete_samples, 1u);
  EXPECT_EQ(a.stats().late_frames, 1u);  // f4[3], after sample 4 was dropped
  expect_frames_accounted(a);
}

TEST_F(CanSampleAssemblerTest, DepthTwoToleratesOneSampleOfOverlap) {
  map_.reassembly_depth = 2;
  CanSampleAssembler a(map_, 256, 200.0);
  const Frames f4 = frames_of(4);
  const Frames f5 = frames_of(5);
  const Frames stream{f4[0], f4[1], f4[2], f5[0], f4[3], f5[1], f5[2], f5[3]};
  EXPECT_EQ(feed(a, stream), (std::vector<std::uint32_t>{4, 5}));
  EXPECT_EQ(a.stats().incomplete_samples, 0u);
  // Completing a newer sample drops the older partial one: output stays in sequence order.
  const Frames f6 = frames_of(6);
  const Frames f7 = frames_of(7);
  EXPECT_EQ(feed(a, {f6[0], f7[0], f7[1], f7[2], f7[3], f6[1]}), (std::vector<std::uint32_t>{7}));
  EXPECT_EQ(a.stats().incomplete_samples, 1u);
  EXPECT_EQ(a.stats().late_frames, 1u);
  expect_frames_accounted(a);
}

TEST_F(CanSampleAssemblerTest, SequenceWrapsAtTheModulusAndRestartsAreAccepted) {
  CanSampleAssembler a(map_, 200, 200.0);  // the device wraps at 200, inside the 8-bit field
  Frames stream;
  for (std::uint32_t seq : {198u, 199u, 0u, 1u}) {
    const Frames f = frames_of(seq);
    stream.insert(stream.end(), f.begin(), f.end());
  }
  EXPECT_EQ(feed(a, stream), (std::vector<std::uint32_t>{198, 199, 0, 1}));
  EXPECT_EQ(a.stats().sequence_gaps, 0u);
  // 250 cannot come from a counter wrapping at 200.
  EXPECT_TRUE(feed(a, frames_of(250)).empty());
  EXPECT_EQ(a.stats().bad_frames, 4u);
  // The device restarts at 100 (far behind 1 in modulo terms): accepted, one gap.
  EXPECT_EQ(feed(a, frames_of(100)), (std::vector<std::uint32_t>{100}));
  EXPECT_EQ(a.stats().sequence_gaps, 1u);
  expect_frames_accounted(a);
}

TEST_F(CanSampleAssemblerTest, DeviceTimeCounterIsUnwrapped) {
  CanSampleAssembler a(map_, 256, 200.0);
  // The u32 microsecond counter wraps at 4294.967296 s.
  const double wrap_s = 4294.967296;
  std::vector<core::ImuSample> out;
  for (std::uint32_t i = 0; i < 4; ++i) {
    const double t = wrap_s - 0.01 + 0.005 * i;  // crosses the wrap after the second sample
    for (const auto& f : encode_sample(map_, can_test::sample(i, t))) a.feed(f, out);
  }
  ASSERT_EQ(out.size(), 4u);
  for (std::uint32_t i = 0; i < 4; ++i) {
    EXPECT_NEAR(out[i].device_time_s, wrap_s - 0.01 + 0.005 * i, 1e-6) << "sample " << i;
  }
}

TEST_F(CanSampleAssemblerTest, WithoutDeviceTimeTheSequenceGivesTheTime) {
  const CanSignalMap map = CanSignalMap::from_json(can_test::float_map_json(), "m");
  CanSampleAssembler a(map, 256, 100.0);
  std::vector<core::ImuSample> out;
  for (std::uint32_t seq : {250u, 251u, 255u, 0u, 1u}) {  // a gap of 3 and a wrap
    for (const auto& f : encode_sample(map, can_test::sample(seq, 0.0))) a.feed(f, out);
  }
  ASSERT_EQ(out.size(), 5u);
  const std::vector<double> expected_s{0.0, 0.01, 0.05, 0.06, 0.07};
  for (std::size_t i = 0; i < out.size(); ++i)
    EXPECT_NEAR(out[i].device_time_s, expected_s[i], 1e-12);
  EXPECT_EQ(a.stats().sequence_gaps, 1u);
}

TEST_F(CanSampleAssemblerTest, NonFiniteValuesDropTheSample) {
  const CanSignalMap map = CanSignalMap::from_json(can_test::float_map_json(), "m");
  CanSampleAssembler a(map, 256, 100.0);
  core::ImuSample s = can_test::sample(1, 0.0);
  s.accel_mps2.y() = std::numeric_limits<double>::quiet_NaN();
  std::vector<core::ImuSample> out;
  for (const auto& f : encode_sample(map, s)) a.feed(f, out);
  EXPECT_TRUE(out.empty());
  EXPECT_EQ(a.stats().invalid_samples, 1u);
  expect_frames_accounted(a);
}

TEST_F(CanSampleAssemblerTest, ResetDropsPartialSamples) {
  CanSampleAssembler a(map_, 256, 200.0);
  const Frames f = frames_of(1);
  feed(a, {f[0], f[1]});
  EXPECT_EQ(a.pending_frames(), 2u);
  a.reset();
  EXPECT_EQ(a.pending_frames(), 0u);
  EXPECT_EQ(a.stats().incomplete_samples, 1u);
  expect_frames_accounted(a);
}

/// Garbage of every kind, alone and mixed into a valid stream: never a crash, every frame
/// accounted for, and every delivered sample one that was sent.
class CanSampleAssemblerCorpusTest : public CanSampleAssemblerTest,
                                     public ::testing::WithParamInterface<std::uint64_t> {};

TEST_P(CanSampleAssemblerCorpusTest, GarbageNeverCrashesAndEveryFrameIsCounted) {
  std::mt19937_64 rng(GetParam());
  for (std::size_t depth : {1u, 3u}) {
    map_.reassembly_depth = depth;
    CanSampleAssembler a(map_, 256, 200.0);
    std::vector<core::ImuSample> out;
    std::uint32_t sent = 0;
    for (int step = 0; step < 5000; ++step) {
      const auto kind = rng() % 4;
      if (kind == 0) {
        // A valid sample, frames possibly shuffled.
        Frames f = frames_of(sent % 256);
        ++sent;
        std::shuffle(f.begin(), f.end(), rng);
        for (const auto& fr : f) a.feed(fr, out);
        continue;
      }
      can_frame g{};
      std::uint8_t bytes[sizeof g];
      for (auto& b : bytes) b = static_cast<std::uint8_t>(rng());
      std::memcpy(&g, bytes, sizeof g);  // any id, flags, length and padding
      if (kind == 2) g.can_id = 0x101 + static_cast<canid_t>(rng() % 4);  // a known id
      if (kind == 3) g.len = static_cast<std::uint8_t>(rng() % 10);
      a.feed(g, out);
    }
    expect_frames_accounted(a);
    EXPECT_EQ(a.stats().samples, out.size());
    EXPECT_GT(a.stats().samples, 0u);
    // Whatever got through has values the map can express (no NaN, within field ranges).
    for (const auto& s : out) {
      ASSERT_TRUE(s.gyro_dps.allFinite() && s.accel_mps2.allFinite());
      ASSERT_LE(s.gyro_dps.cwiseAbs().maxCoeff(), 1342.2);
      ASSERT_LT(s.sequence, 256u);
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Seeds, CanSampleAssemblerCorpusTest,
                         ::testing::Values(1u, 42u, 20261122u));

}  // namespace
}  // namespace calstand::drivers
