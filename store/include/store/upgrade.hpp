#pragma once

#include <functional>
#include <string>

namespace calstand::store {

/// What upgrade_database() did to a database's schema.
struct Upgrade {
  int from_version = 0;  ///< the file's schema version before (0: a new database)
  int to_version = 0;    ///< latest_schema_version(): the file's version now
  std::string backup;    ///< the copy made before migrating; empty when none was needed
};

/// The schema version (PRAGMA user_version) of the database file at `path`, read without
/// changing it; 0 for a file that is absent or empty. Throws StoreError when it cannot read it.
int file_schema_version(const std::string& path);

/// Brings the database at `path` to this build's schema, as the daemon does on start (an
/// upgrade of the package leaves the station's database as it was). A database of an older
/// schema is first copied whole beside it by SQLite's `VACUUM INTO`, a consistent snapshot,
/// synced to disk: `<path>.schema<N>.bak` (N its version), or `<path>.schema<N>.<k>.bak` when
/// that name is taken; then it is migrated (each migration in its own transaction). A new
/// database is created; one at this schema is left as it is. `before_backup(from, to)`, when
/// given, is called before the copy starts (it can take minutes on a large database).
/// Throws StoreError naming the file and both versions for a database newer than this build
/// (a downgrade: refused, the file untouched), and as Database() does otherwise.
Upgrade upgrade_database(const std::string& path,
                         const std::function<void(int from, int to)>& before_backup = {});

}  // namespace calstand::store
