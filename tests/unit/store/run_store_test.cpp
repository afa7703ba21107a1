#include "store/run_store.hpp"

#include <gtest/gtest.h>

#include "core/error.hpp"
#include "store/hash.hpp"
#include "store/sample_codec.hpp"

namespace calstand::store {
namespace {

NewRun six_position_run(std::optional<std::int64_t> station = std::nullopt) {
  NewRun r;
  r.station_id = station;
  r.procedure_name = "six-position";
  r.procedure_text = R"({"format": "calstand-procedure/1", "steps": []})";
  r.parameters = {{"capture_s", 60}};
  r.station_snapshot = {{"name", "sim-station"}};
  return r;
}

std::vector<NewStep> three_steps() {
  return {{"move", "x up", {{"outer_deg", 0.0}, {"inner_deg", 90.0}}, "steps[0]"},
          {"capture", "x up", {{"duration_s", 60.0}}, "steps[1]"},
          {"rate", "z ccw", {{"inner_rate_dps", -90.0}}, "steps[2].steps[0]"}};
}

class RunStoreTest : public ::testing::Test {
 protected:
  Database db_{":memory:"};
  RunStore store_{db_};
};

TEST(Hash, Sha256OfKnownText) {
  EXPECT_EQ(sha256_hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
}

TEST_F(RunStoreTest, RunRoundTripKeepsProcedureHashParametersAndSnapshot) {
  const auto station = store_.upsert_station("sim-station", {{"seed", 1}},
                                             {{"table", "table", "sim"}, {"imu", "imu0", "sim"}});
  const auto run = store_.create_run(six_position_run(station));
  const RunRecord r = store_.load_run(run);
  EXPECT_EQ(r.summary.id, run);
  EXPECT_EQ(r.summary.procedure_name, "six-position");
  EXPECT_EQ(r.summary.status, "idle");
  EXPECT_EQ(r.station_id, station);
  EXPECT_EQ(r.procedure_text, six_position_run().procedure_text);
  EXPECT_EQ(r.procedure_sha256, sha256_hex(six_position_run().procedure_text));
  EXPECT_EQ(r.parameters, six_position_run().parameters);
  EXPECT_EQ(r.station_snapshot, six_position_run().station_snapshot);
  EXPECT_FALSE(r.summary.created_utc.empty());
  EXPECT_TRUE(r.summary.started_utc.empty());
}

TEST_F(RunStoreTest, UpsertStationReplacesConfigAndDevices) {
  const auto a = store_.upsert_station("s", {{"v", 1}}, {{"imu", "imu0", "sim"}});
  const auto b = store_.upsert_station("s", {{"v", 2}}, {{"imu", "imu1", "serial"}});
  EXPECT_EQ(a, b);
  EXPECT_EQ(db_.sql().execAndGet("SELECT config FROM stations").getString(), R"({"v":2})");
  EXPECT_EQ(db_.sql().execAndGet("SELECT group_concat(name) FROM devices").getString(), "imu1");
}

TEST_F(RunStoreTest, StepsRoundTripWithTransitions) {
  const auto run = store_.create_run(six_position_run());
  const auto ids = store_.add_steps(run, three_steps());
  ASSERT_EQ(ids.size(), 3u);
  EXPECT_EQ(store_.step_id(run, 2), ids[2]);
  store_.mark_step_running(run, 0, 1, {10.0, "2024-01-01T00:00:10.000Z"});
  store_.mark_step_completed(run, 0, 1, {12.5, "2024-01-01T00:00:12.500Z"});
  store_.mark_step_running(run, 1, 1, {13.0, "t"});
  store_.mark_step_invalidated(run, 1, "chamber left its band");
  store_.mark_step_running(run, 1, 2, {14.0, "t"});

  const auto steps = store_.load_steps(run);
  ASSERT_EQ(steps.size(), 3u);
  EXPECT_EQ(steps[0].status, StepStatus::kCompleted);
  EXPECT_EQ(steps[0].kind, "move");
  EXPECT_EQ(steps[0].commanded, three_steps()[0].commanded);
  EXPECT_EQ(steps[0].good_attempt, 1);
  EXPECT_EQ(steps[0].started_clock_s, 10.0);
  EXPECT_EQ(steps[0].ended_clock_s, 12.5);
  EXPECT_EQ(steps[0].ended_utc, "2024-01-01T00:00:12.500Z");
  EXPECT_EQ(steps[1].status, StepStatus::kRunning);
  EXPECT_EQ(steps[1].attempts, 2);
  EXPECT_EQ(steps[1].started_clock_s, 14.0);
  EXPECT_EQ(steps[2].origin, "steps[2].steps[0]");
  EXPECT_EQ(steps[2].status, StepStatus::kPending);

  // A second batch of steps continues the indexes.
  store_.add_steps(run, {{"wait", "w", nlohmann::json::object(), "steps[3]"}});
  EXPECT_EQ(store_.load_steps(run).back().index, 3u);
}

TEST_F(RunStoreTest, FirstUnfinishedStepSkipsCompletedAndSkipped) {
  const auto run = store_.create_run(six_position_run());
  store_.add_steps(run, three_steps());
  EXPECT_EQ(store_.first_unfinished_step(run), 0u);
  store_.mark_step_running(run, 0, 1, {1.0, "t"});
  store_.mark_step_completed(run, 0, 1, {2.0, "t"});
  store_.mark_step_skipped(run, 1, "operator");
  EXPECT_EQ(store_.first_unfinished_step(run), 2u);
  store_.mark_step_running(run, 2, 1, {3.0, "t"});
  store_.mark_step_failed(run, 2, {4.0, "t"}, "table fault");
  EXPECT_EQ(store_.first_unfinished_step(run), 2u);
  EXPECT_EQ(store_.load_steps(run)[2].reason, "table fault");
  store_.mark_step_running(run, 2, 2, {5.0, "t"});
  store_.mark_step_completed(run, 2, 2, {6.0, "t"});
  EXPECT_EQ(store_.first_unfinished_step(run), std::nullopt);
}

TEST_F(RunStoreTest, EventsRoundTripInOrder) {
  const auto run = store_.create_run(six_position_run());
  EventRecord fault;
  fault.run_id = run;
  fault.time_s = 12.0;
  fault.kind = EventKind::kFault;
  fault.source = "table";
  fault.message = "outer axis following error";
  fault.detail = {{"error_deg", 0.5}};
  EventRecord op;
  op.run_id = run;
  op.time_s = 13.0;
  op.kind = EventKind::kOperator;
  op.source = "operator";
  op.message = "pause";
  op.wall_utc = "2024-01-01T00:00:00.000Z";
  store_.add_event(fault);
  store_.add_event(op);
  const auto events = store_.load_run(run).events;
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[0].kind, EventKind::kFault);
  EXPECT_EQ(events[0].source, "table");
  EXPECT_EQ(events[0].message, "outer axis following error");
  EXPECT_EQ(events[0].detail, fault.detail);
  EXPECT_FALSE(events[0].wall_utc.empty());
  EXPECT_EQ(events[1].kind, EventKind::kOperator);
  EXPECT_TRUE(events[1].detail.is_null());
  EXPECT_EQ(events[1].wall_utc, "2024-01-01T00:00:00.000Z");
}

TEST_F(RunStoreTest, RunStatusListAndCounts) {
  const auto a = store_.create_run(six_position_run());
  const auto b = store_.create_run(six_position_run());
  store_.add_steps(b, three_steps());
  store_.mark_step_running(b, 0, 1, {1.0, "t"});
  store_.mark_step_completed(b, 0, 1, {2.0, "t"});
  store_.set_run_status(b, "running", Stamp{1.0, "2024-01-01T00:00:01.000Z"});
  store_.set_run_status(b, "paused", Stamp{9.0, "later"});  // start time kept
  store_.set_run_status(b, "aborted", std::nullopt, Stamp{20.0, "2024-01-01T00:00:20.000Z"},
                        "operator abort");
  const auto runs = store_.list_runs();
  ASSERT_EQ(runs.size(), 2u);
  EXPECT_EQ(runs[0].id, b);  // newest first
  EXPECT_EQ(runs[1].id, a);
  EXPECT_EQ(runs[0].status, "aborted");
  EXPECT_EQ(runs[0].steps_done, 1u);
  EXPECT_EQ(runs[0].steps_total, 3u);
  EXPECT_EQ(runs[0].started_utc, "2024-01-01T00:00:01.000Z");
  EXPECT_EQ(runs[0].ended_utc, "2024-01-01T00:00:20.000Z");
  EXPECT_EQ(runs[0].exit_reason, "operator abort");
  EXPECT_EQ(store_.load_run(b).started_clock_s, 1.0);
  EXPECT_EQ(store_.load_run(b).ended_clock_s, 20.0);
  EXPECT_EQ(store_.run_status(b), "aborted");
  EXPECT_EQ(store_.run_status(a), store_.load_run(a).summary.status);
  // The plain-SQL view agrees.
  EXPECT_EQ(db_.sql()
                .execAndGet("SELECT steps_done FROM run_overview WHERE id = " + std::to_string(b))
                .getInt(),
            1);
}

TEST_F(RunStoreTest, TelemetryIsStored) {
  const auto run = store_.create_run(six_position_run());
  core::TableState t;
  t.time_s = 1.5;
  t.outer.angle_deg = 90.0;
  t.inner.rate_dps = -10.0;
  t.inner.mode = core::AxisMode::kRate;
  core::ChamberState c;
  c.time_s = 2.0;
  c.air_temperature_c = 24.5;
  c.setpoint_c = 25.0;
  c.mode = core::ChamberMode::kActive;
  store_.add_table_telemetry(run, t);
  std::vector<core::ChamberState> many(5, c);
  store_.add_chamber_telemetry(run, many);
  SQLite::Statement q(db_.sql(),
                      "SELECT time_s, outer_deg, inner_rate_dps, inner_mode FROM table_telemetry");
  ASSERT_TRUE(q.executeStep());
  EXPECT_EQ(q.getColumn(0).getDouble(), 1.5);
  EXPECT_EQ(q.getColumn(1).getDouble(), 90.0);
  EXPECT_EQ(q.getColumn(2).getDouble(), -10.0);
  EXPECT_EQ(q.getColumn(3).getString(), std::string(core::to_string(core::AxisMode::kRate)));
  EXPECT_EQ(db_.sql().execAndGet("SELECT COUNT(*), MAX(air_c) FROM chamber_telemetry").getInt(), 5);
}

TEST_F(RunStoreTest, ChamberTelemetryReadsBackInTimeOrderWithinTheWindow) {
  const auto run = store_.create_run(six_position_run());
  const auto other = store_.create_run(six_position_run());
  std::vector<core::ChamberState> rows;
  for (const double t : {3.0, 1.0, 2.0, 4.0}) {
    core::ChamberState c;
    c.time_s = t;
    c.air_temperature_c = 20.0 + t;
    c.setpoint_c = 45.0;
    c.mode = t < 4.0 ? core::ChamberMode::kActive : core::ChamberMode::kFault;
    rows.push_back(c);
  }
  store_.add_chamber_telemetry(run, rows);
  store_.add_chamber_telemetry(other, rows.front());
  const auto all = store_.chamber_telemetry(run);
  ASSERT_EQ(all.size(), 4u);
  for (std::size_t i = 0; i < all.size(); ++i) {
    EXPECT_EQ(all[i].time_s, 1.0 + static_cast<double>(i));
    EXPECT_EQ(all[i].air_temperature_c, 21.0 + static_cast<double>(i));
    EXPECT_EQ(all[i].setpoint_c, 45.0);
  }
  EXPECT_EQ(all[0].mode, core::ChamberMode::kActive);
  EXPECT_EQ(all[3].mode, core::ChamberMode::kFault);
  EXPECT_TRUE(all[3].fault);
  const auto window = store_.chamber_telemetry(run, 2.0, 3.0);
  ASSERT_EQ(window.size(), 2u);
  EXPECT_EQ(window[0].time_s, 2.0);
  EXPECT_EQ(window[1].time_s, 3.0);
  EXPECT_THROW(store_.chamber_telemetry(run + 100), core::InputError);
}

TEST(TelemetryDecimator, KeepsOneRowPerPeriod) {
  TelemetryDecimator d(0.1);
  int kept = 0;
  for (int i = 0; i < 1000; ++i) kept += d.accept(i * 0.01) ? 1 : 0;  // 10 s at 100 Hz
  EXPECT_NEAR(kept, 100, 1);
}

TEST_F(RunStoreTest, DiscardAttemptDeletesOnlyThatAttempt) {
  const auto run = store_.create_run(six_position_run());
  const auto step = store_.add_steps(run, three_steps())[1];
  core::ImuSample s;
  const auto blob = encode_chunk(std::span(&s, 1), SampleEncoding::kCompact);
  for (int attempt : {1, 2}) {
    SQLite::Statement ins(db_.sql(),
                          "INSERT INTO sample_chunks (run_id, step_id, attempt, device, "
                          "first_receive_time_s, last_receive_time_s, count, encoding, data) "
                          "VALUES (?, ?, ?, 'imu0', 0, 0, 1, 1, ?)");
    ins.bind(1, run);
    ins.bind(2, step);
    ins.bind(3, attempt);
    ins.bind(4, blob.data(), static_cast<int>(blob.size()));
    ins.exec();
  }
  store_.discard_attempt(run, 1, 1);
  EXPECT_EQ(db_.sql().execAndGet("SELECT group_concat(attempt) FROM sample_chunks").getString(),
            "2");
}

TEST_F(RunStoreTest, UnknownRunOrStepIsAnInputError) {
  EXPECT_THROW(store_.load_run(42), core::InputError);
  EXPECT_THROW(store_.run_status(42), core::InputError);
  EXPECT_THROW(store_.add_steps(42, three_steps()), core::InputError);
  const auto run = store_.create_run(six_position_run());
  EXPECT_THROW(store_.mark_step_running(run, 7, 1, {0.0, "t"}), core::InputError);
  try {
    store_.first_unfinished_step(42);
    FAIL();
  } catch (const core::InputError& e) {
    EXPECT_EQ(e.where(), "run 42");
  }
}

}  // namespace
}  // namespace calstand::store
