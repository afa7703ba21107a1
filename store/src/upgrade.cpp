#include "store/upgrade.hpp"

#include <SQLiteCpp/Database.h>
#include <SQLiteCpp/Statement.h>
#include <fcntl.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include "core/version.hpp"
#include "sql_util.hpp"
#include "store/database.hpp"
#include "store/error.hpp"

namespace calstand::store {
namespace {

constexpr int kCalstandApplicationId = 0x43534442;  // 'CSDB', as database.cpp sets it

// A name beside `path` no file has yet.
std::string backup_name(const std::string& path, int version) {
  const std::string base = path + ".schema" + std::to_string(version);
  std::string name = base + ".bak";
  for (int k = 1; std::filesystem::exists(name); ++k) {
    name = base + "." + std::to_string(k) + ".bak";
  }
  return name;
}

// VACUUM INTO does not sync what it wrote; a backup lost to a power cut with the migration
// already committed would be no backup.
void sync_file(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0 || ::fsync(fd) != 0) {
    if (fd >= 0) ::close(fd);
    throw StoreError("back up to " + path, "cannot sync the copy to disk");
  }
  ::close(fd);
}

}  // namespace

int file_schema_version(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec) || std::filesystem::file_size(path, ec) == 0) return 0;
  int application_id = 0;
  const int version = detail::guarded("read the schema version of " + path, [&] {
    SQLite::Database db(path, SQLite::OPEN_READONLY);
    application_id = db.execAndGet("PRAGMA application_id").getInt();
    return db.execAndGet("PRAGMA user_version").getInt();
  });
  // Another program's version number says nothing about calstand's schema.
  if (application_id != 0 && application_id != kCalstandApplicationId) {
    throw StoreError("open " + path, "not a calstand database (application_id " +
                                         std::to_string(application_id) + ")");
  }
  return version;
}

Upgrade upgrade_database(const std::string& path,
                         const std::function<void(int from, int to)>& before_backup) {
  Upgrade out;
  out.from_version = file_schema_version(path);
  out.to_version = latest_schema_version();
  if (out.from_version > out.to_version) {
    throw StoreError(
        "open " + path,
        "database schema version " + std::to_string(out.from_version) +
            " is newer than this calstand's " + std::to_string(out.to_version) + " (calstand " +
            core::kVersion +
            "): a downgrade is refused and the file left as it is; use a newer calstand, or "
            "a backup made by this version");
  }
  if (out.from_version > 0 && out.from_version < out.to_version) {
    if (before_backup) before_backup(out.from_version, out.to_version);
    out.backup = backup_name(path, out.from_version);
    detail::guarded("back up " + path + " to " + out.backup, [&] {
      SQLite::Database db(path, SQLite::OPEN_READONLY);
      SQLite::Statement vacuum(db, "VACUUM INTO ?");
      vacuum.bind(1, out.backup);
      vacuum.exec();
    });
    sync_file(out.backup);
  }
  Database migrated(path);  // migrates (or creates), and checks what the file is
  out.to_version = migrated.schema_version();
  return out;
}

}  // namespace calstand::store
