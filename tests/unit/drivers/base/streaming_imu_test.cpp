#include "drivers/streaming_imu.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <string>
#include <thread>

namespace calstand::drivers {
namespace {

using namespace std::chrono_literals;

/// A protocol-free StreamingImu: each step delivers the samples the test asked for, and the
/// link is lost or comes back when the test says.
class FakeStreamingImu final : public StreamingImu {
 public:
  explicit FakeStreamingImu(core::Clock& clock) : StreamingImu("fake", clock, {"extra_fault"}) {}
  ~FakeStreamingImu() override { stop_reader(); }

  double sample_rate_hz() const override { return 10.0; }  // buffer: the 10000-sample floor
  std::uint64_t sequence_modulus() const override { return 1u << 16; }

  std::atomic<bool> can_open{true};
  std::atomic<int> to_send{0};
  std::atomic<bool> link_up{true};
  std::atomic<bool> can_reopen{false};
  std::atomic<int> reopen_attempts{0};
  std::atomic<int> summaries{0};

 private:
  void open_link(bool) override {
    if (!can_open) throw std::runtime_error("fake: no such device");
  }
  bool reopen_link() override {
    ++reopen_attempts;
    link_up = can_reopen.load();
    return link_up;
  }
  Result read_step() override {
    if (!link_up) return Result::failure("fake: unplugged");
    std::vector<core::ImuSample> samples(static_cast<std::size_t>(to_send.exchange(0)));
    for (auto& s : samples) s.sequence = next_++;
    deliver(samples);
    publish_protocol_counters({{"frames", next_}});
    std::this_thread::sleep_for(1ms);  // as a read waiting for data would
    return Result::success();
  }
  void summarise_faults(double, double) override { ++summaries; }

  std::uint32_t next_ = 0;  // reader thread only
};

template <typename Done>
bool wait_until(Done done) {
  for (int i = 0; i < 300 && !done(); ++i) std::this_thread::sleep_for(10ms);
  return done();
}

bool has_event(const std::vector<DeviceEvent>& events, const std::string& text) {
  for (const auto& e : events) {
    if (e.message.find(text) != std::string::npos) return true;
  }
  return false;
}

TEST(StreamingImu, CountersMergeTheBasesTheSubclasssAndTheProtocols) {
  core::SteadyClock clock;
  FakeStreamingImu imu(clock);
  const auto before = imu.fault_counters();
  for (const char* key : {"read_errors", "reopens", "buffer_overflows", "extra_fault"}) {
    ASSERT_TRUE(before.count(key)) << key;
    EXPECT_EQ(before.at(key), 0u) << key;
  }
  ASSERT_TRUE(imu.configure());
  ASSERT_TRUE(imu.activate());
  imu.to_send = 3;
  ASSERT_TRUE(wait_until([&] {
    return imu.fault_counters().count("frames") && imu.fault_counters().at("frames") == 3;
  }));
  ASSERT_TRUE(imu.deactivate());
  EXPECT_GE(imu.summaries.load(), 1);  // the last summary when the reader stops
}

TEST(StreamingImu, AnUndrainedBufferKeepsTheNewestAndCountsTheRest) {
  core::SteadyClock clock;
  FakeStreamingImu imu(clock);
  ASSERT_TRUE(imu.configure());
  ASSERT_TRUE(imu.activate());
  imu.to_send = 10005;
  ASSERT_TRUE(wait_until([&] { return imu.fault_counters().at("buffer_overflows") == 5; }));
  const auto got = imu.poll();
  ASSERT_EQ(got.size(), 10000u);
  EXPECT_EQ(got.front().sequence, 5u);
  EXPECT_EQ(got.back().sequence, 10004u);
  EXPECT_TRUE(imu.poll().empty());
}

TEST(StreamingImu, ALostLinkIsAnErrorUntilItIsReopened) {
  core::SteadyClock clock;
  FakeStreamingImu imu(clock);
  ASSERT_TRUE(imu.configure());
  ASSERT_TRUE(imu.activate());
  imu.link_up = false;
  ASSERT_TRUE(wait_until([&] { return imu.state() == DeviceState::kError; }));
  EXPECT_EQ(imu.fault_counters().at("read_errors"), 1u);
  imu.can_reopen = true;
  ASSERT_TRUE(wait_until([&] { return imu.state() == DeviceState::kActive; }));
  EXPECT_EQ(imu.fault_counters().at("reopens"), 1u);
  const auto events = imu.take_events();
  EXPECT_TRUE(has_event(events, "link lost: fake: unplugged"));
  EXPECT_TRUE(has_event(events, "link back"));
  imu.to_send = 1;
  ASSERT_TRUE(wait_until([&] { return imu.fault_counters().at("frames") == 1; }));
  ASSERT_EQ(imu.poll().size(), 1u);
}

TEST(StreamingImu, DeactivateStopsARetryingReaderPromptly) {
  core::SteadyClock clock;
  FakeStreamingImu imu(clock);
  ASSERT_TRUE(imu.configure());
  ASSERT_TRUE(imu.activate());
  imu.link_up = false;
  // 0.1 + 0.2 + 0.4 s of backoff: the reader is now in a 0.8 s wait.
  ASSERT_TRUE(wait_until([&] { return imu.reopen_attempts.load() >= 4; }));
  EXPECT_LE(imu.reopen_attempts.load(), 5);  // backing off, not spinning
  const auto start = std::chrono::steady_clock::now();
  ASSERT_TRUE(imu.deactivate());
  EXPECT_LT(std::chrono::steady_clock::now() - start, 200ms);
  EXPECT_EQ(imu.state(), DeviceState::kError);  // deactivate() does not clear an error
}

TEST(StreamingImu, ALinkThatCannotBeOpenedIsAnErrorWithItsReason) {
  core::SteadyClock clock;
  FakeStreamingImu imu(clock);
  EXPECT_FALSE(imu.activate());  // not configured
  imu.can_open = false;
  const Result r = imu.configure();
  EXPECT_FALSE(r);
  EXPECT_EQ(r.message, "fake: no such device");
  EXPECT_EQ(imu.state(), DeviceState::kError);
  imu.can_open = true;
  EXPECT_TRUE(imu.configure());
  EXPECT_EQ(imu.state(), DeviceState::kInactive);
}

}  // namespace
}  // namespace calstand::drivers
