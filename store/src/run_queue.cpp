#include "store/run_queue.hpp"

#include <SQLiteCpp/Statement.h>

#include "sql_util.hpp"
#include "store/stamp.hpp"

namespace calstand::store {

void enqueue_run(Database& db, std::int64_t run, const std::string& submitted_by) {
  detail::guarded("enqueue run", [&] {
    SQLite::Statement st(
        db.sql(), "INSERT INTO run_queue (run_id, submitted_utc, submitted_by) VALUES (?, ?, ?)");
    st.bind(1, run);
    st.bind(2, utc_now_iso8601());
    st.bind(3, submitted_by);
    st.exec();
  });
}

std::vector<QueuedRun> queued_runs(Database& db) {
  return detail::guarded("list queued runs", [&] {
    SQLite::Statement q(db.sql(),
                        "SELECT q.run_id, q.submitted_utc, q.submitted_by FROM run_queue q "
                        "JOIN runs r ON r.id = q.run_id WHERE r.status = 'queued' "
                        "ORDER BY q.rowid");
    std::vector<QueuedRun> out;
    while (q.executeStep()) {
      out.push_back(
          {q.getColumn(0).getInt64(), q.getColumn(1).getString(), q.getColumn(2).getString()});
    }
    return out;
  });
}

void dequeue_run(Database& db, std::int64_t run) {
  detail::guarded("dequeue run", [&] {
    SQLite::Statement st(db.sql(), "DELETE FROM run_queue WHERE run_id = ?");
    st.bind(1, run);
    st.exec();
  });
}

std::vector<std::int64_t> interrupted_runs(Database& db) {
  return detail::guarded("list interrupted runs", [&] {
    SQLite::Statement q(db.sql(),
                        "SELECT id FROM runs WHERE status IN "
                        "('running', 'paused', 'held', 'interrupted') ORDER BY id");
    std::vector<std::int64_t> out;
    while (q.executeStep()) out.push_back(q.getColumn(0).getInt64());
    return out;
  });
}

void mark_run_resumable(Database& db, std::int64_t run, const std::string& status,
                        const std::string& reason) {
  detail::guarded("mark run resumable", [&] {
    SQLite::Statement st(db.sql(),
                         "UPDATE runs SET status = ?, exit_reason = ?, ended_utc = NULL, "
                         "ended_clock_s = NULL WHERE id = ?");
    st.bind(1, status);
    st.bind(2, reason);
    st.bind(3, run);
    st.exec();
  });
}

}  // namespace calstand::store
