#include "store/acceptances.hpp"

#include <SQLiteCpp/Statement.h>

#include "core/error.hpp"
#include "sql_util.hpp"
#include "store/calibrations.hpp"
#include "store/stamp.hpp"

namespace calstand::store {

std::int64_t insert_acceptance(Database& db, std::int64_t calibration, const std::string& spec_name,
                               const std::string& spec_sha256, const std::string& verdict,
                               const nlohmann::json& result) {
  load_calibration(db, calibration);  // InputError for an unknown calibration
  if (verdict != "pass" && verdict != "fail" && verdict != "indeterminate") {
    throw core::InputError("verdict", "'" + verdict + "' is not pass, fail or indeterminate");
  }
  return detail::guarded("insert acceptance", [&] {
    SQLite::Statement st(
        db.sql(),
        "INSERT INTO acceptances (calibration_id, spec_name, spec_sha256, verdict, "
        "result, created_utc) VALUES (?, ?, ?, ?, ?, ?)");
    st.bind(1, calibration);
    st.bind(2, spec_name);
    st.bind(3, spec_sha256);
    st.bind(4, verdict);
    st.bind(5, result.dump());
    st.bind(6, utc_now_iso8601());
    st.exec();
    return db.sql().getLastInsertRowid();
  });
}

std::optional<AcceptanceRow> latest_acceptance(Database& db, std::int64_t calibration) {
  return detail::guarded("read acceptance", [&]() -> std::optional<AcceptanceRow> {
    SQLite::Statement q(db.sql(),
                        "SELECT id, calibration_id, spec_name, spec_sha256, verdict, result, "
                        "created_utc FROM acceptances WHERE calibration_id = ? "
                        "ORDER BY id DESC LIMIT 1");
    q.bind(1, calibration);
    if (!q.executeStep()) return std::nullopt;
    return AcceptanceRow{
        q.getColumn(0).getInt64(),  q.getColumn(1).getInt64(),
        q.getColumn(2).getString(), q.getColumn(3).getString(),
        q.getColumn(4).getString(), nlohmann::json::parse(q.getColumn(5).getString()),
        q.getColumn(6).getString()};
  });
}

}  // namespace calstand::store
