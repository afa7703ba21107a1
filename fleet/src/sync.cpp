#include "fleet/sync.hpp"

#include <SQLiteCpp/Column.h>
#include <SQLiteCpp/Statement.h>
#include <fmt/format.h>

#include <array>
#include <chrono>
#include <map>
#include <optional>
#include <pqxx/pqxx>
#include <set>
#include <stdexcept>
#include <string_view>

#include "binary_copy.hpp"
#include "core/error.hpp"
#include "fleet/central_error.hpp"
#include "fleet/central_schema.hpp"
#include "store/error.hpp"
#include "store/run_store.hpp"
#include "store/stamp.hpp"
#include "store/station_identity.hpp"

namespace calstand::fleet {
namespace {

using detail::BinaryCopy;
using detail::BinaryCopyRows;
using detail::CopyType;

/// A central table's staging table (copy_rows): its name and the types of its columns.
struct Staging {
  std::string name;
  std::map<std::string, CopyType> types;
};

/// The session's staging table of central `table`, made when missing; `staged` keeps the ones
/// this sync has made sure of. PostgreSQL refuses COPY into a table under row-level security,
/// and COPY has no ON CONFLICT: the staging table (temporary, so without either, emptied at
/// commit or rollback) gives both.
const Staging& staging_of(pqxx::dbtransaction& tx, std::map<std::string, Staging>& staged,
                          const std::string& table) {
  if (const auto found = staged.find(table); found != staged.end()) return found->second;
  Staging s;
  s.name = "calstand_staging_" + table;
  if (tx.exec("SELECT to_regclass('pg_temp." + s.name + "') IS NULL")[0][0].as<bool>()) {
    // The session's temporary tables live in its temp_buffers: room for a batch of sample
    // chunks (64 of ~150 kB) so that staging does not spill to disk. Settable only before the
    // session's first temporary table, which this is.
    if (staged.empty()) tx.exec("SET temp_buffers = '32MB'");
    // INCLUDING STORAGE: the sample chunks' EXTERNAL (central migration 3), so that staging
    // does not try to compress them either.
    tx.exec("CREATE TEMPORARY TABLE " + s.name + " (LIKE " + table +
            " INCLUDING DEFAULTS INCLUDING STORAGE) ON COMMIT DELETE ROWS");
  }
  // The types binary COPY writes each column in, from the staging table itself (LIKE the
  // central table), so that they cannot drift from central_schema.sql.
  const pqxx::result columns = tx.exec(
      "SELECT attname, format_type(atttypid, atttypmod) FROM pg_attribute WHERE attrelid = "
      "'pg_temp." +
      s.name + "'::regclass AND attnum > 0 AND NOT attisdropped");
  for (const auto& row : columns) {
    const auto name = row[0].as<std::string>();
    s.types[name] = detail::copy_type_of(table + "." + name, row[1].as<std::string>());
  }
  return staged.emplace(table, std::move(s)).first->second;
}

/// Appends SQLite value `c` to `rows` as column `column` of type `type`.
void put_value(BinaryCopyRows& rows, CopyType type, const char* column, const SQLite::Column& c) {
  // SQLiteCpp's type codes are extern constants, not case labels.
  const int t = c.getType();
  if (t == SQLite::Null) {
    rows.null();
  } else if (t == SQLite::INTEGER) {
    rows.integer(type, column, c.getInt64());
  } else if (t == SQLite::FLOAT) {
    rows.real(type, column, c.getDouble());
  } else if (t == SQLite::BLOB) {
    rows.bytes(type, column, c.getBlob(), static_cast<std::size_t>(c.getBytes()));
  } else {
    rows.text(type, column, std::string_view(c.getText(), static_cast<std::size_t>(c.getBytes())));
  }
}

/// Copies the rows of `q` into central `table` by binary COPY (one stream, not a round trip
/// per row; binary_copy.hpp says why binary) into the session's staging table of it, then one
/// INSERT ... SELECT from there that skips rows already central, all in `tx`. Each row is
/// `fixed` (the same for every row, e.g. the station and the central run, as PostgreSQL's text
/// input reads them) then the query's columns, in the order of `columns` (N of them). `each(q)`
/// is called per row before it is sent. Returns the rows read from `q`.
template <std::size_t N, class Each>
std::int64_t copy_rows(pqxx::dbtransaction& tx, std::map<std::string, Staging>& staged,
                       const std::string& table, const std::array<const char*, N>& columns,
                       const std::vector<std::string>& fixed, SQLite::Statement& q, Each each) {
  // Rows are sent in pieces of about this many bytes: few calls into libpq, little memory.
  constexpr std::size_t kSendBytes = std::size_t{1} << 20;
  const Staging& staging = staging_of(tx, staged, table);
  std::array<CopyType, N> types{};
  for (std::size_t i = 0; i < N; ++i) {
    const auto t = staging.types.find(columns[i]);
    if (t == staging.types.end()) {
      throw std::invalid_argument(fmt::format("{} has no column {}", table, columns[i]));
    }
    types[i] = t->second;
  }
  std::int64_t rows = 0;
  try {
    BinaryCopyRows prefix;  // the fixed fields, encoded once
    for (std::size_t i = 0; i < fixed.size(); ++i) prefix.text(types[i], columns[i], fixed[i]);
    BinaryCopy copy(tx, staging.name, std::vector<std::string>(columns.begin(), columns.end()));
    BinaryCopyRows out;
    while (q.executeStep()) {
      each(q);
      out.begin_row(N);
      out.append(prefix);
      for (std::size_t i = fixed.size(); i < N; ++i) {
        put_value(out, types[i], columns[i], q.getColumn(static_cast<int>(i - fixed.size())));
      }
      ++rows;
      if (out.data().size() >= kSendBytes) {
        copy.write(out.data());
        out.clear();
      }
    }
    copy.write(out.data());
    copy.finish();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(fmt::format("{} row {}: {}", table, rows + 1, e.what()));
  }
  if (rows > 0) {
    std::string list;
    for (const char* c : columns) list += (list.empty() ? "" : ", ") + std::string(c);
    tx.exec("INSERT INTO " + table + " (" + list + ") SELECT " + list + " FROM " + staging.name +
            " ON CONFLICT DO NOTHING");
  }
  return rows;
}

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
    if (!stopped()) copy_run_details();
    if (!stopped()) copy_station_events();
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
    } catch (...) {
      rethrow_as_central("prepare statements");
    }
  }

  void register_station() {
    try {
      pqxx::work tx(central_);
      lock_station(tx);
      pqxx::result r =
          tx.exec_params("SELECT name FROM stations WHERE uuid = $1", report_.station_uuid);
      if (r.empty()) {
        // A name is unique in the fleet (central migration 2): the index refuses a taken one
        // whichever role registered it, though row-level security hides that station from us.
        try {
          tx.exec_params(
              "INSERT INTO stations (uuid, name, store_schema, registered_utc) "
              "VALUES ($1, $2, $3, $4) ON CONFLICT (uuid) DO NOTHING",
              report_.station_uuid, options_.station_name, station_.schema_version(),
              store::utc_now_iso8601());
        } catch (const pqxx::unique_violation&) {
          throw CentralError("register station " + report_.station_uuid,
                             fmt::format("the name '{}' is another station's in this fleet; "
                                         "a station's name is unique: choose another (--name)",
                                         options_.station_name));
        }
        r = tx.exec_params("SELECT name FROM stations WHERE uuid = $1", report_.station_uuid);
      }
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

  // A run's step means and telemetry, once the run is central: all of it in one transaction
  // with its run_details row, so that a cut sync copies a run's details whole or not at all.
  void copy_run_details() {
    copy_stream(
        "run_details", "run_details", "runs", 16,
        [&](std::int64_t after, std::size_t limit) {
          return read_local("SELECT id, id FROM runs WHERE id > ? ORDER BY id LIMIT ?", after,
                            limit, false);
        },
        [&](pqxx::work& tx, const LocalRef& r, std::int64_t central_run) -> std::int64_t {
          return insert_run_details(tx, r.id, central_run);
        });
  }

  std::int64_t insert_run_details(pqxx::work& tx, std::int64_t local_run,
                                  std::int64_t central_run) {
    const std::vector<std::string> fixed = {report_.station_uuid, std::to_string(central_run)};
    const auto nothing = [](const SQLite::Statement&) {};
    SQLite::Statement means(station_.sql(),
                            "SELECT step_id, attempt, device, count, first_receive_time_s, "
                            "last_receive_time_s, gx_dps, gy_dps, gz_dps, ax_mps2, ay_mps2, "
                            "az_mps2, temperature_c, std_gx_dps, std_gy_dps, std_gz_dps, "
                            "std_ax_mps2, std_ay_mps2, std_az_mps2, std_temperature_c "
                            "FROM step_means WHERE run_id = ?");
    means.bind(1, local_run);
    const std::int64_t step_means = copy_rows<22>(tx, staged_, "step_means",
                                                  {"station",
                                                   "run_id",
                                                   "step_local_id",
                                                   "attempt",
                                                   "device",
                                                   "count",
                                                   "first_receive_time_s",
                                                   "last_receive_time_s",
                                                   "gx_dps",
                                                   "gy_dps",
                                                   "gz_dps",
                                                   "ax_mps2",
                                                   "ay_mps2",
                                                   "az_mps2",
                                                   "temperature_c",
                                                   "std_gx_dps",
                                                   "std_gy_dps",
                                                   "std_gz_dps",
                                                   "std_ax_mps2",
                                                   "std_ay_mps2",
                                                   "std_az_mps2",
                                                   "std_temperature_c"},
                                                  fixed, means, nothing);
    SQLite::Statement table(station_.sql(),
                            "SELECT id, step_id, time_s, outer_deg, inner_deg, outer_rate_dps, "
                            "inner_rate_dps, outer_mode, inner_mode FROM table_telemetry "
                            "WHERE run_id = ? ORDER BY id");
    table.bind(1, local_run);
    const std::int64_t table_rows =
        copy_rows<11>(tx, staged_, "table_telemetry",
                      {"station", "run_id", "local_id", "step_local_id", "time_s", "outer_deg",
                       "inner_deg", "outer_rate_dps", "inner_rate_dps", "outer_mode", "inner_mode"},
                      fixed, table, nothing);
    SQLite::Statement chamber(station_.sql(),
                              "SELECT id, time_s, air_c, setpoint_c, mode FROM chamber_telemetry "
                              "WHERE run_id = ? ORDER BY id");
    chamber.bind(1, local_run);
    const std::int64_t chamber_rows =
        copy_rows<7>(tx, staged_, "chamber_telemetry",
                     {"station", "run_id", "local_id", "time_s", "air_c", "setpoint_c", "mode"},
                     fixed, chamber, nothing);
    tx.exec_params("INSERT INTO run_details (station, local_id, run_id) VALUES ($1, $2, $3)",
                   report_.station_uuid, local_run, central_run);
    report_.copied.step_means += step_means;
    report_.copied.table_telemetry += table_rows;
    report_.copied.chamber_telemetry += chamber_rows;
    return 1 + step_means + table_rows + chamber_rows;
  }

  // Events of no run (an interlock closed between runs, a link lost while idle); a run's own
  // events go with the run.
  void copy_station_events() {
    copy_stream(
        "station_events", "events", "", options_.batch_rows,
        [&](std::int64_t after, std::size_t limit) {
          return read_local(
              "SELECT id, id FROM events WHERE run_id IS NULL AND id > ? ORDER BY id LIMIT ?",
              after, limit, false);
        },
        [&](pqxx::work& tx, const LocalRef& r, std::int64_t) -> std::int64_t {
          SQLite::Statement q(station_.sql(),
                              "SELECT time_s, wall_utc, kind, source, message, detail FROM events "
                              "WHERE id = ?");
          q.bind(1, r.id);
          if (!q.executeStep()) return 0;
          tx.exec_prepared(
              "calstand_insert_event", report_.station_uuid, r.id, std::optional<std::int64_t>(),
              q.getColumn(0).getDouble(), q.getColumn(1).getString(), q.getColumn(2).getString(),
              q.getColumn(3).getString(), q.getColumn(4).getString(),
              q.getColumn(5).isNull() ? std::optional<std::string>()
                                      : std::optional<std::string>(q.getColumn(5).getString()));
          ++report_.copied.station_events;
          return 1;
        });
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
          // The batch's chunks go into the session's staging table with COPY (one stream
          // instead of a round trip per chunk), then into sample_chunks with one insert that
          // skips chunks already central: all in this transaction with the cursor, so a cut
          // sync resumes exactly. The staging table empties itself at commit or rollback.
          SyncCounts batch;
          const std::int64_t fetched = copy_rows<11>(
              tx, staged_, "sample_chunks",
              {"station", "run_id", "local_id", "step_idx", "attempt", "device",
               "first_receive_time_s", "last_receive_time_s", "count", "encoding", "data"},
              {report_.station_uuid, std::to_string(central_run)}, q,
              [&](const SQLite::Statement& row) {
                cursor = row.getColumn(0).getInt64();
                ++batch.sample_chunks;
                batch.samples += row.getColumn(6).getInt64();
                batch.sample_bytes += row.getColumn(8).getBytes();
              });
          complete = fetched < static_cast<std::int64_t>(options_.batch_chunks);
          tx.exec_params(
              "INSERT INTO sample_cursors (station, run_id, last_local_id, complete) "
              "VALUES ($1, $2, $3, $4) ON CONFLICT (run_id) DO UPDATE SET "
              "last_local_id = EXCLUDED.last_local_id, complete = EXCLUDED.complete",
              report_.station_uuid, central_run, cursor, complete);
          commit(tx);
          report_.copied.sample_chunks += batch.sample_chunks;
          report_.copied.samples += batch.samples;
          report_.copied.sample_bytes += batch.sample_bytes;
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
  /// Central tables whose staging table this sync has made sure of (copy_rows).
  std::map<std::string, Staging> staged_;
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
            {"step_means", c.step_means},
            {"table_telemetry", c.table_telemetry},
            {"chamber_telemetry", c.chamber_telemetry},
            {"station_events", c.station_events},
            {"sample_chunks", c.sample_chunks},
            {"samples", c.samples},
            {"sample_bytes", c.sample_bytes},
            {"transactions", c.transactions}}},
          {"waiting_runs", report.waiting_runs},
          {"seconds", report.seconds},
          {"stopped", report.stopped}};
}

}  // namespace calstand::fleet
