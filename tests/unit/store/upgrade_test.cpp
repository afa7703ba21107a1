#include "store/upgrade.hpp"

#include <SQLiteCpp/Database.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "../../support/older_database.hpp"
#include "store/calibrations.hpp"
#include "store/database.hpp"
#include "store/error.hpp"
#include "temp_dir.hpp"

namespace calstand::store {
namespace {

using testing::TempDir;

const std::string kSchema = std::string(CALSTAND_SOURCE_DIR) + "/store/schema.sql";

int user_version(const std::string& path) {
  SQLite::Database db(path, SQLite::OPEN_READONLY);
  return db.execAndGet("PRAGMA user_version").getInt();
}

int stations_named_older(const std::string& path) {
  SQLite::Database db(path, SQLite::OPEN_READONLY);
  return db.execAndGet("SELECT COUNT(*) FROM stations WHERE name = 'older'").getInt();
}

int backups_in(const std::filesystem::path& dir) {
  int n = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) {
    if (e.path().extension() == ".bak") ++n;
  }
  return n;
}

TEST(Upgrade, AnOlderDatabaseIsBackedUpBesideItThenMigrated) {
  ASSERT_GE(latest_schema_version(), 2) << "no older schema to upgrade from";
  TempDir dir;
  const std::string path = dir.file("station.db");
  const int older = latest_schema_version() - 1;
  calstand::testing::make_database_at_version(path, kSchema, older);
  std::vector<std::pair<int, int>> announced;
  const Upgrade up =
      upgrade_database(path, [&](int from, int to) { announced.emplace_back(from, to); });
  EXPECT_EQ(up.from_version, older);
  EXPECT_EQ(up.to_version, latest_schema_version());
  EXPECT_EQ(up.backup, path + ".schema" + std::to_string(older) + ".bak");
  ASSERT_EQ(announced.size(), 1u);
  EXPECT_EQ(announced[0], std::make_pair(older, latest_schema_version()));
  // The copy is the database as it was; the database is migrated, its rows kept.
  EXPECT_EQ(user_version(up.backup), older);
  EXPECT_EQ(stations_named_older(up.backup), 1);
  EXPECT_EQ(user_version(path), latest_schema_version());
  EXPECT_EQ(stations_named_older(path), 1);
  SQLite::Database backup(up.backup, SQLite::OPEN_READONLY);
  EXPECT_EQ(backup.execAndGet("PRAGMA integrity_check").getString(), "ok");
}

// Schema version 7 keeps a calibration's step residuals beside it for its certificate: a
// version-6 database with a record upgrades, its record is kept without residuals (its
// certificate refits, factory/certificate_data.cpp), and new records store theirs.
TEST(Upgrade, ARecordOfVersion6IsKeptWithoutResidualsAndNewRecordsStoreThem) {
  TempDir dir;
  const std::string path = dir.file("station.db");
  calstand::testing::make_database_at_version(path, kSchema, 6);
  {
    SQLite::Database old(path, SQLite::OPEN_READWRITE);
    old.exec(
        "INSERT INTO runs (id, procedure_name, procedure_text, procedure_sha256, parameters, "
        "station_snapshot, status, created_utc) VALUES (1, 'six-position', '{}', '', '{}', '{}', "
        "'completed', 'then')");
    old.exec(
        "INSERT INTO calibrations (id, run_id, imu, model, record, created_utc, serial) VALUES "
        "(1, 1, 'imu0', 'gyro_bias', '{\"method\": \"table\"}', 'then', 'SN1')");
  }
  const Upgrade up = upgrade_database(path);
  EXPECT_EQ(up.from_version, 6);
  EXPECT_EQ(up.to_version, latest_schema_version());
  Database db(path);
  EXPECT_EQ(load_calibration(db, 1).serial, "SN1");
  EXPECT_FALSE(load_calibration_residuals(db, 1).has_value());
  const nlohmann::json residuals = {{"format", "calstand-step-residuals/1"},
                                    {"steps", nlohmann::json::array()}};
  const std::int64_t id =
      insert_calibration(db, 1, "imu0", "gyro_bias", {{"method", "table"}}, residuals);
  ASSERT_TRUE(load_calibration_residuals(db, id).has_value());
  EXPECT_EQ(*load_calibration_residuals(db, id), residuals);
  // Deleting a record takes its residuals with it.
  db.sql().exec("DELETE FROM calibrations WHERE id = " + std::to_string(id));
  EXPECT_FALSE(load_calibration_residuals(db, id).has_value());
  EXPECT_EQ(db.sql().execAndGet("SELECT COUNT(*) FROM calibration_residuals").getInt(), 0);
}

TEST(Upgrade, ABackupNameTakenGetsANumber) {
  TempDir dir;
  const std::string path = dir.file("station.db");
  const int older = latest_schema_version() - 1;
  calstand::testing::make_database_at_version(path, kSchema, older);
  const std::string first = path + ".schema" + std::to_string(older) + ".bak";
  { std::ofstream(first) << "an operator's own copy"; }
  const Upgrade up = upgrade_database(path);
  EXPECT_EQ(up.backup, path + ".schema" + std::to_string(older) + ".1.bak");
  EXPECT_EQ(std::filesystem::file_size(first), std::string("an operator's own copy").size());
  EXPECT_EQ(user_version(up.backup), older);
}

TEST(Upgrade, ACurrentOrNewDatabaseNeedsNoBackup) {
  TempDir dir;
  const std::string path = dir.file("station.db");
  int calls = 0;
  const auto count = [&](int, int) { ++calls; };
  const Upgrade created = upgrade_database(path, count);  // absent: created
  EXPECT_EQ(created.from_version, 0);
  EXPECT_EQ(created.to_version, latest_schema_version());
  EXPECT_TRUE(created.backup.empty());
  const Upgrade again = upgrade_database(path, count);  // current: left as it is
  EXPECT_EQ(again.from_version, latest_schema_version());
  EXPECT_TRUE(again.backup.empty());
  EXPECT_EQ(calls, 0);
  EXPECT_EQ(backups_in(dir.path()), 0);
}

TEST(Upgrade, ADatabaseNewerThanThisBuildIsRefusedByNameAndLeftAlone) {
  TempDir dir;
  const std::string path = dir.file("station.db");
  const int newer = latest_schema_version() + 1;
  {
    Database db(path);
    db.sql().exec("PRAGMA user_version = " + std::to_string(newer));
  }
  const auto before = std::filesystem::last_write_time(path);
  try {
    upgrade_database(path);
    FAIL() << "a newer database was opened";
  } catch (const StoreError& e) {
    const std::string said = e.what();
    EXPECT_NE(said.find(path), std::string::npos) << said;
    EXPECT_NE(said.find("schema version " + std::to_string(newer)), std::string::npos) << said;
    EXPECT_NE(said.find("newer than this calstand's " + std::to_string(latest_schema_version())),
              std::string::npos)
        << said;
    EXPECT_NE(said.find("downgrade is refused"), std::string::npos) << said;
  }
  EXPECT_EQ(user_version(path), newer);
  EXPECT_EQ(std::filesystem::last_write_time(path), before);
  EXPECT_EQ(backups_in(dir.path()), 0);
}

TEST(Upgrade, AForeignSqliteFileIsRefusedWithoutABackup) {
  TempDir dir;
  const std::string path = dir.file("other.db");
  {
    SQLite::Database other(path, SQLite::OPEN_READWRITE | SQLite::OPEN_CREATE);
    other.exec("PRAGMA application_id = 1234");
    other.exec("PRAGMA user_version = 3");
    other.exec("CREATE TABLE notes (text TEXT)");
  }
  try {
    upgrade_database(path);
    FAIL() << "a foreign file was opened";
  } catch (const StoreError& e) {
    EXPECT_NE(std::string(e.what()).find("not a calstand database"), std::string::npos) << e.what();
  }
  EXPECT_EQ(user_version(path), 3);
}

}  // namespace
}  // namespace calstand::store
