#include "store/fit_history.hpp"

#include <SQLiteCpp/Statement.h>

#include <nlohmann/json.hpp>

#include "sql_util.hpp"
#include "store/run_store.hpp"
#include "store/stamp.hpp"

namespace calstand::store {
namespace {

void bind_optional(SQLite::Statement& st, int index, const std::optional<double>& v) {
  // NaN (an undefined chi2/dof) is stored as NULL: SQLite has no NaN.
  if (v && *v == *v) {
    st.bind(index, *v);
  } else {
    st.bind(index);
  }
}

std::optional<double> optional_column(const SQLite::Column& c) {
  if (c.isNull()) return std::nullopt;
  return c.getDouble();
}

}  // namespace

std::int64_t record_fit(Database& db, const FitRecord& fit) {
  RunStore(db).load_steps(fit.run);  // InputError for an unknown run
  return detail::guarded("record fit", [&] {
    SQLite::Statement st(db.sql(),
                         "INSERT INTO fits (run_id, device, command, model, custom_terms, "
                         "sensors, parameters, chi2_dof, rms_gyro_dps, rms_accel_mps2, "
                         "rms_turn_deg, created_utc) VALUES (?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
    st.bind(1, fit.run);
    st.bind(2, fit.device);
    st.bind(3, fit.command);
    st.bind(4, fit.model);
    st.bind(5, nlohmann::json(fit.custom_terms).dump());
    st.bind(6, fit.sensors);
    st.bind(7, fit.parameters);
    bind_optional(st, 8, fit.chi2_dof);
    bind_optional(st, 9, fit.rms_gyro_dps);
    bind_optional(st, 10, fit.rms_accel_mps2);
    bind_optional(st, 11, fit.rms_turn_deg);
    st.bind(12, fit.created_utc.empty() ? utc_now_iso8601() : fit.created_utc);
    st.exec();
    return db.sql().getLastInsertRowid();
  });
}

std::vector<FitRecord> fit_history(Database& db, std::int64_t run) {
  RunStore(db).load_steps(run);
  return detail::guarded("read fit history", [&] {
    SQLite::Statement q(db.sql(),
                        "SELECT id, run_id, device, command, model, custom_terms, sensors, "
                        "parameters, chi2_dof, rms_gyro_dps, rms_accel_mps2, rms_turn_deg, "
                        "created_utc FROM "
                        "fits WHERE run_id = ? ORDER BY id");
    q.bind(1, run);
    std::vector<FitRecord> out;
    while (q.executeStep()) {
      FitRecord f;
      f.id = q.getColumn(0).getInt64();
      f.run = q.getColumn(1).getInt64();
      f.device = q.getColumn(2).getString();
      f.command = q.getColumn(3).getString();
      f.model = q.getColumn(4).getString();
      f.custom_terms =
          nlohmann::json::parse(q.getColumn(5).getString()).get<std::vector<std::string>>();
      f.sensors = q.getColumn(6).getString();
      f.parameters = q.getColumn(7).getInt();
      f.chi2_dof = optional_column(q.getColumn(8));
      f.rms_gyro_dps = optional_column(q.getColumn(9));
      f.rms_accel_mps2 = optional_column(q.getColumn(10));
      f.rms_turn_deg = optional_column(q.getColumn(11));
      f.created_utc = q.getColumn(12).getString();
      out.push_back(std::move(f));
    }
    return out;
  });
}

}  // namespace calstand::store
