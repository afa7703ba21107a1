#include "store/run_store.hpp"

#include <SQLiteCpp/Statement.h>
#include <SQLiteCpp/Transaction.h>

#include <algorithm>
#include <limits>

#include "core/error.hpp"
#include "sql_util.hpp"
#include "store/hash.hpp"
#include "store/run_lock.hpp"
#include "store/run_queue.hpp"
#include "store/units.hpp"

namespace calstand::store {

using detail::guarded;

namespace {

// The columns event_of_row() reads, in its order.
constexpr const char* kEventColumns =
    "SELECT id, run_id, time_s, wall_utc, kind, source, message, detail";

// One row of `kEventColumns`; a station-wide event (run_id NULL) has no run.
EventRecord event_of_row(SQLite::Statement& ev) {
  EventRecord e;
  e.id = ev.getColumn(0).getInt64();
  if (!ev.getColumn(1).isNull()) e.run_id = ev.getColumn(1).getInt64();
  e.time_s = ev.getColumn(2).getDouble();
  e.wall_utc = ev.getColumn(3).getString();
  e.kind = parse_event_kind(ev.getColumn(4).getString());
  e.source = ev.getColumn(5).getString();
  e.message = ev.getColumn(6).getString();
  if (!ev.getColumn(7).isNull()) e.detail = nlohmann::json::parse(ev.getColumn(7).getString());
  return e;
}

std::string dump(const nlohmann::json& j) { return j.is_null() ? "null" : j.dump(); }

StepRecord read_step(SQLite::Statement& q) {
  // Column order of kStepColumns.
  StepRecord s;
  s.id = q.getColumn(0).getInt64();
  s.index = static_cast<std::size_t>(q.getColumn(1).getInt64());
  s.kind = q.getColumn(2).getString();
  s.label = q.getColumn(3).getString();
  s.commanded = nlohmann::json::parse(q.getColumn(4).getString());
  s.origin = q.getColumn(5).getString();
  s.status = parse_step_status(q.getColumn(6).getString());
  s.reason = detail::text_or_empty(q.getColumn(7));
  s.attempts = q.getColumn(8).getInt();
  if (!q.getColumn(9).isNull()) s.good_attempt = q.getColumn(9).getInt();
  s.started_clock_s = detail::optional_double(q.getColumn(10));
  s.ended_clock_s = detail::optional_double(q.getColumn(11));
  s.started_utc = detail::text_or_empty(q.getColumn(12));
  s.ended_utc = detail::text_or_empty(q.getColumn(13));
  return s;
}

constexpr const char* kStepColumns =
    "id, idx, kind, label, commanded, origin, status, reason, attempts, good_attempt, "
    "started_clock_s, ended_clock_s, started_utc, ended_utc";

RunSummary read_summary(SQLite::Statement& q) {
  // Column order of kSummaryQuery.
  RunSummary r;
  r.id = q.getColumn(0).getInt64();
  r.procedure_name = q.getColumn(1).getString();
  r.status = q.getColumn(2).getString();
  r.steps_done = static_cast<std::size_t>(q.getColumn(3).getInt64());
  r.steps_total = static_cast<std::size_t>(q.getColumn(4).getInt64());
  r.created_utc = q.getColumn(5).getString();
  r.started_utc = detail::text_or_empty(q.getColumn(6));
  r.ended_utc = detail::text_or_empty(q.getColumn(7));
  r.exit_reason = detail::text_or_empty(q.getColumn(8));
  return r;
}

// A run whose row says it is being driven (running, paused) while no process holds its run lock
// was cut off: it reads `interrupted` (the row is left as it is; a resume or a daemon's
// recovery takes it from there).
void show_cut_off_as_interrupted(RunSummary& r, const std::string& db_path) {
  if ((r.status == "running" || r.status == "paused") && !RunLock::held(db_path, r.id)) {
    r.status = kInterruptedStatus;
  }
}

constexpr const char* kSummaryQuery =
    "SELECT r.id, r.procedure_name, r.status, "
    "(SELECT COUNT(*) FROM steps s WHERE s.run_id = r.id AND s.status = 'completed'), "
    "(SELECT COUNT(*) FROM steps s WHERE s.run_id = r.id), "
    "r.created_utc, r.started_utc, r.ended_utc, r.exit_reason FROM runs r";

void insert_table_row(SQLite::Statement& st, std::int64_t run, const core::TableState& s) {
  st.reset();
  st.bind(1, run);
  st.bind(2, s.time_s);
  st.bind(3, s.outer.angle_deg);
  st.bind(4, s.inner.angle_deg);
  st.bind(5, s.outer.rate_dps);
  st.bind(6, s.inner.rate_dps);
  st.bind(7, std::string(core::to_string(s.outer.mode)));
  st.bind(8, std::string(core::to_string(s.inner.mode)));
  st.exec();
}

void insert_chamber_row(SQLite::Statement& st, std::int64_t run, const core::ChamberState& s) {
  st.reset();
  st.bind(1, run);
  st.bind(2, s.time_s);
  st.bind(3, s.air_temperature_c);
  st.bind(4, s.setpoint_c);
  st.bind(5, std::string(core::to_string(s.mode)));
  st.exec();
}

constexpr const char* kInsertTable =
    "INSERT INTO table_telemetry (run_id, time_s, outer_deg, inner_deg, outer_rate_dps, "
    "inner_rate_dps, outer_mode, inner_mode) VALUES (?, ?, ?, ?, ?, ?, ?, ?)";
constexpr const char* kInsertChamber =
    "INSERT INTO chamber_telemetry (run_id, time_s, air_c, setpoint_c, mode) "
    "VALUES (?, ?, ?, ?, ?)";

}  // namespace

void RunStore::require_run(std::int64_t run) {
  const bool found = guarded("find run", [&] {
    SQLite::Statement q(db_.sql(), "SELECT 1 FROM runs WHERE id = ?");
    q.bind(1, run);
    return q.executeStep();
  });
  if (!found) {
    throw core::InputError("run " + std::to_string(run), "no such run in " + db_.path());
  }
}

std::int64_t RunStore::upsert_station(const std::string& name, const nlohmann::json& config,
                                      const std::vector<DeviceRecord>& devices) {
  return guarded("upsert station " + name, [&] {
    SQLite::Transaction tx(db_.sql(), SQLite::TransactionBehavior::IMMEDIATE);
    SQLite::Statement up(db_.sql(),
                         "INSERT INTO stations (name, config, updated_utc) VALUES (?, ?, ?) "
                         "ON CONFLICT (name) DO UPDATE SET config = excluded.config, "
                         "updated_utc = excluded.updated_utc RETURNING id");
    up.bind(1, name);
    up.bind(2, dump(config));
    up.bind(3, utc_now_iso8601());
    up.executeStep();
    const std::int64_t id = up.getColumn(0).getInt64();
    up.reset();
    SQLite::Statement del(db_.sql(), "DELETE FROM devices WHERE station_id = ?");
    del.bind(1, id);
    del.exec();
    SQLite::Statement ins(db_.sql(),
                          "INSERT INTO devices (station_id, kind, name, backend) "
                          "VALUES (?, ?, ?, ?)");
    for (const auto& d : devices) {
      ins.reset();
      ins.bind(1, id);
      ins.bind(2, d.kind);
      ins.bind(3, d.name);
      ins.bind(4, d.backend);
      ins.exec();
    }
    tx.commit();
    return id;
  });
}

std::int64_t RunStore::create_run(const NewRun& run) {
  return guarded("insert run", [&] {
    SQLite::Statement st(db_.sql(),
                         "INSERT INTO runs (station_id, procedure_name, procedure_text, "
                         "procedure_sha256, parameters, station_snapshot, status, created_utc) "
                         "VALUES (?, ?, ?, ?, ?, ?, ?, ?)");
    if (run.station_id) {
      st.bind(1, *run.station_id);
    } else {
      st.bind(1);
    }
    st.bind(2, run.procedure_name);
    st.bind(3, run.procedure_text);
    st.bind(4, sha256_hex(run.procedure_text));
    st.bind(5, dump(run.parameters));
    st.bind(6, dump(run.station_snapshot));
    st.bind(7, run.status);
    st.bind(8, utc_now_iso8601());
    st.exec();
    return db_.sql().getLastInsertRowid();
  });
}

std::vector<std::int64_t> RunStore::add_steps(std::int64_t run, const std::vector<NewStep>& steps) {
  require_run(run);
  return guarded("insert steps", [&] {
    SQLite::Transaction tx(db_.sql(), SQLite::TransactionBehavior::IMMEDIATE);
    SQLite::Statement next(db_.sql(),
                           "SELECT COALESCE(MAX(idx) + 1, 0) FROM steps WHERE run_id = ?");
    next.bind(1, run);
    next.executeStep();
    std::int64_t index = next.getColumn(0).getInt64();
    SQLite::Statement ins(db_.sql(),
                          "INSERT INTO steps (run_id, idx, kind, label, commanded, origin) "
                          "VALUES (?, ?, ?, ?, ?, ?)");
    std::vector<std::int64_t> ids;
    ids.reserve(steps.size());
    for (const auto& s : steps) {
      ins.reset();
      ins.bind(1, run);
      ins.bind(2, index++);
      ins.bind(3, s.kind);
      ins.bind(4, s.label);
      ins.bind(5, dump(s.commanded));
      ins.bind(6, s.origin);
      ins.exec();
      ids.push_back(db_.sql().getLastInsertRowid());
    }
    tx.commit();
    return ids;
  });
}

std::int64_t RunStore::step_id(std::int64_t run, std::size_t index) {
  const auto id = guarded("find step", [&]() -> std::optional<std::int64_t> {
    SQLite::Statement q(db_.sql(), "SELECT id FROM steps WHERE run_id = ? AND idx = ?");
    q.bind(1, run);
    q.bind(2, static_cast<std::int64_t>(index));
    if (!q.executeStep()) return std::nullopt;
    return q.getColumn(0).getInt64();
  });
  if (!id) {
    throw core::InputError("run " + std::to_string(run) + " step " + std::to_string(index),
                           "no such step in " + db_.path());
  }
  return *id;
}

void RunStore::mark_step_running(std::int64_t run, std::size_t index, int attempt,
                                 const Stamp& at) {
  const std::int64_t id = step_id(run, index);
  guarded("mark step running", [&] {
    SQLite::Statement st(db_.sql(),
                         "UPDATE steps SET status = 'running', reason = NULL, "
                         "attempts = attempts + 1, good_attempt = NULL, started_clock_s = ?, "
                         "started_utc = ?, ended_clock_s = NULL, ended_utc = NULL "
                         "WHERE id = ?");
    st.bind(1, at.clock_s);
    st.bind(2, at.utc);
    st.bind(3, id);
    st.exec();
  });
  (void)attempt;  // attempts counts starts; the engine's numbering is kept with the samples
}

void RunStore::mark_step_completed(std::int64_t run, std::size_t index, int attempt,
                                   const Stamp& at) {
  const std::int64_t id = step_id(run, index);
  guarded("mark step completed", [&] {
    SQLite::Statement st(db_.sql(),
                         "UPDATE steps SET status = 'completed', reason = NULL, "
                         "good_attempt = ?, ended_clock_s = ?, ended_utc = ? WHERE id = ?");
    st.bind(1, attempt);
    st.bind(2, at.clock_s);
    st.bind(3, at.utc);
    st.bind(4, id);
    st.exec();
  });
}

void RunStore::mark_step_failed(std::int64_t run, std::size_t index, const Stamp& at,
                                const std::string& why) {
  const std::int64_t id = step_id(run, index);
  guarded("mark step failed", [&] {
    SQLite::Statement st(db_.sql(),
                         "UPDATE steps SET status = 'failed', reason = ?, ended_clock_s = ?, "
                         "ended_utc = ? WHERE id = ?");
    st.bind(1, why);
    st.bind(2, at.clock_s);
    st.bind(3, at.utc);
    st.bind(4, id);
    st.exec();
  });
}

void RunStore::mark_step_invalidated(std::int64_t run, std::size_t index, const std::string& why) {
  const std::int64_t id = step_id(run, index);
  guarded("mark step invalidated", [&] {
    SQLite::Statement st(db_.sql(),
                         "UPDATE steps SET status = 'invalidated', reason = ?, "
                         "good_attempt = NULL WHERE id = ?");
    st.bind(1, why);
    st.bind(2, id);
    st.exec();
  });
}

void RunStore::mark_step_skipped(std::int64_t run, std::size_t index, const std::string& why) {
  const std::int64_t id = step_id(run, index);
  guarded("mark step skipped", [&] {
    SQLite::Statement st(db_.sql(), "UPDATE steps SET status = 'skipped', reason = ? WHERE id = ?");
    st.bind(1, why);
    st.bind(2, id);
    st.exec();
  });
}

void RunStore::discard_attempt(std::int64_t run, std::size_t index, int attempt) {
  const std::int64_t id = step_id(run, index);
  guarded("discard attempt", [&] {
    SQLite::Transaction tx(db_.sql(), SQLite::TransactionBehavior::IMMEDIATE);
    for (const char* sql : {"DELETE FROM sample_chunks WHERE step_id = ? AND attempt = ?",
                            "DELETE FROM step_means WHERE step_id = ? AND attempt = ?"}) {
      SQLite::Statement st(db_.sql(), sql);
      st.bind(1, id);
      st.bind(2, attempt);
      st.exec();
    }
    tx.commit();
  });
}

std::int64_t RunStore::add_event(const EventRecord& e) {
  return guarded("insert event", [&] {
    SQLite::Statement st(db_.sql(),
                         "INSERT INTO events (run_id, time_s, wall_utc, kind, source, message, "
                         "detail) VALUES (?, ?, ?, ?, ?, ?, ?)");
    if (e.run_id) {
      st.bind(1, *e.run_id);
    } else {
      st.bind(1);
    }
    st.bind(2, e.time_s);
    st.bind(3, e.wall_utc.empty() ? utc_now_iso8601() : e.wall_utc);
    st.bind(4, std::string(to_string(e.kind)));
    st.bind(5, e.source);
    st.bind(6, e.message);
    if (e.detail.is_null()) {
      st.bind(7);
    } else {
      st.bind(7, e.detail.dump());
    }
    st.exec();
    return db_.sql().getLastInsertRowid();
  });
}

void RunStore::add_table_telemetry(std::int64_t run, const core::TableState& state) {
  add_table_telemetry(run, std::span<const core::TableState>(&state, 1));
}

void RunStore::add_table_telemetry(std::int64_t run, std::span<const core::TableState> states) {
  guarded("insert table telemetry", [&] {
    SQLite::Transaction tx(db_.sql(), SQLite::TransactionBehavior::IMMEDIATE);
    SQLite::Statement st(db_.sql(), kInsertTable);
    for (const auto& s : states) insert_table_row(st, run, s);
    tx.commit();
  });
}

void RunStore::add_chamber_telemetry(std::int64_t run, const core::ChamberState& state) {
  add_chamber_telemetry(run, std::span<const core::ChamberState>(&state, 1));
}

void RunStore::add_chamber_telemetry(std::int64_t run, std::span<const core::ChamberState> states) {
  guarded("insert chamber telemetry", [&] {
    SQLite::Transaction tx(db_.sql(), SQLite::TransactionBehavior::IMMEDIATE);
    SQLite::Statement st(db_.sql(), kInsertChamber);
    for (const auto& s : states) insert_chamber_row(st, run, s);
    tx.commit();
  });
}

std::vector<core::TableState> RunStore::table_telemetry(std::int64_t run, double from_s,
                                                        double to_s) {
  require_run(run);
  return guarded("read table telemetry", [&] {
    SQLite::Statement q(db_.sql(),
                        "SELECT time_s, outer_deg, inner_deg, outer_rate_dps, inner_rate_dps, "
                        "outer_mode, inner_mode FROM table_telemetry "
                        "WHERE run_id = ? AND time_s >= ? AND time_s <= ? ORDER BY time_s, id");
    q.bind(1, run);
    q.bind(2, from_s);
    q.bind(3, to_s);
    const auto mode_of = [](const SQLite::Column& c) {
      const std::string text = c.isNull() ? "" : c.getString();
      for (const auto m : {core::AxisMode::kRest, core::AxisMode::kPosition, core::AxisMode::kRate,
                           core::AxisMode::kSine, core::AxisMode::kFault}) {
        if (text == core::to_string(m)) return m;
      }
      return core::AxisMode::kRest;
    };
    std::vector<core::TableState> rows;
    while (q.executeStep()) {
      core::TableState s;
      s.time_s = q.getColumn(0).getDouble();
      s.outer.angle_deg = q.getColumn(1).getDouble();
      s.inner.angle_deg = q.getColumn(2).getDouble();
      s.outer.rate_dps = q.getColumn(3).getDouble();
      s.inner.rate_dps = q.getColumn(4).getDouble();
      s.outer.mode = mode_of(q.getColumn(5));
      s.inner.mode = mode_of(q.getColumn(6));
      s.outer.fault = s.outer.mode == core::AxisMode::kFault;
      s.inner.fault = s.inner.mode == core::AxisMode::kFault;
      rows.push_back(std::move(s));
    }
    return rows;
  });
}

std::vector<core::ChamberState> RunStore::chamber_telemetry(std::int64_t run, double from_s,
                                                            double to_s) {
  require_run(run);
  return guarded("read chamber telemetry", [&] {
    SQLite::Statement q(db_.sql(),
                        "SELECT time_s, air_c, setpoint_c, mode FROM chamber_telemetry "
                        "WHERE run_id = ? AND time_s >= ? AND time_s <= ? ORDER BY time_s");
    q.bind(1, run);
    q.bind(2, from_s);
    q.bind(3, to_s);
    std::vector<core::ChamberState> rows;
    while (q.executeStep()) {
      core::ChamberState s;
      s.time_s = q.getColumn(0).getDouble();
      s.air_temperature_c = q.getColumn(1).getDouble();
      s.setpoint_c = q.getColumn(2).getDouble();
      const std::string mode = q.getColumn(3).isNull() ? "" : q.getColumn(3).getString();
      for (const auto m :
           {core::ChamberMode::kStandby, core::ChamberMode::kActive, core::ChamberMode::kFault}) {
        if (mode == core::to_string(m)) s.mode = m;
      }
      s.fault = s.mode == core::ChamberMode::kFault;
      rows.push_back(std::move(s));
    }
    return rows;
  });
}

void RunStore::set_run_status(std::int64_t run, const std::string& status,
                              const std::optional<Stamp>& started,
                              const std::optional<Stamp>& ended, const std::string& exit_reason) {
  require_run(run);
  guarded("update run status", [&] {
    SQLite::Statement st(
        db_.sql(),
        "UPDATE runs SET status = ?1, "
        "started_clock_s = CASE WHEN ?2 AND started_utc IS NULL THEN ?3 ELSE started_clock_s END, "
        "started_utc = CASE WHEN ?2 AND started_utc IS NULL THEN ?4 ELSE started_utc END, "
        "ended_clock_s = CASE WHEN ?5 THEN ?6 ELSE ended_clock_s END, "
        "ended_utc = CASE WHEN ?5 THEN ?7 ELSE ended_utc END, "
        "exit_reason = CASE WHEN ?8 <> '' THEN ?8 ELSE exit_reason END WHERE id = ?9");
    st.bind(1, status);
    st.bind(2, started.has_value() ? 1 : 0);
    st.bind(3, started ? started->clock_s : 0.0);
    st.bind(4, started ? started->utc : std::string());
    st.bind(5, ended.has_value() ? 1 : 0);
    st.bind(6, ended ? ended->clock_s : 0.0);
    st.bind(7, ended ? ended->utc : std::string());
    st.bind(8, exit_reason);
    st.bind(9, run);
    st.exec();
  });
}

std::vector<RunSummary> RunStore::list_runs(std::optional<std::size_t> limit,
                                            std::optional<std::int64_t> before_id) {
  return guarded("list runs", [&] {
    // The step counts are subqueries per run: with the limit in SQL only this page pays them.
    SQLite::Statement q(db_.sql(), std::string(kSummaryQuery) +
                                       (before_id ? " WHERE r.id < :before" : "") +
                                       " ORDER BY r.id DESC" + (limit ? " LIMIT :limit" : ""));
    if (before_id) q.bind(":before", *before_id);
    if (limit) {
      q.bind(":limit", static_cast<std::int64_t>(std::min<std::size_t>(
                           *limit, std::numeric_limits<std::int64_t>::max())));
    }
    std::vector<RunSummary> out;
    while (q.executeStep()) {
      out.push_back(read_summary(q));
      show_cut_off_as_interrupted(out.back(), db_.path());
    }
    return out;
  });
}

std::vector<StepRecord> RunStore::load_steps(std::int64_t run) {
  return guarded("load steps", [&] {
    SQLite::Statement q(db_.sql(), std::string("SELECT ") + kStepColumns +
                                       " FROM steps WHERE run_id = ? ORDER BY idx");
    q.bind(1, run);
    std::vector<StepRecord> out;
    while (q.executeStep()) out.push_back(read_step(q));
    return out;
  });
}

std::string RunStore::run_status(std::int64_t run) {
  require_run(run);
  return guarded("read run status", [&] {
    SQLite::Statement q(db_.sql(), "SELECT status FROM runs WHERE id = ?");
    q.bind(1, run);
    q.executeStep();
    return q.getColumn(0).getString();
  });
}

RunRecord RunStore::load_run(std::int64_t run) {
  require_run(run);
  RunRecord r = guarded("load run", [&] {
    RunRecord rec;
    SQLite::Statement s(db_.sql(), std::string(kSummaryQuery) + " WHERE r.id = ?");
    s.bind(1, run);
    s.executeStep();
    rec.summary = read_summary(s);
    show_cut_off_as_interrupted(rec.summary, db_.path());
    SQLite::Statement q(db_.sql(),
                        "SELECT station_id, procedure_text, procedure_sha256, parameters, "
                        "station_snapshot, started_clock_s, ended_clock_s FROM runs WHERE id = ?");
    q.bind(1, run);
    q.executeStep();
    if (!q.getColumn(0).isNull()) rec.station_id = q.getColumn(0).getInt64();
    rec.procedure_text = q.getColumn(1).getString();
    rec.procedure_sha256 = q.getColumn(2).getString();
    rec.parameters = nlohmann::json::parse(q.getColumn(3).getString());
    rec.station_snapshot = nlohmann::json::parse(q.getColumn(4).getString());
    rec.started_clock_s = detail::optional_double(q.getColumn(5));
    rec.ended_clock_s = detail::optional_double(q.getColumn(6));
    SQLite::Statement ev(db_.sql(),
                         std::string(kEventColumns) + " FROM events WHERE run_id = ? ORDER BY id");
    ev.bind(1, run);
    while (ev.executeStep()) rec.events.push_back(event_of_row(ev));
    return rec;
  });
  r.steps = load_steps(run);
  r.units = units_of_run(db_, run);
  return r;
}

std::vector<EventRecord> RunStore::station_events(std::size_t limit) {
  SQLite::Statement ev(db_.sql(), std::string(kEventColumns) +
                                      " FROM events WHERE run_id IS NULL ORDER BY id DESC LIMIT ?");
  ev.bind(1, static_cast<std::int64_t>(limit));
  std::vector<EventRecord> out;
  while (ev.executeStep()) out.push_back(event_of_row(ev));
  std::reverse(out.begin(), out.end());
  return out;
}

std::optional<std::size_t> RunStore::first_unfinished_step(std::int64_t run) {
  require_run(run);
  return guarded("find first unfinished step", [&]() -> std::optional<std::size_t> {
    SQLite::Statement q(db_.sql(),
                        "SELECT MIN(idx) FROM steps WHERE run_id = ? AND status NOT IN "
                        "('completed', 'skipped')");
    q.bind(1, run);
    q.executeStep();
    if (q.getColumn(0).isNull()) return std::nullopt;
    return static_cast<std::size_t>(q.getColumn(0).getInt64());
  });
}

}  // namespace calstand::store
