#pragma once

#include <stdexcept>
#include <string>

namespace calstand::store {

/// Another process drives the station of this database (what() names it and what to do).
class DatabaseBusy : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Who may run procedures on a database at once. A daemon owns its database alone
/// (exclusive): it treats every run left 'running' as interrupted, so a foreground
/// `calstand run` beside it would look like a crash to it. Foreground runs share the database
/// with each other (shared), never with a daemon.
///
/// Held with flock() on `DB.lock` beside the database: the kernel drops it when the process
/// dies, so a kill -9 or a power loss leaves no stale lock. Reading the database (fit,
/// report, export) needs no lock.
class DatabaseLock {
 public:
  enum class Mode { kShared, kExclusive };

  /// Takes the lock without waiting; `owner` (e.g. "calstandd pid 1234 on 127.0.0.1:8765")
  /// is written into the lock file by an exclusive holder, for others' error messages.
  /// Throws DatabaseBusy when a conflicting holder has it, std::runtime_error when the lock
  /// file cannot be opened.
  DatabaseLock(const std::string& db_path, Mode mode, const std::string& owner);
  ~DatabaseLock();
  DatabaseLock(const DatabaseLock&) = delete;
  DatabaseLock& operator=(const DatabaseLock&) = delete;

  /// The lock file's path for database `db_path`.
  static std::string lock_path(const std::string& db_path);

 private:
  int fd_ = -1;
};

}  // namespace calstand::store
