#include "fleet/sync.hpp"

#include <SQLiteCpp/Statement.h>
#include <fmt/format.h>

#include <chrono>
#include <map>
#include <optional>
#include <pqxx/pqxx>
#include <set>

#include "core/error.hpp"
#include "fleet/central_error.hpp"
#include "fleet/central_schema.hpp"
#include "store/error.hpp"
#include "store/run_store.hpp"
#include "store/stamp.hpp"
#include "store/station_identity.hpp"

namespace calstand::fleet {
namespace {

template <class T>
std::optional<T> optional_field(const pqxx::field& f) {
  if (f.is_null()) return std::nullopt;
  return f.as<T>();
}

std::optional<std::string> nonempty(const std::string& s) {
  if (s.empty()) return std::nullopt;
  return s;
}

std::optional<std::string> json_or_null(const nlohmann::json& j) {
  if (j.is_null()) return std::nullopt;
  return j.dump();
}

// The central ids of `local_ids` of the station's rows in `table` (runs or calibrations).
std::map<std::int64_t, std::int64_t> central_ids(pqxx::transaction_base& tx,
                                                 const std::string& table,
                                                 const std::string& station,
                                                 const std::set<std::int64_t>& local_ids) {
  std::map<std::int64_t, std::int64_t> out;
  if (local_ids.empty()) return out;
  std::string array = "{";
  for (std::int64_t id : local_ids) array += (array.size() > 1 ? "," : "") + std::to_string(id);
  array += "}";
  const pqxx::result r = tx.exec_params(
      "SELECT local_id, id FROM " + table + " WHERE station = $1 AND local_id = ANY($2::bigint[])",
      station, array);
  for (const auto& row : r) out[row[0].as<std::int64_t>()] = row[1].as<std::int64_t>();
  return out;
}

// The local ids in (from, to] of the station's rows in central `table`.
std::set<std::int64_t> central_local_ids(pqxx::transaction_base& tx, const std::string& table,
                                         const std::string& station, std::int64_t from,
                                         std::int64_t to) {
  std::set<std::int64_t> out;
  const pqxx::result r = tx.exec_params(
      "SELECT local_id FROM " + table + " WHERE station = $1 AND local_id > $2 AND local_id <= $3",
      station, from, to);
  for (const auto& row : r) out.insert(row[0].as<std::int64_t>());
  return out;
}

class StationSync {
 public:
  StationSync(store::Database& station, pqxx::connection& central, const SyncOptions& options)
      : station_(station), central_(central), options_(options) {}

  SyncReport run() {
    const auto started = std::chrono::steady_clock::now();
    if (station_.schema_version() != kSyncedStoreSchemaVersion) {
      throw store::StoreError(
          "sync " + station_.path(),
          fmt::format("the station database is at schema version {}, this sync reads version {}; "
                      "refused: a calstand whose sync knows version {} is needed",
                      station_.schema_version(), kSyncedStoreSchemaVersion,
                      station_.schema_version()));
    }
    report_.station_uuid = store::station_uuid(station_);
    require_central_schema(central_,
                           fmt::format("database {} on {}", central_.dbname(),
                                       central_.hostname() ? central_.hostname() : "a socket"),
                           "station " + options_.station_name);
    prepare();
    register_station();
    copy_runs();
    if (!stopped()) copy_calibrations();
    if (!stopped()) copy_acceptances();
    if (!stopped()) copy_fits();
    if (options_.samples && !stopped()) copy_samples();
    report_.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    return report_;
  }

 private:
  bool stopped() {
    if (options_.stop_requested && options_.stop_requested()) report_.stopped = true;
    return report_.stopped;
  }

  // Serialises syncs of this station (a daemon's publisher and a `calstand sync` by hand);
  // released when the transaction ends.
  void lock_station(pqxx::transaction_base& tx) {
    tx.exec_params("SELECT pg_advisory_xact_lock(hashtext($1))", report_.station_uuid);
  }

  std::int64_t read_cursor(pqxx::transaction_base& tx, const std::string& stream) {
    const pqxx::result r =
        tx.exec_params("SELECT last_local_id FROM sync_cursors WHERE station = $1 AND stream = $2",
                       report_.station_uuid, stream);
    return r.empty() ? 0 : r[0][0].as<std::int64_t>();
  }

  void write_cursor(pqxx::transaction_base& tx, const std::string& stream, std::int64_t at) {
    tx.exec_params(
        "INSERT INTO sync_cursors (station, stream, last_local_id) VALUES ($1, $2, $3) "
        "ON CONFLICT (station, stream) DO UPDATE SET last_local_id = EXCLUDED.last_local_id",
        report_.station_uuid, stream, at);
  }

  void commit(pqxx::work& tx) {
    tx.commit();
    ++report_.copied.transactions;
  }

  void prepare() {
    try {
      central_.prepare("calstand_insert_run",
                       "INSERT INTO runs (station, local_id, procedure_name, procedure_text, "
                       "procedure_sha256, parameters, station_snapshot, status, exit_reason, "
                       "created_utc, started_utc, started_clock_s, ended_utc, ended_clock_s) "
                       "VALUES ($1, $2, $3, $4, $5, $6::jsonb, $7::jsonb, $8, $9, $10, $11, $12, "
                       "$13, $14) ON CONFLICT (station, local_id) DO NOTHING RETURNING id");
      central_.prepare("calstand_insert_step",
                       "INSERT INTO steps (station, local_id, run_id, idx, kind, label, "
                       "commanded, origin, status, reason, attempts, good_attempt, started_utc, "
                       "started_clock_s, ended_utc, ended_clock_s) VALUES ($1, $2, $3, $4, $5, "
                       "$6, $7::jsonb, $8, $9, $10, $11, $12, $13, $14, $15, $16)");
      central_.prepare("calstand_insert_event",
                       "INSERT INTO events (station, local_id, run_id, time_s, wall_utc, kind, "
                       "source, message, detail) VALUES ($1, $2, $3, $4, $5, $6, $7, $8, "
                       "$9::jsonb)");
      central_.prepare("calstand_insert_unit",
                       "INSERT INTO run_units (station, run_id, imu, model, serial, source) "
                       "VALUES ($1, $2, $3, $4, $5, $6)");
      central_.prepare("calstand_insert_calibration",
                       "INSERT INTO calibrations (station, local_id, run_id, imu, model, record, "
                       "created_utc, serial) VALUES ($1, $2, $3, $4, $5, $6::jsonb, $7, $8) "
                       "ON CONFLICT (station, local_id) DO NOTHING");
      central_.prepare("calstand_insert_acceptance",
                       "INSERT INTO acceptances (station, local_id, calibration_id, spec_name, "
                       "spec_sha256, verdict, result, created_utc) VALUES ($1, $2, $3, $4, $5, "
                       "$6, $7::jsonb, $8) ON CONFLICT (station, local_id) DO NOTHING");
      central_.prepare("calstand_insert_fit",
                       "INSERT INTO fits (station, local_id, run_id, device, command, model, "
                       "custom_terms, sensors, parameters, chi2_dof, rms_gyro_dps, "
                       "rms_accel_mps2, rms_turn_deg, created_utc) VALUES ($1, $2, $3, $4, $5, "
                       "$6, $7::jsonb, $8, $9, $10, $11, $12, $13, $14) "
                       "ON CONFLICT (station, local_id) DO NOTHING");
      central_.prepare("calstand_insert_chunk",
                       "INSERT INTO sample_chunks (station, local_id, run_id, step_idx, attempt, "
                       "device, first_receive_time_s, last_receive_time_s, count, encoding, "
                       "data) VALUES ($1, $2, $3, $4, $5, $6, $7, $8, $9, $10, $11) "
                       "ON CONFLICT (station, local_id) DO NOTHING");
    } catch (...) {
      rethrow_as_central("prepare statements");
    }
  }

  void register_station() {
    try {
      pqxx::work tx(central_);
      lock_station(tx);
      tx.exec_params(
          "INSERT INTO stations (uuid, name, store_schema, registered_utc) "
          "VALUES ($1, $2, $3, $4) ON CONFLICT (uuid) DO NOTHING",
          report_.station_uuid, options_.station_name, station_.schema_version(),
          store::utc_now_iso8601());
      const pqxx::result r =
          tx.exec_params("SELECT name FROM stations WHERE uuid = $1", report_.station_uuid);
      if (r.empty()) {
        throw CentralError(
            "register station " + report_.station_uuid,
            "that station id is registered to another database role; a station syncs as the "
            "role it first registered with (docs/fleet.md)");
      }
      report_.station_name = r[0][0].as<std::string>();
      commit(tx);
    } catch (...) {
      rethrow_as_central("register station " + report_.station_uuid);
    }
  }

  // Inserts one ended run with its steps, events and units; returns the rows written (0 when
  // another sync had copied it).
  std::int64_t insert_run(pqxx::work& tx, std::int64_t local_run) {
    store::RunStore runs(station_);
    const store::RunRecord run = runs.load_run(local_run);
    const std::string& id = report_.station_uuid;
    const pqxx::result inserted = tx.exec_prepared(
        "calstand_insert_run", id, local_run, run.summary.procedure_name, run.procedure_text,
        run.procedure_sha256, run.parameters.dump(), run.station_snapshot.dump(),
        run.summary.status, nonempty(run.summary.exit_reason), run.summary.created_utc,
        nonempty(run.summary.started_utc), run.started_clock_s, nonempty(run.summary.ended_utc),
        run.ended_clock_s);
    if (inserted.empty()) return 0;
    const auto central_run = inserted[0][0].as<std::int64_t>();
    for (const store::StepRecord& s : run.steps) {
      tx.exec_prepared("calstand_insert_step", id, s.id, central_run,
                       static_cast<std::int64_t>(s.index), s.kind, s.label, s.commanded.dump(),
                       s.origin, std::string(store::to_string(s.status)), nonempty(s.reason),
                       s.attempts, s.good_attempt, nonempty(s.started_utc), s.started_clock_s,
                       nonempty(s.ended_utc), s.ended_clock_s);
    }
    for (const store::EventRecord& e : run.events) {
      tx.exec_prepared("calstand_insert_event", id, e.id, central_run, e.time_s, e.wall_utc,
                       std::string(store::to_string(e.kind)), e.source, e.message,
                       json_or_null(e.detail));
    }
    for (const store::RunUnit& u : run.units) {
      tx.exec_prepared("calstand_insert_unit", id, central_run, u.imu, u.model, u.serial, u.source);
    }
    ++report_.copied.runs;
    report_.copied.steps += static_cast<std::int64_t>(run.steps.size());
    report_.copied.events += static_cast<std::int64_t>(run.events.size());
    report_.copied.run_units += static_cast<std::int64_t>(run.units.size());
    return 1 + static_cast<std::int64_t>(run.steps.size() + run.events.size() + run.units.size());
  }

  /// One local row of an append-only stream: its id and the local id of the row it hangs on
  /// (a run, or for an acceptance a calibration).
  struct LocalRef {
    std::int64_t id = 0;
    std::int64_t parent = 0;
    bool eligible = true;  ///< runs: ended
  };

  /// The walk shared by every stream: windows of local rows above the cursor, each window one
  /// central transaction that copies what is missing and moves the cursor over the rows that
  /// are now all central (a row that must wait, e.g. a run still running, stops the cursor
  /// there for this sync; rows after it are still copied, and found central next time).
  ///
  /// `read_window(after, limit)`: local rows with id > after, by id. `parent_table`: the
  /// central table of the parents ("" for runs themselves). `copy(tx, ref, central_parent)`:
  /// inserts the row, returns the rows written.
  template <class ReadWindow, class Copy>
  void copy_stream(const std::string& stream, const std::string& table,
                   const std::string& parent_table, std::size_t window_rows, ReadWindow read_window,
                   Copy copy) {
    const std::string operation = "copy " + stream;
    try {
      std::optional<std::int64_t> scan_from;
      bool contiguous = true;
      while (!stopped()) {
        pqxx::work tx(central_);
        lock_station(tx);
        const std::int64_t cursor = read_cursor(tx, stream);
        if (!scan_from) scan_from = cursor;
        const std::vector<LocalRef> window = read_window(std::max(cursor, *scan_from), window_rows);
        if (window.empty()) break;
        const std::set<std::int64_t> present = central_local_ids(
            tx, table, report_.station_uuid, window.front().id - 1, window.back().id);
        std::map<std::int64_t, std::int64_t> parents;
        if (!parent_table.empty()) {
          std::set<std::int64_t> wanted;
          for (const LocalRef& r : window) wanted.insert(r.parent);
          parents = central_ids(tx, parent_table, report_.station_uuid, wanted);
        }
        std::int64_t moved_cursor = cursor;
        std::int64_t written = 0;
        std::int64_t last_seen = *scan_from;
        for (const LocalRef& r : window) {
          bool central = present.count(r.id) != 0;
          if (!central && r.eligible) {
            if (parent_table.empty()) {
              written += copy(tx, r, 0);
              central = true;
            } else if (const auto p = parents.find(r.parent); p != parents.end()) {
              written += copy(tx, r, p->second);
              central = true;
            }
          }
          if (!central) {
            if (stream == "runs") report_.waiting_runs.push_back(r.id);
            contiguous = false;
          }
          if (contiguous && central) moved_cursor = r.id;
          last_seen = r.id;
          if (written >= static_cast<std::int64_t>(options_.batch_rows)) break;
        }
        if (moved_cursor != cursor) write_cursor(tx, stream, moved_cursor);
        commit(tx);
        scan_from = last_seen;
      }
    } catch (...) {
      rethrow_as_central(operation);
    }
  }

  std::vector<LocalRef> read_local(const std::string& sql, std::int64_t after, std::size_t limit,
                                   bool runs) {
    SQLite::Statement q(station_.sql(), sql);
    q.bind(1, after);
    q.bind(2, static_cast<std::int64_t>(limit));
    std::vector<LocalRef> out;
    while (q.executeStep()) {
      LocalRef r;
      r.id = q.getColumn(0).getInt64();
      if (runs) {
        r.eligible = store::run_has_ended(q.getColumn(1).getString());
      } else {
        r.parent = q.getColumn(1).getInt64();
      }
      out.push_back(r);
    }
    return out;
  }

  void copy_runs() {
    // A window of runs is small: a run carries its steps, events and units.
    copy_stream(
        "runs", "runs", "", 16,
        [&](std::int64_t after, std::size_t limit) {
          return read_local("SELECT id, status FROM runs WHERE id > ? ORDER BY id LIMIT ?", after,
                            limit, true);
        },
        [&](pqxx::work& tx, const LocalRef& r, std::int64_t) { return insert_run(tx, r.id); });
  }

  void copy_calibrations() {
    copy_stream(
        "calibrations", "calibrations", "runs", options_.batch_rows,
        [&](std::int64_t after, std::size_t limit) {
          return read_local("SELECT id, run_id FROM calibrations WHERE id > ? ORDER BY id LIMIT ?",
                            after, limit, false);
        },
        [&](pqxx::work& tx, const LocalRef& r, std::int64_t central_run) -> std::int64_t {
          SQLite::Statement q(station_.sql(),
                              "SELECT imu, model, record, created_utc, serial FROM calibrations "
                              "WHERE id = ?");
          q.bind(1, r.id);
          if (!q.executeStep()) return 0;
          tx.exec_prepared("calstand_insert_calibration", report_.station_uuid, r.id, central_run,
                           q.getColumn(0).getString(), q.getColumn(1).getString(),
                           q.getColumn(2).getString(), q.getColumn(3).getString(),
                           q.getColumn(4).getString());
          ++report_.copied.calibrations;
          return 1;
        });
  }

  void copy_acceptances() {
    copy_stream(
        "acceptances", "acceptances", "calibrations", options_.batch_rows,
        [&](std::int64_t after, std::size_t limit) {
          return read_local(
              "SELECT id, calibration_id FROM acceptances WHERE id > ? ORDER BY id LIMIT ?", after,
              limit, false);
        },
        [&](pqxx::work& tx, const LocalRef& r, std::int64_t central_calibration) -> std::int64_t {
          SQLite::Statement q(station_.sql(),
                              "SELECT spec_name, spec_sha256, verdict, result, created_utc FROM "
                              "acceptances WHERE id = ?");
          q.bind(1, r.id);
          if (!q.executeStep()) return 0;
          tx.exec_prepared("calstand_insert_acceptance", report_.station_uuid, r.id,
                           central_calibration, q.getColumn(0).getString(),
                           q.getColumn(1).getString(), q.getColumn(2).getString(),
                           q.getColumn(3).getString(), q.getColumn(4).getString());
          ++report_.copied.acceptances;
          return 1;
        });
  }

  void copy_fits() {
    copy_stream(
        "fits", "fits", "runs", options_.batch_rows,
        [&](std::int64_t after, std::size_t limit) {
          return read_local("SELECT id, run_id FROM fits WHERE id > ? ORDER BY id LIMIT ?", after,
                            limit, false);
        },
        [&](pqxx::work& tx, const LocalRef& r, std::int64_t central_run) -> std::int64_t {
          SQLite::Statement q(station_.sql(),
                              "SELECT device, command, model, custom_terms, sensors, parameters, "
                              "chi2_dof, rms_gyro_dps, rms_accel_mps2, rms_turn_deg, created_utc "
                              "FROM fits WHERE id = ?");
          q.bind(1, r.id);
          if (!q.executeStep()) return 0;
          const auto real = [&](int column) -> std::optional<double> {
            if (q.getColumn(column).isNull()) return std::nullopt;
            return q.getColumn(column).getDouble();
          };
          tx.exec_prepared("calstand_insert_fit", report_.station_uuid, r.id, central_run,
                           q.getColumn(0).getString(), q.getColumn(1).getString(),
                           q.getColumn(2).getString(), q.getColumn(3).getString(),
                           q.getColumn(4).getString(), q.getColumn(5).getInt(), real(6), real(7),
                           real(8), real(9), q.getColumn(10).getString());
          ++report_.copied.fits;
          return 1;
        });
  }

  void copy_samples() {
    try {
      // The copied runs whose chunks are not all here yet (their runs have ended: the chunks
      // do not change any more).
      std::vector<std::pair<std::int64_t, std::int64_t>> pending;  // local run, central run
      {
        pqxx::read_transaction tx(central_);
        const pqxx::result r = tx.exec_params(
            "SELECT r.local_id, r.id FROM runs r LEFT JOIN sample_cursors c ON c.run_id = r.id "
            "WHERE r.station = $1 AND c.complete IS NOT TRUE ORDER BY r.local_id",
            report_.station_uuid);
        for (const auto& row : r) {
          pending.emplace_back(row[0].as<std::int64_t>(), row[1].as<std::int64_t>());
        }
      }
      SQLite::Statement q(station_.sql(),
                          "SELECT c.id, s.idx, c.attempt, c.device, c.first_receive_time_s, "
                          "c.last_receive_time_s, c.count, c.encoding, c.data FROM sample_chunks c "
                          "JOIN steps s ON s.id = c.step_id WHERE c.run_id = ? AND c.id > ? "
                          "ORDER BY c.id LIMIT ?");
      for (const auto& [local_run, central_run] : pending) {
        bool complete = false;
        while (!complete && !stopped()) {
          pqxx::work tx(central_);
          lock_station(tx);
          const pqxx::result at = tx.exec_params(
              "SELECT last_local_id, complete FROM sample_cursors WHERE run_id = $1", central_run);
          std::int64_t cursor = at.empty() ? 0 : at[0][0].as<std::int64_t>();
          complete = !at.empty() && at[0][1].as<bool>();
          if (complete) break;
          q.reset();
          q.bind(1, local_run);
          q.bind(2, cursor);
          q.bind(3, static_cast<std::int64_t>(options_.batch_chunks));
          std::size_t fetched = 0;
          while (q.executeStep()) {
            ++fetched;
            const std::int64_t chunk = q.getColumn(0).getInt64();
            const auto* data = static_cast<const unsigned char*>(q.getColumn(8).getBlob());
            const auto bytes = static_cast<std::size_t>(q.getColumn(8).getBytes());
            tx.exec_prepared("calstand_insert_chunk", report_.station_uuid, chunk, central_run,
                             q.getColumn(1).getInt(), q.getColumn(2).getInt(),
                             q.getColumn(3).getString(), q.getColumn(4).getDouble(),
                             q.getColumn(5).getDouble(), q.getColumn(6).getInt(),
                             q.getColumn(7).getInt(), pqxx::binarystring(data, bytes));
            ++report_.copied.sample_chunks;
            report_.copied.samples += q.getColumn(6).getInt64();
            report_.copied.sample_bytes += static_cast<std::int64_t>(bytes);
            cursor = chunk;
          }
          complete = fetched < options_.batch_chunks;
          tx.exec_params(
              "INSERT INTO sample_cursors (station, run_id, last_local_id, complete) "
              "VALUES ($1, $2, $3, $4) ON CONFLICT (run_id) DO UPDATE SET "
              "last_local_id = EXCLUDED.last_local_id, complete = EXCLUDED.complete",
              report_.station_uuid, central_run, cursor, complete);
          commit(tx);
        }
        if (stopped()) return;
      }
    } catch (...) {
      rethrow_as_central("copy samples");
    }
  }

  store::Database& station_;
  pqxx::connection& central_;
  const SyncOptions& options_;
  SyncReport report_;
};

}  // namespace

void SyncOptions::validate() const {
  if (station_name.empty()) throw core::InputError("station name", "empty");
  if (batch_rows == 0) throw core::InputError("batch rows", "must be at least 1");
  if (batch_chunks == 0) throw core::InputError("batch chunks", "must be at least 1");
}

SyncReport sync_station(store::Database& station, pqxx::connection& central,
                        const SyncOptions& options) {
  options.validate();
  return StationSync(station, central, options).run();
}

nlohmann::json to_json(const SyncReport& report) {
  const SyncCounts& c = report.copied;
  return {{"station", {{"uuid", report.station_uuid}, {"name", report.station_name}}},
          {"copied",
           {{"runs", c.runs},
            {"steps", c.steps},
            {"events", c.events},
            {"run_units", c.run_units},
            {"calibrations", c.calibrations},
            {"acceptances", c.acceptances},
            {"fits", c.fits},
            {"sample_chunks", c.sample_chunks},
            {"samples", c.samples},
            {"sample_bytes", c.sample_bytes},
            {"transactions", c.transactions}}},
          {"waiting_runs", report.waiting_runs},
          {"seconds", report.seconds},
          {"stopped", report.stopped}};
}

}  // namespace calstand::fleet
