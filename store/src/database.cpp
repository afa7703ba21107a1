#include "store/database.hpp"

#include <SQLiteCpp/Statement.h>
#include <SQLiteCpp/Transaction.h>
#include <sqlite3.h>

#include <algorithm>
#include <chrono>
#include <stdexcept>
#include <string>
#include <thread>

#include "sql_util.hpp"

namespace calstand::store {
namespace {

constexpr int kApplicationId = 0x43534442;  // 'CSDB', set by migration 1

const std::vector<detail::Migration>& migrations() {
  static const std::vector<detail::Migration> m = [] {
    const auto text = detail::schema_file("schema.sql");
    if (!text) throw std::logic_error("schema.sql is not compiled in");
    return detail::parse_migrations(*text);
  }();
  return m;
}

int pragma_int(SQLite::Database& db, const char* pragma) {
  return db.execAndGet(std::string("PRAGMA ") + pragma).getInt();
}

SQLite::Database open_connection(const std::string& path, int busy_timeout_ms) {
  return detail::guarded("open " + path, [&] {
    return SQLite::Database(path, SQLite::OPEN_READWRITE | SQLite::OPEN_CREATE | SQLite::OPEN_URI,
                            busy_timeout_ms);
  });
}

// Refuses files that are not (or not yet) calstand databases, before anything is written.
// The three reads share one read transaction: another process creating the same new database
// may commit migration 1 between them, and tables with version 0 read from two snapshots
// looked like a foreign database.
void check_identity(SQLite::Database& db, const std::string& path) {
  SQLite::Transaction snapshot(db, SQLite::TransactionBehavior::DEFERRED);
  const int app_id = pragma_int(db, "application_id");
  const int version = pragma_int(db, "user_version");
  if (app_id != 0 && app_id != kApplicationId) {
    throw StoreError("open " + path,
                     "not a calstand database (application_id " + std::to_string(app_id) + ")");
  }
  if (app_id == 0 && version == 0) {
    const int tables =
        db.execAndGet("SELECT COUNT(*) FROM sqlite_schema WHERE type = 'table'").getInt();
    if (tables != 0) {
      throw StoreError("open " + path,
                       "not a calstand database (it has tables but no calstand schema)");
    }
  }
  if (version > latest_schema_version()) {
    throw StoreError("open " + path, "database schema version " + std::to_string(version) +
                                         " is newer than this calstand's " +
                                         std::to_string(latest_schema_version()) +
                                         "; use a newer calstand");
  }
  snapshot.commit();  // read only: ends the snapshot
}

bool is_busy(const SQLite::Exception& e) {
  return (e.getErrorCode() & 0xff) == SQLITE_BUSY || (e.getErrorCode() & 0xff) == SQLITE_LOCKED;
}

// Runs `fn` again while SQLite says the database is busy, for up to `timeout_ms`. Needed where
// SQLite returns SQLITE_BUSY without calling the busy handler: switching a new file to WAL while
// another process reads it, or upgrading a read snapshot that another process's commit made
// stale. Two processes opening the same new database at once (`calstand run` and a `calstand
// show` polling it) met exactly that.
template <class F>
void retry_while_busy(int timeout_ms, F&& fn) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  for (auto pause = std::chrono::milliseconds(1);;
       pause = std::min(pause * 2, std::chrono::milliseconds(50))) {
    try {
      fn();
      return;
    } catch (const SQLite::Exception& e) {
      if (!is_busy(e) || std::chrono::steady_clock::now() + pause > deadline) throw;
    }
    std::this_thread::sleep_for(pause);
  }
}

void migrate(SQLite::Database& db, const std::string& path, int busy_timeout_ms) {
  for (const auto& m : migrations()) {
    detail::guarded("migrate " + path + " to version " + std::to_string(m.version), [&] {
      retry_while_busy(busy_timeout_ms, [&] {
        // Read first: an up-to-date database is opened without taking the write lock.
        if (pragma_int(db, "user_version") >= m.version) return;
        SQLite::Transaction tx(db, SQLite::TransactionBehavior::IMMEDIATE);
        // Another process may have migrated while this one waited for the write lock.
        if (pragma_int(db, "user_version") >= m.version) return;
        db.exec(m.sql);
        db.exec("PRAGMA user_version = " + std::to_string(m.version));
        tx.commit();
      });
    });
  }
}

}  // namespace

int latest_schema_version() { return static_cast<int>(migrations().size()); }

Database::Database(const std::string& path, DatabaseOptions options)
    : path_(path), db_(open_connection(path, options.busy_timeout_ms)) {
  detail::guarded("open " + path, [&] {
    retry_while_busy(options.busy_timeout_ms, [&] {
      check_identity(db_, path_);
      // journal_mode cannot change inside a transaction, and sticks to the file; an in-memory
      // database answers "memory", which is fine.
      db_.exec("PRAGMA journal_mode = WAL");
    });
    db_.exec("PRAGMA synchronous = NORMAL");
    db_.exec("PRAGMA foreign_keys = ON");
  });
  migrate(db_, path_, options.busy_timeout_ms);
}

int Database::schema_version() const {
  return detail::guarded("read user_version", [&] {
    return const_cast<SQLite::Database&>(db_).execAndGet("PRAGMA user_version").getInt();
  });
}

}  // namespace calstand::store
