#pragma once

#include <SQLiteCpp/Database.h>

#include <string>

namespace calstand::store {

/// The schema version this build writes: the last `-- migration N` block of store/schema.sql.
int latest_schema_version();

/// Options of Database; the defaults suit the daemon and the command line.
struct DatabaseOptions {
  /// How long a statement waits for another connection's write lock before failing [ms].
  int busy_timeout_ms = 10000;
};

/// One connection to a calstand SQLite database, migrated to the latest schema on open.
///
/// Settings of every connection: WAL journal, foreign keys on, synchronous=NORMAL. Durability:
/// in WAL mode with synchronous=NORMAL a commit is not fsynced; a crash of the process loses
/// nothing committed, and a power loss loses at most the transactions committed since the last
/// WAL sync, never corrupting the file. Points that must survive power loss (a step's samples,
/// see CaptureWriter::commit_step) commit with synchronous=FULL, which syncs the whole WAL.
///
/// A connection is used by one thread at a time (SQLite connections are not shared); each
/// thread opens its own, e.g. the CaptureWriter opens a second one to the same file. WAL lets
/// readers run while one connection writes; writers wait up to busy_timeout_ms for each other.
class Database {
 public:
  /// Opens (creating when absent) the database at `path` (":memory:" for a private in-memory
  /// database) and applies pending migrations, each in its own transaction.
  /// Throws StoreError when the file cannot be opened, is not a calstand database, has a schema
  /// newer than latest_schema_version(), or a migration fails (that migration is rolled back).
  explicit Database(const std::string& path, DatabaseOptions options = {});

  /// The underlying SQLiteCpp connection, for queries of other modules and tests.
  SQLite::Database& sql() { return db_; }
  const SQLite::Database& sql() const { return db_; }
  /// The path given to the constructor.
  const std::string& path() const { return path_; }
  /// PRAGMA user_version of the open database (latest_schema_version() after the constructor).
  int schema_version() const;

 private:
  std::string path_;
  SQLite::Database db_;
};

}  // namespace calstand::store
