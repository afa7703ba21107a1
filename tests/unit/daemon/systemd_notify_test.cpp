#include "daemon/service/systemd_notify.hpp"

#include <gtest/gtest.h>
#include <spdlog/logger.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>

#include "../../support/notify_peer.hpp"
#include "daemon/service/journal_sink.hpp"
#include "daemon/service/log_fields.hpp"
#include "daemon/service/service_heartbeat.hpp"

namespace calstand::daemon::service {
namespace {

using calstand::testing::DatagramPeer;
using calstand::testing::parse_journal_datagram;
using calstand::testing::parse_notify_message;
using std::chrono::milliseconds;

std::string socket_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() /
          ("calstand-notify-" + std::to_string(::getpid()) + "-" + name))
      .string();
}

TEST(SystemdNotifier, SendsEachMessageAsOneDatagramToAPathSocket) {
  DatagramPeer systemd(socket_path("path"));
  const SystemdNotifier notifier(systemd.address(), std::nullopt);
  ASSERT_TRUE(notifier.enabled());
  EXPECT_TRUE(notifier.notify("READY=1\nSTATUS=idle"));
  const auto got = systemd.next(milliseconds(2000));
  ASSERT_TRUE(got);
  const auto m = parse_notify_message(*got);
  EXPECT_EQ(m.at("READY"), "1");
  EXPECT_EQ(m.at("STATUS"), "idle");
}

TEST(SystemdNotifier, ReachesAnAbstractSocket) {
  DatagramPeer systemd("@calstand-notify-" + std::to_string(::getpid()));
  const SystemdNotifier notifier(systemd.address(), std::nullopt);
  EXPECT_TRUE(notifier.notify("WATCHDOG=1"));
  const auto got = systemd.next(milliseconds(2000));
  ASSERT_TRUE(got);
  EXPECT_EQ(parse_notify_message(*got).at("WATCHDOG"), "1");
}

TEST(SystemdNotifier, FromTheEnvironmentTakesSocketAndWatchdogAndClearsThem) {
  DatagramPeer systemd(socket_path("env"));
  ::setenv("NOTIFY_SOCKET", systemd.address().c_str(), 1);
  ::setenv("WATCHDOG_USEC", "3000000", 1);
  ::setenv("WATCHDOG_PID", std::to_string(::getpid()).c_str(), 1);
  const SystemdNotifier notifier = SystemdNotifier::from_environment();
  ASSERT_TRUE(notifier.enabled());
  ASSERT_TRUE(notifier.watchdog());
  EXPECT_EQ(notifier.watchdog()->count(), 3000000);
  // A program the daemon starts must not speak for it.
  EXPECT_EQ(std::getenv("NOTIFY_SOCKET"), nullptr);
  EXPECT_EQ(std::getenv("WATCHDOG_USEC"), nullptr);
  EXPECT_EQ(std::getenv("WATCHDOG_PID"), nullptr);
  EXPECT_TRUE(notifier.notify("READY=1"));
  EXPECT_TRUE(systemd.next(milliseconds(2000)));
}

TEST(SystemdNotifier, AWatchdogMeantForAnotherProcessIsNotOurs) {
  DatagramPeer systemd(socket_path("other-pid"));
  ::setenv("NOTIFY_SOCKET", systemd.address().c_str(), 1);
  ::setenv("WATCHDOG_USEC", "3000000", 1);
  ::setenv("WATCHDOG_PID", std::to_string(::getpid() + 1).c_str(), 1);
  const SystemdNotifier notifier = SystemdNotifier::from_environment();
  EXPECT_TRUE(notifier.enabled());
  EXPECT_FALSE(notifier.watchdog());
}

TEST(SystemdNotifier, WithoutNotifySocketItSendsNothing) {
  ::unsetenv("NOTIFY_SOCKET");
  const SystemdNotifier notifier = SystemdNotifier::from_environment();
  EXPECT_FALSE(notifier.enabled());
  EXPECT_FALSE(notifier.notify("READY=1"));
}

TEST(SystemdNotifier, RefusesASocketThatIsNeitherPathNorAbstractName) {
  EXPECT_THROW(SystemdNotifier("relative/notify", std::nullopt), std::system_error);
}

TEST(StatusLine, SaysWhatTheStationDoes) {
  LiveSnapshot s;
  EXPECT_EQ(status_line(s), "idle");
  s.waiting = "disk full: 12.0 MB free";
  EXPECT_EQ(status_line(s), "waiting: disk full: 12.0 MB free");
  s.held = 4;
  EXPECT_EQ(status_line(s), "held: run 4 waits for an operator's resume or abort");
  s.run = 12;
  s.progress.state = RunState::kRunning;
  s.progress.step = 2;  // the third step
  s.progress.steps = 24;
  s.progress.phase = "capturing";
  EXPECT_EQ(status_line(s), "running run 12 step 3/24 (capturing)");
  s.progress.state = RunState::kPaused;
  EXPECT_EQ(status_line(s), "paused run 12 step 3/24");
}

// The heartbeat pings at half the watchdog interval, never more often, and sends the status
// only when it changes.
TEST(ServiceHeartbeat, PingsEveryHalfWatchdogAndSendsTheStatusWhenItChanges) {
  DatagramPeer systemd(socket_path("heartbeat"));
  const SystemdNotifier notifier(systemd.address(), std::chrono::microseconds(200000));
  std::atomic<bool> running{false};
  ServiceHeartbeat beat(notifier, [&] {
    LiveSnapshot s;
    if (running) {
      s.run = 3;
      s.progress.step = 1;
      s.progress.steps = 5;
      s.progress.state = RunState::kRunning;
    }
    return s;
  });
  const auto start = std::chrono::steady_clock::now();
  std::thread engine([&] {
    while (std::chrono::steady_clock::now() - start < milliseconds(1000)) {
      if (std::chrono::steady_clock::now() - start > milliseconds(500)) running = true;
      beat.beat();
      std::this_thread::sleep_for(milliseconds(2));
    }
  });
  const auto got = systemd.collect(milliseconds(1200));
  engine.join();
  std::vector<std::chrono::steady_clock::time_point> pings;
  std::vector<std::string> statuses;
  for (const auto& [at, d] : got) {
    const auto m = parse_notify_message(d);
    if (m.count("WATCHDOG")) pings.push_back(at);
    if (m.count("STATUS")) statuses.push_back(m.at("STATUS"));
  }
  ASSERT_GE(pings.size(), 5u) << "1 s of beats at a 100 ms ping period";
  EXPECT_LE(pings.size(), 11u);
  ASSERT_EQ(statuses.size(), 2u);
  EXPECT_EQ(statuses[0], "idle");
  EXPECT_EQ(statuses[1], "running run 3 step 2/5");
}

TEST(JournalMessage, CarriesTheThreadsRunStepAndDevice) {
  const auto plain = parse_journal_datagram(journal_message("calstandd", 6, "started"));
  EXPECT_EQ(plain.at("MESSAGE"), "started");
  EXPECT_EQ(plain.at("PRIORITY"), "6");
  EXPECT_EQ(plain.at("SYSLOG_IDENTIFIER"), "calstandd");
  EXPECT_EQ(plain.count("RUN"), 0u);
  const ScopedLogFields run(LogFields{12, std::nullopt, std::nullopt});
  {
    const ScopedLogFields device(LogFields{std::nullopt, 3, std::string("imu0")});
    const auto m = parse_journal_datagram(journal_message("calstandd", 4, "link lost"));
    EXPECT_EQ(m.at("RUN"), "12");
    EXPECT_EQ(m.at("STEP"), "3");
    EXPECT_EQ(m.at("DEVICE"), "imu0");
  }
  // The scope's end puts back what was there: the run, no step, no device.
  const auto after = parse_journal_datagram(journal_message("calstandd", 6, "next"));
  EXPECT_EQ(after.at("RUN"), "12");
  EXPECT_EQ(after.count("STEP"), 0u);
  EXPECT_EQ(after.count("DEVICE"), 0u);
}

TEST(JournalStream, StderrIsTheJournalOnlyWhenJournalStreamNamesIt) {
  struct stat st {};
  ASSERT_EQ(::fstat(STDERR_FILENO, &st), 0);
  const std::string self = std::to_string(st.st_dev) + ":" + std::to_string(st.st_ino);
  ::setenv("JOURNAL_STREAM", self.c_str(), 1);
  EXPECT_TRUE(stderr_is_journal());
  // Inherited from a parent whose stderr was the journal, while ours is elsewhere.
  const std::string other = std::to_string(st.st_dev) + ":" + std::to_string(st.st_ino + 1);
  ::setenv("JOURNAL_STREAM", other.c_str(), 1);
  EXPECT_FALSE(stderr_is_journal());
  ::setenv("JOURNAL_STREAM", "not-a-stream", 1);
  EXPECT_FALSE(stderr_is_journal());
  ::unsetenv("JOURNAL_STREAM");
  EXPECT_FALSE(stderr_is_journal());
}

TEST(JournalSink, SendsEachLineAsADatagramWithAMultiLineMessageFramed) {
  DatagramPeer journald(socket_path("journal"));
  auto sink = std::make_shared<JournalSink>("calstandd", journald.address());
  spdlog::logger logger("test", sink);
  logger.warn("table: link lost\nretrying");
  const auto got = journald.next(milliseconds(2000));
  ASSERT_TRUE(got);
  EXPECT_NE(got->find("MESSAGE\n"), std::string::npos) << "a message with a newline is framed";
  const auto m = parse_journal_datagram(*got);
  EXPECT_EQ(m.at("MESSAGE"), "table: link lost\nretrying");
  EXPECT_EQ(m.at("PRIORITY"), "4");
  EXPECT_EQ(m.at("SYSLOG_IDENTIFIER"), "calstandd");
}

}  // namespace
}  // namespace calstand::daemon::service
