#include "daemon/service/event_hub.hpp"

#include <gtest/gtest.h>

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

}  // namespace
