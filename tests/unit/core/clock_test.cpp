#include "core/clock.hpp"

#include <gtest/gtest.h>

namespace calstand::core {
namespace {

TEST(VirtualClock, AdvancesOnlyWhenTold) {
  VirtualClock clock(10.0);
  EXPECT_DOUBLE_EQ(clock.now_s(), 10.0);
  clock.sleep_until(100.0);  // waiting never moves virtual time
  EXPECT_DOUBLE_EQ(clock.now_s(), 10.0);
  clock.advance(2.5);
  EXPECT_DOUBLE_EQ(clock.now_s(), 12.5);
  clock.advance(-1.0);
  EXPECT_DOUBLE_EQ(clock.now_s(), 12.5);
  clock.advance_to(11.0);
  EXPECT_DOUBLE_EQ(clock.now_s(), 12.5);
  clock.advance_to(20.0);
  EXPECT_DOUBLE_EQ(clock.now_s(), 20.0);
  EXPECT_TRUE(clock.is_virtual());
}

TEST(SteadyClock, IsMonotonicAndSleeps) {
  SteadyClock clock;
  const double t0 = clock.now_s();
  clock.sleep_until(t0 + 0.02);
  const double t1 = clock.now_s();
  EXPECT_GE(t1, t0 + 0.02);
  EXPECT_FALSE(clock.is_virtual());
}

TEST(ClockInterface, BothClocksServeTheSameCode) {
  VirtualClock virtual_clock;
  SteadyClock steady_clock;
  auto elapsed_since = [](const Clock& c, double t0) { return c.now_s() - t0; };
  virtual_clock.advance(3600.0);
  EXPECT_DOUBLE_EQ(elapsed_since(virtual_clock, 0.0), 3600.0);
  EXPECT_LT(elapsed_since(steady_clock, 0.0), 60.0);
}

}  // namespace
}  // namespace calstand::core
