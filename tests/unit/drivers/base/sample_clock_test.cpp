#include "drivers/sample_clock.hpp"

#include <gtest/gtest.h>

#include <random>

namespace calstand::drivers {
namespace {

// Samples every 10 ms of device time, delivered in bursts every 50 ms with a random extra
// delay: the stamps must recover the true instants, not the burst arrival times.
TEST(SampleClock, RecoversSampleInstantsFromBurstyArrival) {
  SampleClock clock;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(0.0, 0.004);
  const double offset = 1234.5;  // station time minus device time
  double worst_after_settle = 0.0;
  for (int i = 0; i < 2000; ++i) {
    const double device = 0.01 * i;
    // Sent when the burst's last sample (the fifth) has been taken.
    const double burst_end = 0.05 * std::floor(device / 0.05 + 1e-9) + 0.04;
    const double arrival = burst_end + offset + 0.0005 + jitter(rng);
    const double t = clock.stamp(device, arrival);
    EXPECT_LE(t, arrival);
    if (i > 100) worst_after_settle = std::max(worst_after_settle, std::abs(t - (device + offset)));
  }
  // The least-delayed sample of a burst waited 0.5 ms plus jitter; the estimate keeps the best.
  EXPECT_LT(worst_after_settle, 0.002);
}

TEST(SampleClock, FollowsADeviceClockRestart) {
  SampleClock clock;
  for (int i = 0; i < 100; ++i) clock.stamp(100.0 + 0.01 * i, 500.0 + 0.01 * i);
  // The device restarts: its clock begins again at 0.
  const double t = clock.stamp(0.0, 501.5);
  EXPECT_NEAR(t, 501.5, 1e-9);
  EXPECT_EQ(clock.restarts(), 1u);
  EXPECT_NEAR(clock.stamp(0.01, 501.51), 501.51, 1e-9);
}

TEST(SampleClock, StampsNeverGoBackwards) {
  SampleClock clock;
  double last = -1e9;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> delay(0.0, 0.02);
  double arrival = 0.0;
  for (int i = 0; i < 5000; ++i) {
    const double device = 0.001 * i;
    arrival = std::max(arrival, device + 10.0 + delay(rng));  // arrivals are in order
    const double t = clock.stamp(device, arrival);
    EXPECT_GE(t, last);
    last = t;
  }
}

TEST(SampleClock, TracksSlowDriftBetweenClocks) {
  // The device clock runs 100 ppm slow: after the window the offset follows it.
  SampleClock clock(/*window_s=*/5.0);
  double worst = 0.0;
  for (int i = 0; i < 60000; ++i) {
    const double device = 0.01 * i;
    const double station = device * (1.0 + 1e-4) + 3.0;
    const double t = clock.stamp(device, station + 0.001);
    if (i > 1000) worst = std::max(worst, std::abs(t - station));
  }
  EXPECT_LT(worst, 0.0015);  // 1 ms fixed delay + at most 5 s x 100 ppm lag
}

TEST(SampleClock, ALongDeliveryStallKeepsTheSampleInstants) {
  // 100 Hz, 20 ms link delay; then the link stalls for 6 s and delivers the backlog at once.
  SampleClock clock;
  for (int i = 0; i < 1000; ++i) clock.stamp(0.01 * i, 0.01 * i + 0.02);
  const double stall_end = 0.01 * 1600 + 0.02;
  for (int i = 1000; i < 1600; ++i) {
    const double t = clock.stamp(0.01 * i, stall_end);
    EXPECT_NEAR(t, 0.01 * i + 0.02, 1e-9) << i;  // not squashed onto the arrival time
  }
  EXPECT_EQ(clock.restarts(), 0u);
}

TEST(SampleClock, AReaderHeldUpLongerThanTheWindowInStationTimeKeepsTheInstantsAtTimeScale20) {
  // A station clock 20 times the wall's (sim-station --time-scale 20), a 200 Hz unit, 1 ms of
  // wall time on the link. Then a busy machine holds the reader up: for 30 s of station time
  // (1.5 s of wall time) every sample waits 5 s more, as a pty full of frames drains no faster
  // than they come. Seen in the command-set station test under load: the window of 10 station
  // seconds (0.5 s of wall time) forgot the link's own delay and took the hold-up for it, and
  // stamped a capture's window full of samples from the move before it.
  constexpr double kScale = 20.0;
  SampleClock clock = SampleClock::for_time_scale(kScale);
  const double link_s = 0.001 * kScale;
  const double offset = 100.0;
  double worst = 0.0;
  for (int i = 0; i < 200 * 60; ++i) {
    const double device = 0.005 * i;
    const bool held_up = device >= 10.0 && device < 40.0;
    const double arrival = device + offset + link_s + (held_up ? 5.0 : 0.0);
    worst = std::max(worst, std::abs(clock.stamp(device, arrival) - (device + offset + link_s)));
  }
  EXPECT_LT(worst, 1e-9);
  EXPECT_EQ(clock.restarts(), 0u);
}

TEST(SampleClock, ForTimeScaleOneIsTheLabClock) {
  // At the wall's own pace the window and the jump limit are the lab's: 10 s and 5 s.
  SampleClock clock = SampleClock::for_time_scale(1.0);
  for (int i = 0; i < 100; ++i) clock.stamp(0.01 * i, 50.0 + 0.01 * i);
  clock.stamp(0.99 + 6.0, 50.0 + 0.99 + 6.0);  // leaps 6 s ahead: a new epoch
  EXPECT_EQ(clock.restarts(), 1u);
}

}  // namespace
}  // namespace calstand::drivers
