#include "daemon/engine_command.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <string>
#include <thread>
#include <vector>

namespace calstand::daemon {
namespace {

TEST(EngineCommandQueue, TakesEverythingInTheOrderItWasPushed) {
  EngineCommandQueue queue;
  EXPECT_TRUE(queue.take_all().empty());
  queue.push({EngineCommand::Kind::kPause, true, std::nullopt, "", "bob"});
  queue.push({EngineCommand::Kind::kAbort, false, std::nullopt, "smoke", "alice"});
  const auto taken = queue.take_all();
  ASSERT_EQ(taken.size(), 2u);
  EXPECT_EQ(taken[0].kind, EngineCommand::Kind::kPause);
  EXPECT_TRUE(taken[0].immediate);
  EXPECT_EQ(taken[1].kind, EngineCommand::Kind::kAbort);
  EXPECT_EQ(taken[1].why, "smoke");
  EXPECT_TRUE(queue.take_all().empty());  // taken once
  queue.push({EngineCommand::Kind::kResume, false, std::nullopt, "", "bob"});
  queue.clear();
  EXPECT_TRUE(queue.take_all().empty());
}

// Two threads push while a third takes: nothing is lost or doubled, and each thread's
// requests come out in the order it pushed them.
TEST(EngineCommandQueue, KeepsEachPushersOrderUnderConcurrency) {
  EngineCommandQueue queue;
  constexpr int kEach = 2000;
  std::atomic<int> done{0};
  auto pusher = [&](const std::string& who) {
    for (int i = 0; i < kEach; ++i) {
      queue.push({EngineCommand::Kind::kSkip, false, static_cast<std::size_t>(i), "", who});
    }
    ++done;
  };
  std::thread a(pusher, "a"), b(pusher, "b");
  std::vector<EngineCommand> taken;
  for (;;) {
    const bool pushers_done = done == 2;  // read before taking: then this take is the last
    const auto batch = queue.take_all();
    taken.insert(taken.end(), batch.begin(), batch.end());
    if (pushers_done) break;
  }
  a.join();
  b.join();
  ASSERT_EQ(taken.size(), 2u * kEach);
  std::size_t next_a = 0, next_b = 0;
  for (const auto& c : taken) {
    std::size_t& next = c.who == "a" ? next_a : next_b;
    ASSERT_EQ(*c.step, next) << c.who;
    ++next;
  }
  EXPECT_EQ(next_a, static_cast<std::size_t>(kEach));
  EXPECT_EQ(next_b, static_cast<std::size_t>(kEach));
}

}  // namespace
}  // namespace calstand::daemon
