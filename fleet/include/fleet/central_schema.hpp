#pragma once
// The central database's own versioned schema (fleet/central_schema.sql), apart from the
// station's SQLite schema: a fleet upgrades its server and its stations at different times.

#include <pqxx/connection>
#include <string>
#include <vector>

namespace calstand::fleet {

/// The central schema version this build reads and writes: the last `-- migration N` block of
/// fleet/central_schema.sql.
int central_schema_version();
/// The title of migration `version` of this build ("" when it has no such migration).
std::string central_migration_title(int version);

/// Brings the central database to central_schema_version(), each migration in its own
/// transaction recorded in table calstand_schema; returns the versions applied (none when it
/// was current). Run by the database's owner (it creates tables and the group roles
/// calstand_station and calstand_reader). Concurrent calls serialise on an advisory lock.
/// Throws CentralError when the database is newer than this build, or a migration fails (that
/// migration is rolled back).
std::vector<int> migrate_central(pqxx::connection& connection);

/// Refuses a central database not at exactly this build's version, naming both versions by
/// number and title and which side to update: an older database is migrated by its owner
/// (`calstand fleet migrate`), against a newer one this station's calstand is updated.
/// `who` names the caller in the message (e.g. `station lab-3`). Throws CentralError.
void require_central_schema(pqxx::connection& connection, const std::string& display,
                            const std::string& who);

}  // namespace calstand::fleet
