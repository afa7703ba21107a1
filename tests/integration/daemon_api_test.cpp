// The control API of calstandd against a daemon started in-process on an ephemeral loopback
// port with the simulated station: submit and watch, queue, pause/resume, abort, the refused
// requests (401/400/404/409/413/422), and stop/restart with both recovery policies.
#include <gtest/gtest.h>

#include <map>
#include <memory>
#include <random>

#include "daemon/api/api_server.hpp"
#include "daemon/service/event_hub.hpp"
#include "daemon/service/run_service.hpp"
#include "daemon_test_support.hpp"
#include "in_process_daemon.hpp"
#include "sim/sim_world.hpp"
#include "store/database.hpp"
#include "store/run_store.hpp"

namespace {

using namespace calstand;
using calstand::testing::ApiClient;
using calstand::testing::EventStreamReader;
using calstand::testing::Reply;
using calstand::testing::wait_until;
using daemon::service::RecoveryPolicy;

// Six static positions, 12 steps: with 5 s captures a run takes a fraction of a second of
// wall time; with 300 s captures a few seconds (each capture ~0.3 s on an idle machine), long
// enough to act on mid-run without racing the run's end.
const nlohmann::json kShort = {{"capture_s", 5}};
const nlohmann::json kLong = {{"capture_s", 300}};
// Who the test client is in the records: its X-Calstand-Operator header and address, and the
// name of the token it sends (the daemon's CALSTAND_TOKEN-style single token).
const char* const kTester = "tester@127.0.0.1 (token operator)";

using calstand::testing::InProcessDaemon;

std::string status_of(ApiClient& api, std::int64_t run) {
  const Reply r = api.get("/runs/" + std::to_string(run));
  return r.status == 200 ? r.body.value("status", "") : "";
}

bool wait_for_status(ApiClient& api, std::int64_t run, const std::string& status) {
  return wait_until([&] { return status_of(api, run) == status; });
}

// True once the run is on the station, running, with at least `steps` steps done.
bool running_with_steps_done(ApiClient& api, std::int64_t run, std::size_t steps) {
  const Reply r = api.get("/runs/" + std::to_string(run));
  return r.status == 200 && r.body.contains("live") && r.body["live"]["state"] == "running" &&
         r.body["steps_done"].get<std::size_t>() >= steps;
}

bool has_event(const Reply& events, const std::string& source, const std::string& text) {
  for (const auto& e : events.body) {
    if (e["source"] == source && e["message"].get<std::string>().find(text) != std::string::npos)
      return true;
  }
  return false;
}

// cpp-httplib ignores a stop() that comes before its listening thread has marked the server
// running, and that thread then accepts forever: calstandd given SIGTERM in its first moments
// hung in join (found under AddressSanitizer). Stopping right after starting must return, every
// time; before the fix this hung within a few rounds (ctest's time limit fails it).
TEST(DaemonApi, AStopRightAfterTheStartReturns) {
  const std::string db = calstand::testing::fresh_dir("stop-at-start") + "/station.db";
  daemon::service::EventHub hub(16);
  daemon::service::RunService service({sim::load_station_or_default(""), db, RecoveryPolicy::kAuto},
                                      hub);
  for (int round = 0; round < 200; ++round) {
    daemon::api::ApiOptions options;
    options.port = 0;
    options.token = calstand::testing::kTestToken;
    daemon::api::ApiServer server(service, hub, options);
    ASSERT_GT(server.start(), 0) << "round " << round;
    server.stop();
  }
}

TEST(DaemonApi, SubmitsAndWatchesARunToCompletion) {
  InProcessDaemon d(calstand::testing::fresh_dir("watch") + "/station.db");
  ApiClient api(d.port());
  EventStreamReader stream(d.port());
  ASSERT_TRUE(
      wait_until([&] { return stream.saw([](const auto& m) { return m.type == "station"; }); }));

  const Reply submitted =
      api.post_json("/runs", {{"procedure", "six-position"}, {"parameters", kShort}});
  ASSERT_EQ(submitted.status, 201) << submitted.raw;
  const std::int64_t run = submitted.body.at("id");
  ASSERT_TRUE(wait_for_status(api, run, "completed"));

  const Reply status = api.get("/runs/" + std::to_string(run));
  EXPECT_EQ(status.body["steps_done"], 12);
  EXPECT_EQ(status.body["steps_total"], 12);
  EXPECT_DOUBLE_EQ(status.body["progress"].get<double>(), 1.0);
  EXPECT_EQ(status.body["parameters"]["capture_s"], 5);

  const Reply steps = api.get("/runs/" + std::to_string(run) + "/steps");
  ASSERT_EQ(steps.body.size(), 12u);
  for (const auto& s : steps.body) EXPECT_EQ(s["status"], "completed") << s.dump();

  const Reply events = api.get("/runs/" + std::to_string(run) + "/events");
  EXPECT_TRUE(has_event(events, kTester, "submitted six-position")) << events.raw;

  // The live stream told the story: the run starting and ending, every step completing, and
  // telemetry on the way.
  ASSERT_TRUE(wait_until([&] {
    return stream.saw(
        [&](const auto& m) { return m.type == "run" && m.data["state"] == "completed"; });
  }));
  for (int i = 0; i < 12; ++i) {
    EXPECT_TRUE(stream.saw([&](const auto& m) {
      return m.type == "step" && m.data["step"] == i && m.data["status"] == "completed" &&
             m.data["run"] == run;
    })) << "step "
        << i;
  }
  EXPECT_TRUE(
      stream.saw([](const auto& m) { return m.type == "run" && m.data["state"] == "running"; }));
  EXPECT_TRUE(
      stream.saw([](const auto& m) { return m.type == "telemetry" && m.data.contains("table"); }));

  const Reply listing = api.get("/runs");
  ASSERT_EQ(listing.status, 200);
  ASSERT_EQ(listing.body.size(), 1u);
  EXPECT_EQ(listing.body[0]["id"], run);

  // The stream's "completed" comes from the engine; the runner lets go of the run just after,
  // so the station is idle soon, not necessarily at once.
  Reply station;
  EXPECT_TRUE(wait_until([&] {
    station = api.get("/station");
    return station.status == 200 && station.body["run"].is_null();
  })) << station.raw;
  ASSERT_EQ(station.status, 200);
  EXPECT_GE(station.body["devices"].size(), 3u);
  EXPECT_FALSE(station.body["telemetry"]["table"].is_null());
}

TEST(DaemonApi, ExportsARunAsAUstarArchive) {
  InProcessDaemon d(calstand::testing::fresh_dir("export") + "/station.db");
  ApiClient api(d.port());
  const std::int64_t run = api.submit("six-position", kShort);
  ASSERT_GT(run, 0);
  ASSERT_TRUE(wait_for_status(api, run, "completed"));
  httplib::Client c("127.0.0.1", d.port());
  const auto res = c.Get(("/runs/" + std::to_string(run) + "/export").c_str());
  ASSERT_TRUE(res);
  ASSERT_EQ(res->status, 200) << res->body;
  EXPECT_EQ(res->get_header_value("Content-Type"), "application/x-tar");
  const std::string& tar = res->body;
  ASSERT_GT(tar.size(), 4u * 512u);
  EXPECT_EQ(tar.size() % 512, 0u);
  const std::string first_name = "run-" + std::to_string(run) + "/meta.json";
  EXPECT_EQ(tar.substr(0, first_name.size()), first_name);
  EXPECT_EQ(tar.substr(257, 5), "ustar");
  EXPECT_NE(tar.find("run-" + std::to_string(run) + "/samples.csv"), std::string::npos);
  EXPECT_NE(tar.find("\"format\""), std::string::npos);  // meta.json's content follows its header
}

TEST(DaemonApi, QueuedRunsRunOneAtATimeInOrder) {
  InProcessDaemon d(calstand::testing::fresh_dir("queue") + "/station.db");
  ApiClient api(d.port());
  const std::int64_t first = api.submit("six-position", kLong);
  const std::int64_t second = api.submit("six-position", kShort);
  ASSERT_GT(first, 0);
  ASSERT_GT(second, 0);
  ASSERT_TRUE(wait_until([&] { return running_with_steps_done(api, first, 1); }));
  EXPECT_EQ(status_of(api, second), "queued");  // the station is busy with the first
  const Reply station = api.get("/station");
  EXPECT_EQ(station.body["run"], first);
  ASSERT_EQ(station.body["queue"].size(), 1u);
  EXPECT_EQ(station.body["queue"][0]["run"], second);
  EXPECT_EQ(station.body["queue"][0]["submitted_by"], kTester);
  // Once the first ends, the second goes.
  ASSERT_EQ(api.post("/runs/" + std::to_string(first) + "/abort", "").status, 202);
  ASSERT_TRUE(wait_for_status(api, second, "completed"));
  EXPECT_EQ(status_of(api, first), "aborted");
  const Reply a = api.get("/runs/" + std::to_string(first));
  const Reply b = api.get("/runs/" + std::to_string(second));
  EXPECT_LE(a.body["ended_utc"].get<std::string>(), b.body["started_utc"].get<std::string>());
}

// A long history comes a page at a time, newest first; each full page links the next, and
// following the links gives every run once.
TEST(DaemonApi, ListsRunsAPageAtATime) {
  InProcessDaemon d(calstand::testing::fresh_dir("pages") + "/station.db");
  ApiClient api(d.port());
  std::vector<std::int64_t> submitted;
  for (int i = 0; i < 5; ++i) submitted.push_back(api.submit("six-position", kLong));
  ASSERT_EQ(std::count(submitted.begin(), submitted.end(), 0), 0);

  std::vector<std::int64_t> listed;
  std::string next = "/runs?limit=2";
  int pages = 0;
  while (!next.empty() && pages < 10) {
    const Reply page = api.get(next);
    ASSERT_EQ(page.status, 200) << next << ": " << page.raw;
    EXPECT_LE(page.body.size(), 2u) << page.raw;
    for (const auto& r : page.body) listed.push_back(r["id"].get<std::int64_t>());
    ++pages;
    next.clear();
    if (const auto link = page.headers.find("Link"); link != page.headers.end()) {
      const auto& value = link->second;  // </runs?limit=2&before=ID>; rel="next"
      ASSERT_NE(value.find("rel=\"next\""), std::string::npos) << value;
      next = value.substr(1, value.find('>') - 1);
    }
  }
  EXPECT_EQ(pages, 3);
  std::vector<std::int64_t> newest_first(submitted.rbegin(), submitted.rend());
  EXPECT_EQ(listed, newest_first);
  // Without a limit, one page of up to 100 and no link; a page that takes exactly the last runs
  // links nothing further, and nothing is before the first run.
  const Reply all = api.get("/runs");
  EXPECT_EQ(all.body.size(), 5u);
  EXPECT_EQ(all.headers.count("Link"), 0u);
  const Reply exact = api.get("/runs?limit=5");
  EXPECT_EQ(exact.body.size(), 5u);
  EXPECT_EQ(exact.headers.count("Link"), 0u) << exact.raw;
  const Reply last_two = api.get("/runs?limit=2&before=" + std::to_string(submitted[2]));
  ASSERT_EQ(last_two.body.size(), 2u) << last_two.raw;
  EXPECT_EQ(last_two.body[0]["id"], submitted[1]);
  EXPECT_EQ(last_two.headers.count("Link"), 0u) << last_two.raw;
  const Reply none = api.get("/runs?before=" + std::to_string(submitted[0]));
  EXPECT_EQ(none.status, 200);
  EXPECT_TRUE(none.body.is_array() && none.body.empty()) << none.raw;

  for (const char* bad : {"/runs?limit=0", "/runs?limit=1001", "/runs?limit=two", "/runs?before=-3",
                          "/runs?limit=5x"}) {
    const Reply r = api.get(bad);
    EXPECT_EQ(r.status, 400) << bad << ": " << r.raw;
    EXPECT_EQ(r.body.value("where", "").substr(0, 1), "?") << bad << ": " << r.raw;
  }
  for (auto it = submitted.rbegin(); it != submitted.rend(); ++it) {
    EXPECT_EQ(api.post("/runs/" + std::to_string(*it) + "/abort", "").status, 202);
  }
  EXPECT_TRUE(wait_for_status(api, submitted.front(), "aborted"));
}

TEST(DaemonApi, PausesAndResumesARun) {
  InProcessDaemon d(calstand::testing::fresh_dir("pause") + "/station.db");
  ApiClient api(d.port());
  const std::int64_t run = api.submit("six-position", kLong);
  ASSERT_GT(run, 0);
  ASSERT_TRUE(wait_until([&] { return running_with_steps_done(api, run, 1); }));
  const std::string path = "/runs/" + std::to_string(run);

  const Reply paused = api.post_json(path + "/pause", {{"immediate", true}});
  ASSERT_EQ(paused.status, 202) << paused.raw;
  ASSERT_TRUE(wait_for_status(api, run, "paused"));
  const auto done_when_paused = api.get(path).body["steps_done"].get<int>();
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  EXPECT_EQ(status_of(api, run), "paused");
  EXPECT_EQ(api.get(path).body["steps_done"].get<int>(), done_when_paused);  // nothing advances
  // Where it stands: the step it will redo, and the station time still needed.
  const Reply where = api.get(path);
  EXPECT_EQ(where.body["live"]["state"], "paused");
  ASSERT_TRUE(where.body["current_step"].is_object()) << where.raw;
  EXPECT_GE(where.body["current_step"]["index"].get<int>(), done_when_paused);
  EXPECT_FALSE(where.body["current_step"]["label"].get<std::string>().empty());
  // At least the captures not yet done (300 s each; six-position has 6), at most the plan.
  const double eta_s = where.body["eta_s"].get<double>();
  EXPECT_GE(eta_s, 300.0 * (12 - where.body["current_step"]["index"].get<int>()) / 2 - 300.0)
      << where.raw;
  EXPECT_LE(eta_s, 12 * 400.0) << where.raw;
  EXPECT_EQ(api.post(path + "/pause", "").status, 409);  // already paused

  const Reply resumed = api.post(path + "/resume", "");
  ASSERT_EQ(resumed.status, 202) << resumed.raw;
  ASSERT_TRUE(wait_for_status(api, run, "completed"));
  const Reply events = api.get(path + "/events");
  EXPECT_TRUE(has_event(events, kTester, "pause requested (at once)")) << events.raw;
  EXPECT_TRUE(has_event(events, kTester, "resume requested")) << events.raw;
  EXPECT_EQ(api.post(path + "/resume", "").status, 409);  // completed: nothing to resume
}

TEST(DaemonApi, AbortsARunToTheSafeState) {
  InProcessDaemon d(calstand::testing::fresh_dir("abort") + "/station.db");
  ApiClient api(d.port());
  EventStreamReader stream(d.port());
  const std::int64_t run = api.submit("six-position", kLong);
  ASSERT_GT(run, 0);
  ASSERT_TRUE(wait_until([&] { return running_with_steps_done(api, run, 1); }));
  const std::string path = "/runs/" + std::to_string(run);

  ASSERT_EQ(api.post_json(path + "/abort", {{"reason", "fixture loose"}}).status, 202);
  ASSERT_TRUE(wait_for_status(api, run, "aborted"));
  const Reply status = api.get(path);
  const std::string reason = status.body["exit_reason"];
  EXPECT_NE(reason.find("tester@127.0.0.1"), std::string::npos) << reason;
  EXPECT_NE(reason.find("fixture loose"), std::string::npos) << reason;
  EXPECT_LT(status.body["steps_done"].get<int>(), 12);
  // The engine made the station safe without a fault, and said so on the stream.
  const Reply events = api.get(path + "/events");
  for (const auto& e : events.body) {
    EXPECT_EQ(e["message"].get<std::string>().find("making the station safe"), std::string::npos)
        << e.dump();
  }
  ASSERT_TRUE(wait_until([&] {
    return stream.saw(
        [&](const auto& m) { return m.type == "run" && m.data["state"] == "aborted"; });
  }));
  EXPECT_EQ(api.post(path + "/abort", "").status, 409);  // already ended
  // The station is free again: the next run goes.
  const std::int64_t next = api.submit("six-position", kShort);
  EXPECT_TRUE(wait_for_status(api, next, "completed"));
}

TEST(DaemonApi, AbortsAQueuedRunBeforeItStarts) {
  InProcessDaemon d(calstand::testing::fresh_dir("abort-queued") + "/station.db");
  ApiClient api(d.port());
  // The simulated station runs as fast as the CPU allows: the first run must outlast a busy
  // machine's scheduling of this thread (kLong took 0.8 s and once finished first), so it gets
  // an hour per position; it is aborted at the end.
  const std::int64_t first = api.submit("six-position", {{"capture_s", 3600}});
  const std::int64_t second = api.submit("six-position", kShort);
  ASSERT_EQ(status_of(api, second), "queued");
  ASSERT_EQ(api.post("/runs/" + std::to_string(second) + "/abort", "").status, 202);
  EXPECT_EQ(status_of(api, second), "aborted");
  EXPECT_EQ(api.get("/runs/" + std::to_string(second)).body["steps_done"], 0);
  ASSERT_EQ(api.post("/runs/" + std::to_string(first) + "/abort", "").status, 202);
  EXPECT_TRUE(wait_for_status(api, first, "aborted"));
}

TEST(DaemonApi, RefusesBadRequestsWithClearErrorsAndKeepsServing) {
  InProcessDaemon d(calstand::testing::fresh_dir("refuse") + "/station.db");
  ApiClient api(d.port());
  const std::string good =
      nlohmann::json{{"procedure", "six-position"}, {"parameters", kShort}}.dump();

  // 401: no token, a wrong one, a prefix of the right one; reads need none.
  EXPECT_EQ(api.post("/runs", good, "").status, 401);
  EXPECT_EQ(api.post("/runs", good, "wrong").status, 401);
  EXPECT_EQ(
      api.post("/runs", good, std::string(calstand::testing::kTestToken).substr(0, 10)).status,
      401);
  EXPECT_EQ(api.get("/runs").status, 200);

  // 400: malformed JSON, with the place.
  const Reply malformed = api.post("/runs", "{\n  \"procedure\": \"six-position\",,\n}");
  EXPECT_EQ(malformed.status, 400);
  EXPECT_NE(malformed.body.value("where", "").find("line 2, column"), std::string::npos)
      << malformed.raw;
  EXPECT_NE(malformed.body.value("error", "").find("malformed JSON"), std::string::npos)
      << malformed.raw;
  EXPECT_EQ(api.post("/runs", "").status, 400);
  // Nested without end: refused before anything recurses over it (it overflowed the stack).
  const Reply deep =
      api.post("/runs", "{\"procedure\": \"six-position\", \"parameters\": {\"x\": " +
                            std::string(20000, '[') + std::string(20000, ']') + "}}");
  EXPECT_EQ(deep.status, 400) << deep.raw.substr(0, 200);
  EXPECT_NE(deep.body.value("error", "").find("nested deeper than"), std::string::npos)
      << deep.raw.substr(0, 200);

  // 404: unknown routes and ids.
  EXPECT_EQ(api.get("/nope").status, 404);
  EXPECT_EQ(api.get("/runs/999").status, 404);
  EXPECT_EQ(api.get("/runs/abc").status, 404);
  EXPECT_EQ(api.get("/runs/99999999999999999999999").status, 404);
  EXPECT_EQ(api.post("/runs/999/pause", "").status, 404);
  EXPECT_EQ(api.get("/calibrations/5").status, 404);
  EXPECT_FALSE(api.get("/nope").body.value("error", "").empty());

  // 413: a body beyond the limit (64 KiB in this daemon).
  const Reply too_large = api.post("/runs", std::string(200 * 1024, ' '));
  EXPECT_EQ(too_large.status, 413);

  // 422: every violation, as the plan check gives them.
  const Reply unknown = api.post_json("/runs", {{"procedure", "no-such-procedure"}});
  EXPECT_EQ(unknown.status, 422);
  EXPECT_EQ(unknown.body["violations"][0]["path"], "procedure");
  const Reply bad_params = api.post_json(
      "/runs", {{"procedure", "six-position"}, {"parameters", {{"capture_s", -5}, {"bogus", 1}}}});
  ASSERT_EQ(bad_params.status, 422) << bad_params.raw;
  EXPECT_GE(bad_params.body["violations"].size(), 2u) << bad_params.raw;
  const Reply bad_inline =
      api.post_json("/runs", {{"procedure", {{"name", "x"}, {"steps", {{{"kind", "fly"}}}}}}});
  ASSERT_EQ(bad_inline.status, 422) << bad_inline.raw;
  EXPECT_FALSE(bad_inline.body["violations"].empty());
  const Reply bad_shape = api.post_json("/runs", {{"procedure", 3}, {"extra", true}});
  ASSERT_EQ(bad_shape.status, 422);
  EXPECT_EQ(bad_shape.body["violations"].size(), 2u) << bad_shape.raw;
  EXPECT_EQ(api.get("/runs").body.size(), 0u);  // nothing refused was written

  // 400 on a bad action body; the daemon still works after all of it.
  const std::int64_t run = api.submit("six-position", kShort);
  ASSERT_GT(run, 0);
  EXPECT_EQ(api.post("/runs/" + std::to_string(run) + "/pause", "{\"immediate\": 3}").status, 400);
  EXPECT_TRUE(wait_for_status(api, run, "completed"));
  EXPECT_EQ(api.get("/station").status, 200);
}

// A daemon stop mid-run (what SIGTERM does) checkpoints the run; a restart resumes it where
// it was, leaving completed steps untouched.
TEST(DaemonApi, StopCheckpointsTheRunAndARestartResumesIt) {
  const std::string db = calstand::testing::fresh_dir("checkpoint") + "/station.db";
  std::int64_t run = 0;
  std::vector<store::StepRecord> before;
  {
    InProcessDaemon d(db);
    ApiClient api(d.port());
    run = api.submit("six-position", kLong);
    ASSERT_TRUE(wait_until([&] { return running_with_steps_done(api, run, 3); }));
  }
  {
    store::Database database(db);
    const auto record = store::RunStore(database).load_run(run);
    EXPECT_EQ(record.summary.status, "interrupted");
    EXPECT_NE(record.summary.exit_reason.find("checkpoint: daemon stopping"), std::string::npos)
        << record.summary.exit_reason;
    EXPECT_TRUE(record.summary.ended_utc.empty());  // not ended: it resumes
    bool said = false;
    for (const auto& e : record.events)
      said = said || e.message.find("checkpointed: station made safe") == 0;
    EXPECT_TRUE(said);
    before = record.steps;
  }
  InProcessDaemon d(db);
  ApiClient api(d.port());
  ASSERT_TRUE(wait_for_status(api, run, "completed"));
  store::Database database(db);
  const auto after = store::RunStore(database).load_steps(run);
  ASSERT_EQ(after.size(), before.size());
  for (std::size_t i = 0; i < after.size(); ++i) {
    EXPECT_EQ(after[i].status, store::StepStatus::kCompleted) << i;
    if (before[i].status == store::StepStatus::kCompleted) {
      EXPECT_EQ(after[i].good_attempt, before[i].good_attempt) << i;
      EXPECT_EQ(after[i].ended_clock_s, before[i].ended_clock_s) << i;
    }
  }
  EXPECT_TRUE(
      has_event(api.get("/runs/" + std::to_string(run) + "/events"), "daemon", "resuming at step"));
}

TEST(DaemonApi, HoldPolicyKeepsAnInterruptedRunUntilAnOperatorResumesIt) {
  const std::string db = calstand::testing::fresh_dir("hold") + "/station.db";
  std::int64_t run = 0;
  {
    InProcessDaemon d(db);
    ApiClient api(d.port());
    run = api.submit("six-position", kLong);
    ASSERT_TRUE(wait_until([&] { return running_with_steps_done(api, run, 1); }));
  }
  InProcessDaemon d(db, RecoveryPolicy::kHold);
  ApiClient api(d.port());
  ASSERT_TRUE(wait_for_status(api, run, "held"));
  // Held: a new submission waits behind it, and nothing moves until the operator decides.
  const std::int64_t queued = api.submit("six-position", kShort);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  EXPECT_EQ(status_of(api, run), "held");
  EXPECT_EQ(status_of(api, queued), "queued");
  EXPECT_EQ(api.get("/station").body["held"], run);
  EXPECT_EQ(api.post("/runs/" + std::to_string(run) + "/pause", "").status, 409);

  ASSERT_EQ(api.post("/runs/" + std::to_string(run) + "/resume", "").status, 202);
  ASSERT_TRUE(wait_for_status(api, run, "completed"));
  EXPECT_TRUE(wait_for_status(api, queued, "completed"));
  const Reply events = api.get("/runs/" + std::to_string(run) + "/events");
  EXPECT_TRUE(has_event(events, "daemon", "held after an interruption")) << events.raw;
  EXPECT_TRUE(has_event(events, kTester, "resume requested")) << events.raw;
}

TEST(DaemonApi, HoldPolicyLetsAnOperatorAbortTheInterruptedRun) {
  const std::string db = calstand::testing::fresh_dir("hold-abort") + "/station.db";
  std::int64_t run = 0;
  {
    InProcessDaemon d(db);
    ApiClient api(d.port());
    run = api.submit("six-position", kLong);
    ASSERT_TRUE(wait_until([&] { return running_with_steps_done(api, run, 1); }));
  }
  InProcessDaemon d(db, RecoveryPolicy::kHold);
  ApiClient api(d.port());
  ASSERT_TRUE(wait_for_status(api, run, "held"));
  ASSERT_EQ(
      api.post_json("/runs/" + std::to_string(run) + "/abort", {{"reason", "unit removed"}}).status,
      202);
  EXPECT_EQ(status_of(api, run), "aborted");
  EXPECT_TRUE(api.get("/station").body["held"].is_null());
}

TEST(DaemonApi, SkipsTheStepInProgressAndRecordsWhoAndWhy) {
  InProcessDaemon d(calstand::testing::fresh_dir("skip") + "/station.db");
  ApiClient api(d.port());
  EventStreamReader stream(d.port());
  const std::int64_t run = api.submit("six-position", kLong);
  ASSERT_GT(run, 0);
  const std::string path = "/runs/" + std::to_string(run);
  // Wait for a capture (odd steps of six-position: move, capture, move, ...), then skip
  // whatever step is in progress when the request lands.
  ASSERT_TRUE(wait_until([&] {
    const Reply r = api.get(path);
    return r.status == 200 && r.body.contains("live") && r.body["live"]["phase"] == "capturing";
  }));
  const Reply skipped = api.post_json(path + "/skip", {{"reason", "connector re-seated"}});
  ASSERT_EQ(skipped.status, 202) << skipped.raw;
  ASSERT_TRUE(wait_for_status(api, run, "completed"));

  const Reply steps = api.get(path + "/steps");
  std::vector<int> skipped_steps;
  for (const auto& s : steps.body) {
    if (s["status"] == "skipped") {
      skipped_steps.push_back(s["index"].get<int>());
      EXPECT_EQ(s["reason"], std::string("skipped by ") + kTester + ": connector re-seated");
      EXPECT_TRUE(s["good_attempt"].is_null());
    } else {
      EXPECT_EQ(s["status"], "completed") << s.dump();
    }
  }
  ASSERT_EQ(skipped_steps.size(), 1u) << steps.raw;
  const int step = skipped_steps[0];
  EXPECT_TRUE(stream.saw([&](const auto& m) {
    return m.type == "step" && m.data["status"] == "skipped" && m.data["step"] == step;
  }));
  EXPECT_EQ(api.get(path).body["steps_done"], 11);  // the skipped step is not done
  const Reply events = api.get(path + "/events");
  EXPECT_TRUE(has_event(events, kTester, "skip requested: connector re-seated")) << events.raw;
  // Refusals: a run that has ended, a bad body, an unknown run.
  EXPECT_EQ(api.post(path + "/skip", "").status, 409);
  EXPECT_EQ(api.post(path + "/skip", "{\"step\": -1}").status, 400);
  EXPECT_EQ(api.post("/runs/999/skip", "").status, 404);
}

TEST(DaemonApi, SkipRefusesARunNotOnTheStationOrAStepItIsNotAt) {
  InProcessDaemon d(calstand::testing::fresh_dir("skip-refused") + "/station.db");
  ApiClient api(d.port());
  const std::int64_t first = api.submit("six-position", kLong);
  const std::int64_t second = api.submit("six-position", kShort);
  ASSERT_TRUE(wait_until([&] { return running_with_steps_done(api, first, 1); }));
  const Reply queued = api.post("/runs/" + std::to_string(second) + "/skip", "");
  EXPECT_EQ(queued.status, 409) << queued.raw;
  const Reply elsewhere = api.post_json("/runs/" + std::to_string(first) + "/skip", {{"step", 11}});
  EXPECT_EQ(elsewhere.status, 409) << elsewhere.raw;
  EXPECT_NE(elsewhere.body.value("error", "").find("not step 11"), std::string::npos)
      << elsewhere.raw;
  ASSERT_EQ(api.post("/runs/" + std::to_string(first) + "/abort", "").status, 202);
  ASSERT_TRUE(wait_for_status(api, second, "completed"));
  const Reply steps = api.get("/runs/" + std::to_string(second) + "/steps");
  for (const auto& s : steps.body) EXPECT_EQ(s["status"], "completed");
}

// A reader that reconnects with Last-Event-ID gets what it missed; one whose id is no longer
// kept is told how much it lost.
TEST(DaemonApi, EventStreamReplaysWhatAReconnectingReaderMissed) {
  InProcessDaemon d(calstand::testing::fresh_dir("replay") + "/station.db");
  ApiClient api(d.port());
  std::string first_id;
  {
    // Read the first message with an id, then go away.
    httplib::Client c("127.0.0.1", d.port());
    c.set_read_timeout(10, 0);
    std::string buffer;
    const std::int64_t run = api.submit("six-position", kShort);
    ASSERT_GT(run, 0);
    c.Get("/events", [&](const char* data, std::size_t n) {
      buffer.append(data, n);
      const auto at = buffer.find("id: ");
      if (at == std::string::npos) return true;
      const auto eol = buffer.find('\n', at);
      if (eol == std::string::npos) return true;
      first_id = buffer.substr(at + 4, eol - at - 4);
      return false;
    });
    ASSERT_FALSE(first_id.empty());
    ASSERT_TRUE(wait_for_status(api, run, "completed"));
  }
  // Everything after that id, in order, ending with the run's completion.
  httplib::Client c("127.0.0.1", d.port());
  c.set_read_timeout(10, 0);
  bool saw_station = false, saw_gap = false, saw_completed = false;
  std::vector<std::uint64_t> seqs;
  calstand::wire::SseDecoder parser([&](const calstand::wire::SseEvent& m) {
    saw_station = saw_station || m.type == "station";
    saw_gap = saw_gap || m.type == "gap";
    if (!m.id.empty()) seqs.push_back(std::stoull(m.id.substr(m.id.find('-') + 1)));
    if (m.type == "run" && m.data.find("\"completed\"") != std::string::npos) {
      saw_completed = true;
      return false;
    }
    return true;
  });
  c.Get("/events", {{"Last-Event-ID", first_id}}, [&](const char* data, std::size_t n) {
    return parser.feed({data, n});
  });
  EXPECT_TRUE(saw_station);
  EXPECT_FALSE(saw_gap);
  EXPECT_TRUE(saw_completed);
  EXPECT_EQ(parser.retry_ms(), std::optional<std::uint64_t>(2000));  // reconnect after 2 s
  ASSERT_FALSE(seqs.empty());
  EXPECT_EQ(seqs.front(), std::stoull(first_id.substr(first_id.find('-') + 1)) + 1);
  for (std::size_t i = 1; i < seqs.size(); ++i) EXPECT_EQ(seqs[i], seqs[i - 1] + 1);
}

// Between runs the table and the chamber are read (never commanded): the station screen shows
// them; the IMUs are closed.
TEST(DaemonApi, StationBetweenRunsShowsTheTableAndTheChamber) {
  InProcessDaemon d(calstand::testing::fresh_dir("idle") + "/station.db");
  ApiClient api(d.port());
  EventStreamReader stream(d.port());
  ASSERT_TRUE(wait_until([&] {
    const Reply r = api.get("/station");
    return r.status == 200 && !r.body["telemetry"]["chamber"].is_null() &&
           !r.body["telemetry"]["table"].is_null();
  }));
  const Reply station = api.get("/station");
  EXPECT_TRUE(station.body["run"].is_null());
  EXPECT_FALSE(station.body.contains("progress"));
  for (const auto& dev : station.body["devices"]) {
    EXPECT_EQ(dev["state"], dev["kind"] == "imu" ? "offline" : "inactive") << dev.dump();
  }
  const auto& chamber = station.body["telemetry"]["chamber"];
  EXPECT_FALSE(chamber["fault"].get<bool>());
  EXPECT_GT(chamber["air_c"].get<double>(), 10.0);  // the lab's air, not a made-up zero
  EXPECT_LT(chamber["air_c"].get<double>(), 40.0);
  EXPECT_TRUE(wait_until([&] {
    return stream.saw(
        [](const auto& m) { return m.type == "telemetry" && m.data["run"].is_null(); });
  }));
  // And a run still takes the station as before.
  const std::int64_t run = api.submit("six-position", kShort);
  EXPECT_TRUE(wait_for_status(api, run, "completed"));
}

// Live streams hold a connection thread each: beyond the cap they are refused, so requests
// (an operator's abort) always get through.
TEST(DaemonApi, LiveStreamsAreCappedSoRequestsStillGetThrough) {
  InProcessDaemon d(calstand::testing::fresh_dir("streams") + "/station.db");
  ApiClient api(d.port());
  std::vector<std::unique_ptr<EventStreamReader>> readers;
  for (int i = 0; i < 8; ++i) readers.push_back(std::make_unique<EventStreamReader>(d.port()));
  ASSERT_TRUE(wait_until([&] {
    for (const auto& r : readers) {
      if (!r->saw([](const auto& m) { return m.type == "station"; })) return false;
    }
    return true;
  }));
  httplib::Client c("127.0.0.1", d.port());
  c.set_read_timeout(5, 0);
  const auto refused = c.Get("/events");
  ASSERT_TRUE(refused);
  EXPECT_EQ(refused->status, 503);
  EXPECT_EQ(refused->get_header_value("Retry-After"), "5");
  EXPECT_EQ(api.get("/station").status, 200);
  const std::int64_t run = api.submit("six-position", kLong);
  ASSERT_GT(run, 0);
  ASSERT_EQ(api.post("/runs/" + std::to_string(run) + "/abort", "").status, 202);
  EXPECT_TRUE(wait_for_status(api, run, "aborted"));
  // A reader that goes gives its place back.
  readers.pop_back();
  EXPECT_TRUE(wait_until([&] {
    EventStreamReader again(d.port());
    return wait_until([&] { return again.saw([](const auto& m) { return m.type == "station"; }); },
                      std::chrono::milliseconds(500));
  }));
}

// A reader too far behind (here: the daemon keeps 16 messages) is told how many it lost, then
// gets what is still kept, in order.
TEST(DaemonApi, EventStreamSaysHowManyMessagesAReaderLost) {
  InProcessDaemon d(calstand::testing::fresh_dir("gap") + "/station.db", RecoveryPolicy::kAuto, 16);
  ApiClient api(d.port());
  std::string first_id;
  {
    httplib::Client c("127.0.0.1", d.port());
    c.set_read_timeout(10, 0);
    const std::int64_t run = api.submit("six-position", kShort);
    ASSERT_GT(run, 0);
    calstand::wire::SseDecoder parser([&](const calstand::wire::SseEvent& m) {
      first_id = m.id;
      return m.id.empty();
    });
    c.Get("/events", [&](const char* data, std::size_t n) { return parser.feed({data, n}); });
    ASSERT_FALSE(first_id.empty());
    ASSERT_TRUE(wait_for_status(api, run, "completed"));  // 30-odd messages: more than kept
  }
  httplib::Client c("127.0.0.1", d.port());
  c.set_read_timeout(10, 0);
  nlohmann::json gap;
  std::vector<std::uint64_t> seqs;
  calstand::wire::SseDecoder parser([&](const calstand::wire::SseEvent& m) {
    if (m.type == "gap") gap = nlohmann::json::parse(m.data);
    if (!m.id.empty()) seqs.push_back(std::stoull(m.id.substr(m.id.find('-') + 1)));
    return seqs.size() < 16;
  });
  c.Get("/events", {{"Last-Event-ID", first_id}}, [&](const char* data, std::size_t n) {
    return parser.feed({data, n});
  });
  ASSERT_TRUE(gap.is_object());
  EXPECT_EQ(gap["after_id"], first_id);
  ASSERT_EQ(seqs.size(), 16u);
  const std::uint64_t first_seq = std::stoull(first_id.substr(first_id.find('-') + 1));
  EXPECT_EQ(gap["missed"].get<std::uint64_t>(), seqs.front() - first_seq - 1);
  EXPECT_GT(gap["missed"].get<std::uint64_t>(), 0u);
  for (std::size_t i = 1; i < seqs.size(); ++i) EXPECT_EQ(seqs[i], seqs[i - 1] + 1);
}

// A run the operator had paused when the daemon stopped is not resumed by itself on restart,
// whatever the recovery policy: it is held until the operator says so.
TEST(DaemonApi, ARunPausedAtTheCheckpointIsHeldOnRestart) {
  const std::string db = calstand::testing::fresh_dir("paused-checkpoint") + "/station.db";
  std::int64_t run = 0;
  {
    InProcessDaemon d(db);
    ApiClient api(d.port());
    run = api.submit("six-position", kLong);
    ASSERT_TRUE(wait_until([&] { return running_with_steps_done(api, run, 1); }));
    ASSERT_EQ(api.post("/runs/" + std::to_string(run) + "/pause", "").status, 202);
    ASSERT_TRUE(wait_for_status(api, run, "paused"));
  }
  {
    store::Database database(db);
    EXPECT_EQ(store::RunStore(database).load_run(run).summary.status, "held");
  }
  InProcessDaemon d(db, RecoveryPolicy::kAuto);
  ApiClient api(d.port());
  ASSERT_TRUE(wait_until([&] { return api.get("/station").body["held"] == run; }));
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  EXPECT_EQ(status_of(api, run), "held");
  ASSERT_EQ(api.post("/runs/" + std::to_string(run) + "/resume", "").status, 202);
  EXPECT_TRUE(wait_for_status(api, run, "completed"));
  EXPECT_TRUE(
      has_event(api.get("/runs/" + std::to_string(run) + "/events"), "daemon", "it was paused"));
}

// The export is served at any byte range (a download resumed halfway).
TEST(DaemonApi, ExportServesByteRanges) {
  InProcessDaemon d(calstand::testing::fresh_dir("export-range") + "/station.db");
  ApiClient api(d.port());
  const std::int64_t run = api.submit("six-position", kShort);
  ASSERT_TRUE(wait_for_status(api, run, "completed"));
  httplib::Client c("127.0.0.1", d.port());
  const std::string path = "/runs/" + std::to_string(run) + "/export";
  const auto whole = c.Get(path.c_str());
  ASSERT_TRUE(whole);
  ASSERT_EQ(whole->status, 200);
  ASSERT_GT(whole->body.size(), 5000u);
  const auto part = c.Get(path.c_str(), {{"Range", "bytes=700-4299"}});
  ASSERT_TRUE(part);
  EXPECT_EQ(part->status, 206);
  EXPECT_EQ(part->body, whole->body.substr(700, 3600));
  const auto tail = c.Get(path.c_str(), {{"Range", "bytes=-1024"}});
  ASSERT_TRUE(tail);
  EXPECT_EQ(tail->body, std::string(1024, '\0'));  // the end blocks
}

// Nothing a client sends brings the daemon down or makes it fail inside: a seeded stream of
// mangled requests (flipped and cut bytes, wrong types, extreme numbers, junk paths and ids)
// gets 2xx or a 4xx naming what is wrong, never a 5xx or no answer, and the daemon serves on.
TEST(DaemonApi, MangledRequestsGetClearRefusalsAndTheDaemonServesOn) {
  InProcessDaemon d(calstand::testing::fresh_dir("mangled") + "/station.db");
  ApiClient api(d.port());
  std::mt19937 rng(20261201);
  auto pick = [&](std::size_t n) {
    return std::uniform_int_distribution<std::size_t>(0, n - 1)(rng);
  };
  const std::vector<nlohmann::json> oddities = {nullptr,
                                                true,
                                                -1,
                                                0,
                                                1e308,
                                                -1e308,
                                                18446744073709551615ULL,
                                                -9223372036854775807LL - 1,
                                                "",
                                                std::string(300, 'x'),
                                                "\u0000",
                                                nlohmann::json::array(),
                                                nlohmann::json::object(),
                                                nlohmann::json::array({1, "a", nullptr}),
                                                "six-position\n; rm -rf /",
                                                "' OR 1=1 --"};
  const std::vector<std::string> keys = {"procedure", "parameters",   "capture_s", "steps",
                                         "name",      "kind",         "immediate", "reason",
                                         "step",      "temperatures", "x"};
  const std::string good =
      nlohmann::json{{"procedure", "two-position"}, {"parameters", {{"capture_s", 2}}}}.dump();
  const std::vector<std::string> paths = {
      "/runs",          "/runs/1/pause",   "/runs/1/resume",
      "/runs/1/abort",  "/runs/1/skip",    "/runs/0/skip",
      "/runs/-1/abort", "/runs/1/%00",     "/runs/1/../../etc/passwd",
      "/station",       "/calibrations/1x"};
  std::map<int, int> statuses;
  for (int i = 0; i < 300; ++i) {
    std::string body;
    switch (pick(4)) {
      case 0: {  // bytes flipped in a good request
        body = good;
        for (std::size_t k = 0, n = 1 + pick(4); k < n; ++k)
          body[pick(body.size())] = static_cast<char>(pick(256));
        break;
      }
      case 1:  // cut short
        body = good.substr(0, pick(good.size()));
        break;
      case 2: {  // right shape, odd values
        nlohmann::json j = {{"procedure", "two-position"},
                            {"parameters", nlohmann::json::object()}};
        j["parameters"][keys[pick(keys.size())]] = oddities[pick(oddities.size())];
        j[keys[pick(keys.size())]] =
            oddities[pick(oddities.size())];  // may replace "parameters" too
        body = j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
        break;
      }
      default: {  // an inline procedure with odd steps
        nlohmann::json step = {{"kind", oddities[pick(oddities.size())]},
                               {keys[pick(keys.size())], oddities[pick(oddities.size())]}};
        body = nlohmann::json{{"procedure",
                               {{"name", oddities[pick(oddities.size())]}, {"steps", {step}}}}}
                   .dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
      }
    }
    const std::string& path =
        pick(2) == 0 ? paths[0] : paths[pick(paths.size())];  // half to POST /runs
    const Reply r = pick(5) == 0 ? api.get(path) : api.post(path, body);
    ++statuses[r.status];
    ASSERT_TRUE(r.status >= 200 && r.status < 500)
        << r.status << " for " << path << " " << body << ": " << r.raw;
    if (r.status >= 400) {
      EXPECT_TRUE(r.body.is_object() && r.body.contains("error")) << path << ": " << r.raw;
    }
  }
  EXPECT_GT(statuses[400] + statuses[422],
            60);  // most submissions were refused, each with its reason
  EXPECT_EQ(api.get("/station").status, 200);
  const std::int64_t run = api.submit("six-position", kShort);
  ASSERT_GT(run, 0);
  EXPECT_TRUE(wait_until([&] {
                const std::string s = status_of(api, run);
                return s == "completed";
              }) ||
              status_of(api, run) ==
                  "queued");  // behind a mangled but valid submission still running
}

}  // namespace
