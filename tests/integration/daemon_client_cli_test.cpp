// The `calstand` client commands (submit, status, watch, pause, resume, abort, skip) against
// calstandd running as a process, as an operator uses them.
#include <gtest/gtest.h>

#include <future>
#include <thread>

#include "cli_runner.hpp"
#include "daemon_test_support.hpp"

namespace {

using calstand::testing::DaemonProcess;

class DaemonClientCli : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = calstand::testing::fresh_dir("client-cli");
    daemon_ = std::make_unique<DaemonProcess>(dir_ + "/station.db", dir_ + "/calstandd.log");
    ASSERT_GT(daemon_->port(), 0);
    setenv("CALSTAND_TOKEN", calstand::testing::kTestToken, 1);
  }
  void TearDown() override { unsetenv("CALSTAND_TOKEN"); }
  // `calstand ARGS --daemon 127.0.0.1:PORT`.
  calstand::testing::Result calstand(const std::string& args) {
    return calstand::testing::run(args + " --daemon 127.0.0.1:" + std::to_string(daemon_->port()));
  }
  std::string dir_;
  std::unique_ptr<DaemonProcess> daemon_;
};

TEST_F(DaemonClientCli, SubmitWatchAndStatus) {
  const auto submitted = calstand("submit six-position --set capture_s=5 --operator alice");
  ASSERT_EQ(submitted.exit_code, 0) << submitted.out;
  EXPECT_EQ(submitted.out, "run 1 queued\n");

  const auto watched = calstand("watch 1");
  EXPECT_EQ(watched.exit_code, 0) << watched.out;
  EXPECT_NE(watched.out.find("run 1 completed: 12/12 steps"), std::string::npos) << watched.out;

  const auto one = calstand("status 1 --json");
  ASSERT_EQ(one.exit_code, 0) << one.out;
  EXPECT_EQ(nlohmann::json::parse(one.out)["status"], "completed");
  const auto station = calstand("status");
  ASSERT_EQ(station.exit_code, 0) << station.out;
  EXPECT_NE(station.out.find("station sim-station"), std::string::npos) << station.out;
  EXPECT_NE(station.out.find("idle"), std::string::npos) << station.out;
}

// A run has one JSON shape: `calstand runs --json` and `calstand show --json` on the daemon's
// database give what GET /runs, /runs/{id}/steps and /runs/{id}/events give.
TEST_F(DaemonClientCli, RunsAndShowJsonHaveTheShapesOfTheApi) {
  ASSERT_EQ(calstand("submit six-position --set capture_s=5").exit_code, 0);
  ASSERT_EQ(calstand("watch 1").exit_code, 0);
  calstand::testing::ApiClient api(daemon_->port());
  const std::string db = dir_ + "/station.db";

  const auto runs = calstand::testing::run("runs --json --db " + db);
  ASSERT_EQ(runs.exit_code, 0) << runs.out;
  const auto listed = api.get("/runs");
  ASSERT_EQ(listed.status, 200);
  EXPECT_EQ(nlohmann::json::parse(runs.out), listed.body);
  ASSERT_EQ(listed.body.size(), 1u);
  EXPECT_FALSE(listed.body[0]["created_utc"].get<std::string>().empty());

  const auto shown = calstand::testing::run("show --run 1 --json --db " + db);
  ASSERT_EQ(shown.exit_code, 0) << shown.out;
  const auto one = nlohmann::json::parse(shown.out);
  for (const auto& [key, value] : listed.body[0].items()) EXPECT_EQ(one[key], value) << key;
  EXPECT_EQ(one["steps"], api.get("/runs/1/steps").body);
  EXPECT_EQ(one["events"], api.get("/runs/1/events").body);
}

TEST_F(DaemonClientCli, RefusalsAreErrorsWithTheDaemonsReason) {
  const auto invalid = calstand("submit six-position --set capture_s=-5");
  EXPECT_EQ(invalid.exit_code, 2) << invalid.out;
  EXPECT_NE(invalid.out.find("HTTP 422"), std::string::npos) << invalid.out;
  EXPECT_NE(invalid.out.find("--set capture_s: -5 is below the minimum 1"), std::string::npos)
      << invalid.out;

  const auto unknown = calstand("pause 42");
  EXPECT_EQ(unknown.exit_code, 2) << unknown.out;
  EXPECT_NE(unknown.out.find("HTTP 404"), std::string::npos) << unknown.out;

  unsetenv("CALSTAND_TOKEN");
  const auto no_token = calstand("submit six-position");
  EXPECT_EQ(no_token.exit_code, 2) << no_token.out;
  EXPECT_NE(no_token.out.find("HTTP 401"), std::string::npos) << no_token.out;

  const auto nobody = calstand::testing::run("status --daemon 127.0.0.1:1");
  EXPECT_EQ(nobody.exit_code, 1) << nobody.out;
  EXPECT_NE(nobody.out.find("no answer from calstandd"), std::string::npos) << nobody.out;
}

TEST_F(DaemonClientCli, PauseResumeAndAbortARun) {
  ASSERT_EQ(calstand("submit six-position --set capture_s=300").exit_code, 0);
  calstand::testing::ApiClient api(daemon_->port());
  ASSERT_TRUE(calstand::testing::wait_until([&] {
    const auto r = api.get("/runs/1");
    return r.body.contains("live") && r.body["live"]["state"] == "running";
  }));
  const auto paused = calstand("pause 1 --now --operator bob");
  ASSERT_EQ(paused.exit_code, 0) << paused.out;
  EXPECT_EQ(paused.out, "run 1: pause at once requested\n");
  ASSERT_TRUE(
      calstand::testing::wait_until([&] { return api.get("/runs/1").body["status"] == "paused"; }));
  EXPECT_EQ(calstand("resume 1").exit_code, 0);
  const auto aborted = calstand("abort 1 --reason 'unit mounted wrong'");
  EXPECT_EQ(aborted.exit_code, 0) << aborted.out;
  const auto watched = calstand("watch 1");
  EXPECT_EQ(watched.exit_code, 1) << watched.out;
  EXPECT_NE(watched.out.find("unit mounted wrong"), std::string::npos) << watched.out;
  bool bob_paused = false;
  for (const auto& e : api.get("/runs/1/events").body) {
    bob_paused = bob_paused || (e["source"].get<std::string>().rfind("bob@", 0) == 0 &&
                                e["message"] == "pause requested (at once)");
  }
  EXPECT_TRUE(bob_paused);
}

TEST_F(DaemonClientCli, SkipWhilePausedSkipsTheNextStep) {
  ASSERT_EQ(calstand("submit six-position --set capture_s=300").exit_code, 0);
  calstand::testing::ApiClient api(daemon_->port());
  ASSERT_TRUE(calstand::testing::wait_until([&] {
    const auto r = api.get("/runs/1");
    return r.body.contains("live") && r.body["live"]["state"] == "running";
  }));
  ASSERT_EQ(calstand("pause 1").exit_code, 0);  // at the next step boundary
  ASSERT_TRUE(
      calstand::testing::wait_until([&] { return api.get("/runs/1").body["status"] == "paused"; }));
  const std::size_t next = api.get("/runs/1").body["current_step"]["index"].get<std::size_t>();
  const auto wrong = calstand("skip 1 --step " + std::to_string(next + 1));
  EXPECT_EQ(wrong.exit_code, 2) << wrong.out;
  EXPECT_NE(wrong.out.find("HTTP 409"), std::string::npos) << wrong.out;
  const auto skipped =
      calstand("skip 1 --step " + std::to_string(next) + " --reason 'not needed' --operator carol");
  ASSERT_EQ(skipped.exit_code, 0) << skipped.out;
  EXPECT_EQ(skipped.out, "run 1: skip requested\n");
  // Still paused, now before the step after the skipped one.
  ASSERT_TRUE(calstand::testing::wait_until(
      [&] { return api.get("/runs/1/steps").body[next]["status"] == "skipped"; }));
  EXPECT_EQ(api.get("/runs/1").body["status"], "paused");
  EXPECT_EQ(api.get("/runs/1").body["current_step"]["index"], next + 1);
  const auto step = api.get("/runs/1/steps").body[next];
  EXPECT_EQ(step["reason"].get<std::string>().rfind("skipped by carol@", 0), 0u) << step.dump();
  ASSERT_EQ(calstand("resume 1").exit_code, 0);
  const auto watched = calstand("watch 1");
  EXPECT_EQ(watched.exit_code, 0) << watched.out;
  EXPECT_NE(watched.out.find("run 1 completed: 11/12 steps, 1 skipped"), std::string::npos)
      << watched.out;
}

// `calstand watch` rides out a daemon killed and brought back (as systemd's Restart= does):
// the stream reconnects and the resumed run is followed to its end. The daemon is killed
// while the watch follows the run, or before the watch has started (it waits for the daemon
// as for a lost stream).
void watch_through_a_restart(bool kill_before_the_watch) {
  const std::string dir =
      calstand::testing::fresh_dir(kill_before_the_watch ? "watch-away" : "watch-restart");
  const std::string listen = "127.0.0.1:" + std::to_string(calstand::testing::free_loopback_port());
  auto daemon =
      std::make_unique<DaemonProcess>(dir + "/station.db", dir + "/calstandd.log", listen);
  ASSERT_GT(daemon->port(), 0);
  calstand::testing::ApiClient api(daemon->port());
  // 1000 s captures: about a second of wall time each, so the kill lands mid-run.
  const std::int64_t run = api.submit("six-position", {{"capture_s", 1000}});
  ASSERT_EQ(run, 1);
  ASSERT_TRUE(calstand::testing::wait_until([&] {
    const auto r = api.get("/runs/1");
    return r.body.contains("live") && r.body["steps_done"].get<int>() >= 1;
  }));
  if (kill_before_the_watch) {
    EXPECT_EQ(daemon->signal_and_wait(SIGKILL), -SIGKILL);
  }
  auto watched = std::async(std::launch::async, [&] {
    return calstand::testing::run("watch 1 --reconnect 30 --daemon " + listen);
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(300));  // watching
  if (!kill_before_the_watch) {
    EXPECT_EQ(daemon->signal_and_wait(SIGKILL), -SIGKILL);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(700));  // the daemon is away a while
  daemon = std::make_unique<DaemonProcess>(dir + "/station.db", dir + "/calstandd.log", listen);
  ASSERT_GT(daemon->port(), 0);
  ASSERT_EQ(watched.wait_for(std::chrono::seconds(120)), std::future_status::ready);
  const auto result = watched.get();
  EXPECT_EQ(result.exit_code, 0) << result.out;
  EXPECT_NE(result.out.find("run 1 completed: 12/12 steps"), std::string::npos) << result.out;
}

TEST(DaemonClientCliRestart, WatchRidesOutADaemonRestart) { watch_through_a_restart(false); }

TEST(DaemonClientCliRestart, WatchWaitsForADaemonAwayWhenItStarts) {
  watch_through_a_restart(true);
}

}  // namespace
