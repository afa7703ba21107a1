#include "store/units.hpp"

#include <SQLiteCpp/Statement.h>
#include <SQLiteCpp/Transaction.h>

#include "sql_util.hpp"

namespace calstand::store {

void record_run_units(Database& db, std::int64_t run, const std::vector<RunUnit>& units) {
  detail::guarded("record the run's units", [&] {
    SQLite::Transaction tx(db.sql());
    SQLite::Statement st(db.sql(),
                         "INSERT OR REPLACE INTO run_units (run_id, imu, model, serial, source) "
                         "VALUES (?, ?, ?, ?, ?)");
    for (const RunUnit& u : units) {
      st.reset();
      st.bind(1, run);
      st.bind(2, u.imu);
      st.bind(3, u.model);
      st.bind(4, u.serial);
      st.bind(5, u.source);
      st.exec();
    }
    tx.commit();
  });
}

std::vector<RunUnit> units_of_run(Database& db, std::int64_t run) {
  return detail::guarded("read the run's units", [&] {
    SQLite::Statement q(
        db.sql(), "SELECT imu, model, serial, source FROM run_units WHERE run_id = ? ORDER BY imu");
    q.bind(1, run);
    std::vector<RunUnit> out;
    while (q.executeStep()) {
      out.push_back({q.getColumn(0).getString(), q.getColumn(1).getString(),
                     q.getColumn(2).getString(), q.getColumn(3).getString()});
    }
    return out;
  });
}

RunUnit unit_of_run(Database& db, std::int64_t run, const std::string& imu) {
  for (RunUnit& u : units_of_run(db, run)) {
    if (u.imu == imu) return u;
  }
  RunUnit unknown;
  unknown.imu = imu;
  return unknown;
}

std::vector<std::int64_t> runs_of_serial(Database& db, const std::string& serial) {
  return detail::guarded("find the unit's runs", [&] {
    SQLite::Statement q(db.sql(),
                        "SELECT DISTINCT run_id FROM run_units WHERE serial = ? ORDER BY run_id");
    q.bind(1, serial);
    std::vector<std::int64_t> out;
    while (q.executeStep()) out.push_back(q.getColumn(0).getInt64());
    return out;
  });
}

}  // namespace calstand::store
