#include "store/database.hpp"

#include <SQLiteCpp/Database.h>
#include <gtest/gtest.h>

#include <string>

#include "store/error.hpp"
#include "temp_dir.hpp"

namespace calstand::store {
namespace {

using testing::TempDir;

int count_schema_objects(Database& db) {
  return db.sql().execAndGet("SELECT COUNT(*) FROM sqlite_schema").getInt();
}

std::string open_error(const std::string& path) {
  try {
    Database db(path);
  } catch (const StoreError& e) {
    return e.what();
  }
  return "";
}

TEST(Database, FreshFileIsAtLatestVersionWithEveryTable) {
  TempDir dir;
  Database db(dir.file("fresh.db"));
  EXPECT_EQ(db.schema_version(), latest_schema_version());
  EXPECT_GE(latest_schema_version(), 1);
  for (const char* table : {"stations", "devices", "runs", "steps", "sample_chunks", "step_means",
                            "table_telemetry", "chamber_telemetry", "events", "calibrations"}) {
    EXPECT_EQ(db.sql().tableExists(table), true) << table;
  }
  for (const char* view : {"step_sample_summary", "step_means_view", "run_overview"}) {
    SQLite::Statement q(db.sql(), "SELECT COUNT(*) FROM sqlite_schema WHERE type = 'view' AND name = ?");
    q.bind(1, view);
    q.executeStep();
    EXPECT_EQ(q.getColumn(0).getInt(), 1) << view;
  }
}

TEST(Database, ConnectionSettingsAreWalForeignKeysAndNormalSync) {
  TempDir dir;
  Database db(dir.file("settings.db"));
  EXPECT_EQ(db.sql().execAndGet("PRAGMA journal_mode").getString(), "wal");
  EXPECT_EQ(db.sql().execAndGet("PRAGMA foreign_keys").getInt(), 1);
  EXPECT_EQ(db.sql().execAndGet("PRAGMA synchronous").getInt(), 1);  // NORMAL
  EXPECT_EQ(db.sql().execAndGet("PRAGMA application_id").getInt(), 0x43534442);
  EXPECT_EQ(db.sql().execAndGet("PRAGMA integrity_check").getString(), "ok");
}

TEST(Database, ReopeningIsIdempotentAndKeepsData) {
  TempDir dir;
  const std::string path = dir.file("reopen.db");
  int objects = 0;
  {
    Database db(path);
    objects = count_schema_objects(db);
    db.sql().exec("INSERT INTO stations (name, config, updated_utc) VALUES ('s', '{}', 'now')");
  }
  Database again(path);
  EXPECT_EQ(again.schema_version(), latest_schema_version());
  EXPECT_EQ(count_schema_objects(again), objects);
  EXPECT_EQ(again.sql().execAndGet("SELECT COUNT(*) FROM stations").getInt(), 1);
}

TEST(Database, RefusesANewerSchemaVersion) {
  TempDir dir;
  const std::string path = dir.file("newer.db");
  {
    Database db(path);
    db.sql().exec("PRAGMA user_version = " + std::to_string(latest_schema_version() + 1));
  }
  const std::string error = open_error(path);
  EXPECT_NE(error.find("schema version " + std::to_string(latest_schema_version() + 1)),
            std::string::npos)
      << error;
  EXPECT_NE(error.find("use a newer calstand"), std::string::npos) << error;
}

TEST(Database, RefusesAForeignSqliteFile) {
  TempDir dir;
  const std::string path = dir.file("other.db");
  {
    SQLite::Database other(path, SQLite::OPEN_READWRITE | SQLite::OPEN_CREATE);
    other.exec("CREATE TABLE notes (text TEXT)");
  }
  EXPECT_NE(open_error(path).find("not a calstand database"), std::string::npos);
  // ... and leaves it untouched.
  SQLite::Database other(path);
  EXPECT_EQ(other.execAndGet("PRAGMA user_version").getInt(), 0);
}

TEST(Database, InMemoryDatabaseIsMigrated) {
  Database db(":memory:");
  EXPECT_EQ(db.schema_version(), latest_schema_version());
}

TEST(Database, ForeignKeysAreEnforced) {
  Database db(":memory:");
  EXPECT_THROW(db.sql().exec("INSERT INTO steps (run_id, idx, kind, label, commanded, origin) "
                             "VALUES (99, 0, 'wait', 'w', '{}', 'steps[0]')"),
               SQLite::Exception);
}

}  // namespace
}  // namespace calstand::store
