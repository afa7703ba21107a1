#include "store/calibrations.hpp"

#include <SQLiteCpp/Statement.h>
#include <SQLiteCpp/Transaction.h>

#include "core/error.hpp"
#include "sql_util.hpp"
#include "store/run_store.hpp"
#include "store/stamp.hpp"

namespace calstand::store {
namespace {

CalibrationRow row_of(SQLite::Statement& q) {
  return {q.getColumn(0).getInt64(),
          q.getColumn(1).getInt64(),
          q.getColumn(2).getString(),
          q.getColumn(3).getString(),
          nlohmann::json::parse(q.getColumn(4).getString()),
          q.getColumn(5).getString(),
          q.getColumn(6).getString(),
          std::string()};
}

constexpr const char* kSelect =
    "SELECT id, run_id, imu, model, record, created_utc, serial FROM calibrations ";

}  // namespace

std::int64_t insert_calibration(Database& db, std::int64_t run, const std::string& imu,
                                const std::string& model, const nlohmann::json& record,
                                const nlohmann::json& step_residuals) {
  RunStore(db).load_steps(run);  // InputError for an unknown run
  return detail::guarded("insert calibration", [&] {
    // The record and its residuals together or not at all: a certificate must not find one
    // without the other after a crash between them.
    SQLite::Transaction tx(db.sql(), SQLite::TransactionBehavior::IMMEDIATE);
    SQLite::Statement st(db.sql(),
                         "INSERT INTO calibrations (run_id, imu, model, record, created_utc, "
                         "serial) VALUES (?, ?, ?, ?, ?, ?)");
    st.bind(1, run);
    st.bind(2, imu);
    st.bind(3, model);
    st.bind(4, record.dump());
    st.bind(5, utc_now_iso8601());
    const nlohmann::json* device = record.contains("device") ? &record["device"] : nullptr;
    st.bind(6, device && device->is_object() ? device->value("serial", "") : std::string());
    st.exec();
    const std::int64_t id = db.sql().getLastInsertRowid();
    if (!step_residuals.is_null()) {
      SQLite::Statement residuals(
          db.sql(), "INSERT INTO calibration_residuals (calibration_id, steps) VALUES (?, ?)");
      residuals.bind(1, id);
      residuals.bind(2, step_residuals.dump());
      residuals.exec();
    }
    tx.commit();
    return id;
  });
}

std::optional<nlohmann::json> load_calibration_residuals(Database& db, std::int64_t id) {
  return detail::guarded("read calibration residuals", [&]() -> std::optional<nlohmann::json> {
    SQLite::Statement q(db.sql(),
                        "SELECT steps FROM calibration_residuals WHERE calibration_id = ?");
    q.bind(1, id);
    if (!q.executeStep()) return std::nullopt;
    return nlohmann::json::parse(q.getColumn(0).getString());
  });
}

CalibrationRow load_calibration(Database& db, std::int64_t id) {
  auto row = detail::guarded("read calibration", [&]() -> std::optional<CalibrationRow> {
    SQLite::Statement q(db.sql(), std::string(kSelect) + "WHERE id = ?");
    q.bind(1, id);
    if (!q.executeStep()) return std::nullopt;
    return row_of(q);
  });
  if (!row) throw core::InputError("calibration " + std::to_string(id), "no such calibration");
  return *row;
}

std::vector<CalibrationRow> calibrations_of_run(Database& db, std::int64_t run) {
  return detail::guarded("read calibrations", [&] {
    SQLite::Statement q(db.sql(), std::string(kSelect) + "WHERE run_id = ? ORDER BY id");
    q.bind(1, run);
    std::vector<CalibrationRow> out;
    while (q.executeStep()) out.push_back(row_of(q));
    return out;
  });
}

std::vector<CalibrationRow> calibrations_of_serial(Database& db, const std::string& serial) {
  return detail::guarded("read calibrations", [&] {
    SQLite::Statement q(
        db.sql(), std::string(kSelect) + "WHERE serial = ? ORDER BY created_utc DESC, id DESC");
    q.bind(1, serial);
    std::vector<CalibrationRow> out;
    while (q.executeStep()) out.push_back(row_of(q));
    return out;
  });
}

std::vector<CalibrationRow> calibrations_since(Database& db, const std::string& since_utc) {
  return detail::guarded("read calibrations", [&] {
    SQLite::Statement q(db.sql(), std::string(kSelect) + "WHERE created_utc >= ? ORDER BY id");
    q.bind(1, since_utc);
    std::vector<CalibrationRow> out;
    while (q.executeStep()) out.push_back(row_of(q));
    return out;
  });
}

}  // namespace calstand::store
