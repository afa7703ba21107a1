#pragma once

#include <cstdint>
#include <string>

namespace calstand::store {

/// Which process drives a run. A run whose row says `running` or `paused` while no process
/// holds its lock was cut off (kill -9, a closed terminal, a power loss): RunStore shows it as
/// `interrupted`, and it resumes. A resume takes the lock, so a run is never driven twice.
///
/// An open-file-description lock (fcntl F_OFD_SETLK) on byte `run` of the database's lock
/// file (`DB.lock`, the file DatabaseLock flocks; the two kinds of lock do not interact): the
/// kernel drops it when the process dies, and it conflicts between descriptors of one process
/// too, so a daemon's own reader sees the run it drives as held.
class RunLock {
 public:
  /// Takes the lock of `run` without waiting. Throws DatabaseBusy (database_lock.hpp) when
  /// another process or descriptor holds it, std::runtime_error when the lock file cannot be
  /// opened or locked.
  RunLock(const std::string& db_path, std::int64_t run);
  ~RunLock();
  RunLock(const RunLock&) = delete;
  RunLock& operator=(const RunLock&) = delete;

  /// True when some process holds the lock of `run`, or when that cannot be told (an
  /// in-memory database, a lock file that cannot be opened): only a clear "nobody" is false.
  static bool held(const std::string& db_path, std::int64_t run);

 private:
  int fd_ = -1;
};

}  // namespace calstand::store
