#include "drivers/ride_out.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "../schema_error_field.hpp"
#include "core/error.hpp"

namespace calstand::drivers {
namespace {

/// A station clock whose sleep_until moves it there at once (a real clock that sleeps no wall
/// time), recording each wait: ride_out's waits and limit without any timing in the test.
class JumpingClock final : public core::Clock {
 public:
  double now_s() const override { return now_s_; }
  void sleep_until(double t_s) override {
    waits_s.push_back(t_s - now_s_);
    if (t_s > now_s_) now_s_ = t_s;
  }
  bool is_virtual() const override { return false; }
  std::vector<double> waits_s;

 private:
  double now_s_ = 100.0;
};

RideOutPolicy policy(double limit_s) {
  RideOutPolicy p;
  p.limit_s = limit_s;
  p.first_pause_s = 0.5;
  p.max_pause_s = 2.0;
  return p;
}

TEST(RideOut, ASuccessOrARefusalIsReturnedAtOnce) {
  JumpingClock clock;
  int calls = 0;
  EXPECT_TRUE(ride_out("table", clock, policy(5), [&] {
    ++calls;
    return Result::success();
  }));
  EXPECT_EQ(calls, 1);
  const auto refused = ride_out("table", clock, policy(5), [&] {
    ++calls;
    return Result::failure("controller refused ':D:R 1,500': ERR 201 over the limit");
  });
  EXPECT_FALSE(refused);
  EXPECT_FALSE(refused.link_lost);
  EXPECT_EQ(refused.message, "controller refused ':D:R 1,500': ERR 201 over the limit");
  EXPECT_EQ(calls, 2) << "a refusal is the controller's answer: never repeated";
  EXPECT_TRUE(clock.waits_s.empty());
}

TEST(RideOut, ALinkFailureIsRepeatedWithGrowingPausesUntilItWorks) {
  JumpingClock clock;
  int calls = 0;
  const auto r = ride_out("chamber", clock, policy(30), [&] {
    return ++calls < 5 ? Result::link_failure("chamber: link down (connection refused)")
                       : Result::success();
  });
  EXPECT_TRUE(r) << r.message;
  EXPECT_EQ(calls, 5);
  EXPECT_EQ(clock.waits_s, (std::vector<double>{0.5, 1.0, 2.0, 2.0}));
}

TEST(RideOut, PastThePolicysLimitTheFailureNamesTheDeviceAndHowLong) {
  JumpingClock clock;
  int calls = 0;
  const auto r = ride_out("table", clock, policy(5), [&] {
    ++calls;
    return Result::link_failure("'*idn?': no reply within 1000 ms");
  });
  EXPECT_FALSE(r);
  EXPECT_TRUE(r.link_lost);
  EXPECT_EQ(r.message,
            "table link down for 5.0 s (more than the policy's 5 s): '*idn?': no reply within "
            "1000 ms");
  // 0.5 + 1 + 2 and then only what is left of the 5 s: the last try is at the limit.
  EXPECT_EQ(clock.waits_s, (std::vector<double>{0.5, 1.0, 2.0, 1.5}));
  EXPECT_EQ(calls, 5);
}

TEST(RideOut, AVirtualClockGetsOneAttempt) {
  core::VirtualClock clock;
  int calls = 0;
  const auto r = ride_out("table", clock, policy(5), [&] {
    ++calls;
    return Result::link_failure("link down");
  });
  EXPECT_FALSE(r);
  EXPECT_EQ(calls, 1) << "nobody moves a virtual clock while we wait on it";
}

TEST(RideOut, APolicyThatCannotWorkIsRefusedNamingTheField) {
  auto p = policy(5);
  EXPECT_NO_THROW(p.validate("ride_out"));
  p.limit_s = -1;
  try {
    p.validate("ride_out");
    FAIL() << "accepted a negative limit";
  } catch (const core::InputError& e) {
    EXPECT_EQ(test::error_field(e), "ride_out.limit_s");
  }
  p = policy(5);
  p.max_pause_s = 0.1;
  EXPECT_THROW(p.validate("ride_out"), core::InputError);
}

TEST(RideOut, TheStationsPolicyGivesTheLimit) {
  core::FaultPolicy station;
  station.link_outage_s = 42.0;
  EXPECT_EQ(RideOutPolicy::from_policy(station).limit_s, 42.0);
}

TEST(RideOut, AFailureInContextKeepsItsLinkFlag) {
  const auto r = Result::link_failure("no reply").in("outer axis");
  EXPECT_EQ(r.message, "outer axis: no reply");
  EXPECT_TRUE(r.link_lost);
  EXPECT_FALSE(Result::failure("ERR 201").in("outer axis").link_lost);
  EXPECT_TRUE(Result::success().in("outer axis"));
}

}  // namespace
}  // namespace calstand::drivers
