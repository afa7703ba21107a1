#include "daemon/service/event_hub.hpp"

#include <gtest/gtest.h>

#include <optional>
#include <thread>

namespace {

using calstand::daemon::service::EventHub;
using namespace std::chrono_literals;

TEST(EventHub, ReadersGetWhatCameAfterTheirLastMessageInOrder) {
  EventHub hub;
  hub.publish("step", {{"step", 0}});
  const auto start = hub.last_seq();
  hub.publish("step", {{"step", 1}});
  hub.publish("run", {{"state", "completed"}});
  const auto got = hub.wait_after(start, 0ms);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].data["step"], 1);
  EXPECT_EQ(got[1].type, "run");
  EXPECT_EQ(got[1].seq, hub.last_seq());
  EXPECT_TRUE(hub.wait_after(hub.last_seq(), 0ms).empty());
}

TEST(EventHub, AReaderTooFarBehindSkipsTheOldestInsteadOfBlockingPublishers) {
  EventHub hub(3);
  for (int i = 0; i < 10; ++i) hub.publish("telemetry", {{"i", i}});
  const auto got = hub.wait_after(0, 0ms);
  ASSERT_EQ(got.size(), 3u);
  EXPECT_EQ(got.front().data["i"], 7);
}

TEST(EventHub, AWaitingReaderWakesOnPublishAndOnClose) {
  EventHub hub;
  std::thread publisher([&] {
    std::this_thread::sleep_for(20ms);
    hub.publish("fault", {{"message", "x"}});
  });
  const auto got = hub.wait_after(0, 5s);
  publisher.join();
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].type, "fault");

  std::thread closer([&] {
    std::this_thread::sleep_for(20ms);
    hub.close();
  });
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_TRUE(hub.wait_after(hub.last_seq(), 5s).empty());
  closer.join();
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 4s);
  EXPECT_TRUE(hub.closed());
}

TEST(EventHub, EventIdsNameTheProcessAndTheSequence) {
  EventHub hub(4096, "1700000000000");
  hub.publish("step", {});
  hub.publish("step", {});
  hub.publish("step", {});
  EXPECT_EQ(hub.event_id(2), "1700000000000-2");
  // Ours: resume after that message.
  ASSERT_TRUE(hub.replay_after("1700000000000-2").has_value());
  EXPECT_EQ(hub.replay_after("1700000000000-2")->after_seq, 2u);
  EXPECT_FALSE(hub.replay_after("1700000000000-2")->restarted);
  EXPECT_EQ(hub.replay_after("1700000000000-0")->after_seq, 0u);
  // An earlier process of the daemon (restarted since): everything this one kept is news, and
  // what the old one had not sent is lost.
  ASSERT_TRUE(hub.replay_after("1600000000000-900").has_value());
  EXPECT_EQ(hub.replay_after("1600000000000-900")->after_seq, 0u);
  EXPECT_TRUE(hub.replay_after("1600000000000-900")->restarted);
  // Not ours, or in the future: start live.
  EXPECT_FALSE(hub.replay_after("1700000000000-4").has_value());
  EXPECT_FALSE(hub.replay_after("abc-1").has_value());
  EXPECT_FALSE(hub.replay_after("17").has_value());
  EXPECT_FALSE(hub.replay_after("1700000000000-").has_value());
  EXPECT_FALSE(hub.replay_after("1700000000000-2x").has_value());
  EXPECT_FALSE(hub.replay_after("").has_value());
  EXPECT_FALSE(hub.replay_after("-5").has_value());
}

}  // namespace
