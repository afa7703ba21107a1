#include "store/run_lock.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "store/database_lock.hpp"

namespace calstand::store {
namespace {

// Byte `run` of the lock file, write-locked (the only kind used: a run has one driver).
struct flock run_range(std::int64_t run, short type) {
  struct flock l = {};
  l.l_type = type;
  l.l_whence = SEEK_SET;
  l.l_start = static_cast<off_t>(run);
  l.l_len = 1;
  l.l_pid = 0;  // required 0 for OFD locks
  return l;
}

int open_lock_file(const std::string& db_path) {
  return ::open(DatabaseLock::lock_path(db_path).c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
}

}  // namespace

RunLock::RunLock(const std::string& db_path, std::int64_t run) {
  fd_ = open_lock_file(db_path);
  if (fd_ < 0) {
    throw std::runtime_error(fmt::format("{}: cannot open the lock file: {}",
                                         DatabaseLock::lock_path(db_path), std::strerror(errno)));
  }
  struct flock l = run_range(run, F_WRLCK);
  int rc = 0;
  do {
    rc = ::fcntl(fd_, F_OFD_SETLK, &l);
  } while (rc != 0 && errno == EINTR);
  if (rc != 0) {
    const int error = errno;
    ::close(fd_);
    fd_ = -1;
    if (error == EAGAIN || error == EACCES) {
      throw DatabaseBusy(
          fmt::format("{}: run {} is being run by another process (a foreground `calstand run` or "
                      "calstandd); one process drives a run at a time",
                      db_path, run));
    }
    throw std::runtime_error(fmt::format(
        "{}: cannot lock run {}: {}", DatabaseLock::lock_path(db_path), run, std::strerror(error)));
  }
}

RunLock::~RunLock() {
  if (fd_ >= 0) ::close(fd_);  // closing the descriptor releases its OFD lock
}

bool RunLock::held(const std::string& db_path, std::int64_t run) {
  if (db_path.empty() || db_path == ":memory:") return true;
  const int fd = open_lock_file(db_path);
  if (fd < 0) return true;
  struct flock l = run_range(run, F_WRLCK);
  const int rc = ::fcntl(fd, F_OFD_GETLK, &l);
  ::close(fd);
  return rc != 0 || l.l_type != F_UNLCK;
}

}  // namespace calstand::store
