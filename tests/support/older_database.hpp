#pragma once
// A station database as an older calstand made it: store/schema.sql's migrations 1..N applied
// in order (each with its user_version), as that build did; the upgrade tests start from it.

#include <SQLiteCpp/Database.h>

#include <fstream>
#include <iterator>
#include <stdexcept>
#include <string>

#include "store/migration_blocks.hpp"

namespace calstand::testing {

/// Creates the database `path` at schema version `version` from the schema file `schema_sql`
/// (the source tree's store/schema.sql), with one station row ('older') to find afterwards.
inline void make_database_at_version(const std::string& path, const std::string& schema_sql,
                                     int version) {
  std::ifstream in(schema_sql);
  if (!in) throw std::runtime_error("cannot read " + schema_sql);
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto migrations = store::parse_migrations(text);
  if (version < 1 || version > static_cast<int>(migrations.size())) {
    throw std::runtime_error("no schema version " + std::to_string(version));
  }
  SQLite::Database db(path, SQLite::OPEN_READWRITE | SQLite::OPEN_CREATE);
  for (int v = 1; v <= version; ++v) {
    db.exec("BEGIN");
    db.exec(migrations[static_cast<std::size_t>(v - 1)].sql);
    db.exec("PRAGMA user_version = " + std::to_string(v));
    db.exec("COMMIT");
  }
  db.exec("INSERT INTO stations (name, config, updated_utc) VALUES ('older', '{}', 'then')");
}

}  // namespace calstand::testing
