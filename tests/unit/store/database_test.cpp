#include "store/database.hpp"

#include <SQLiteCpp/Database.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fstream>
#include <iterator>
#include <string>
#include <vector>

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
    SQLite::Statement q(db.sql(),
                        "SELECT COUNT(*) FROM sqlite_schema WHERE type = 'view' AND name = ?");
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

// Processes that open the same new database at once (`calstand run` creating it while a
// `calstand show` polls for it, two factory scripts, the daemon and an import) must all get a
// migrated database: before, about one pair in thirty failed with "database is locked" or took
// the half-created file for a foreign one.
TEST(Database, ProcessesOpeningTheSameNewFileAtOnceAllSucceed) {
  constexpr int kRounds = 40;
  constexpr int kProcesses = 4;
  TempDir dir;
  std::vector<std::string> failures;
  for (int round = 0; round < kRounds; ++round) {
    const std::string db_path = dir.file("race-" + std::to_string(round) + ".db");
    int gate[2];
    ASSERT_EQ(::pipe(gate), 0);
    std::vector<pid_t> children;
    for (int p = 0; p < kProcesses; ++p) {
      const pid_t pid = ::fork();
      if (pid < 0) break;  // counted below: fewer children than kProcesses
      if (pid == 0) {
        ::close(gate[1]);
        char c;
        (void)::read(gate[0], &c, 1);  // returns 0 when the parent closes the gate: all go
        const std::string error = open_error(db_path);
        if (!error.empty()) std::ofstream(db_path + "." + std::to_string(p) + ".err") << error;
        ::_exit(error.empty() ? 0 : 1);
      }
      children.push_back(pid);
    }
    ::close(gate[0]);
    ::close(gate[1]);  // releases every child, also when a fork failed
    ASSERT_EQ(children.size(), static_cast<std::size_t>(kProcesses)) << "fork failed";
    for (int p = 0; p < kProcesses; ++p) {
      int status = 0;
      ::waitpid(children[p], &status, 0);
      if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        std::ifstream err(db_path + "." + std::to_string(p) + ".err");
        failures.push_back("round " + std::to_string(round) + " process " + std::to_string(p) +
                           ": " + std::string(std::istreambuf_iterator<char>(err), {}));
      }
    }
    Database db(db_path);
    EXPECT_EQ(db.schema_version(), latest_schema_version()) << "round " << round;
  }
  EXPECT_TRUE(failures.empty()) << failures.size() << " of " << kRounds * kProcesses
                                << " failed, first: " << failures.front();
}

}  // namespace
}  // namespace calstand::store
