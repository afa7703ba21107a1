#include "drivers/can_sample_streamer.hpp"

#include <gtest/gtest.h>

#include <chrono>

#include "can_test_support.hpp"
#include "drivers/can_imu.hpp"
#include "drivers/socketpair_can.hpp"

namespace calstand::drivers {
namespace {

using namespace std::chrono_literals;

/// A simulated IMU streaming into a CanImu through a socket pair, as sim-station would on vcan.
class CanSampleStreamerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    connection_ = CanImuConnection::from_json({{"interface", "vcan0"},
                                               {"map_file", can_test::example_map_path()},
                                               {"sample_rate_hz", 200}},
                                              "imus[0].connection");
    auto [device_end, driver_end] = SocketPairCan::make_pair();
    streamer_ = std::make_unique<CanSampleStreamer>(std::move(device_end), connection_.map);
    imu_ = std::make_unique<CanImu>("imu-can", connection_, std::move(driver_end), clock_);
    ASSERT_TRUE(imu_->configure());
    ASSERT_TRUE(imu_->activate());
  }
  void TearDown() override { imu_->deactivate(); }

  core::SteadyClock clock_;
  CanImuConnection connection_;
  std::unique_ptr<CanSampleStreamer> streamer_;
  std::unique_ptr<CanImu> imu_;
};

TEST_F(CanSampleStreamerTest, PushedSamplesReachTheDriverInOrder) {
  for (std::uint32_t i = 0; i < 500; ++i) streamer_->push(can_test::sample(i % 256, 0.005 * i));
  const auto got = can_test::collect(*imu_, 500);
  ASSERT_EQ(got.size(), 500u);
  for (std::uint32_t i = 0; i < 500; ++i) ASSERT_EQ(got[i].sequence, i % 256) << "sample " << i;
  EXPECT_EQ(streamer_->frames_sent(), 2000u);
  EXPECT_EQ(streamer_->frames_dropped(), 0u);
  EXPECT_EQ(imu_->fault_counters().at("sequence_gaps"), 0u);
}

TEST_F(CanSampleStreamerTest, SilenceAndInjectedFaultsShowAtTheDriver) {
  streamer_->push(can_test::sample(0, 0.0));
  streamer_->set_silent(true);
  streamer_->push(can_test::sample(1, 0.005));  // lost: the IMU stopped talking
  streamer_->set_silent(false);
  can_frame short_frame = encode_sample(connection_.map, can_test::sample(2, 0.01))[0];
  short_frame.len = 2;
  streamer_->inject(short_frame);
  streamer_->push(can_test::sample(2, 0.01));
  const auto got = can_test::collect(*imu_, 2);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[1].sequence, 2u);
  EXPECT_EQ(streamer_->frames_dropped(), 4u);  // the silent sample's 4 frames
  const auto counters = imu_->fault_counters();
  EXPECT_EQ(counters.at("sequence_gaps"), 1u);
  EXPECT_EQ(counters.at("bad_dlc"), 1u);
}

TEST_F(CanSampleStreamerTest, AFullQueueDropsTheOldestFrames) {
  auto [device_end, unread_end] = SocketPairCan::make_pair();
  // A queue of 3 frames and nobody reading fast enough: frames are lost, push never blocks.
  CanSampleStreamer tiny(std::move(device_end), connection_.map, 3);
  const auto start = std::chrono::steady_clock::now();
  for (std::uint32_t i = 0; i < 2000; ++i) tiny.push(can_test::sample(i % 256, 0.005 * i));
  EXPECT_LT(std::chrono::steady_clock::now() - start, 2s);
  EXPECT_GT(tiny.frames_dropped(), 0u);
  EXPECT_LE(tiny.frames_sent() + tiny.frames_dropped(), 8000u);  // none counted twice
}

}  // namespace
}  // namespace calstand::drivers
