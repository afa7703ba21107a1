#include "store/database_lock.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace calstand::store {
namespace {

// What the exclusive holder wrote into the lock file ("" when nothing).
std::string recorded_owner(int fd) {
  char buffer[256] = {};
  const ssize_t n = ::pread(fd, buffer, sizeof buffer - 1, 0);
  std::string owner = n > 0 ? std::string(buffer, static_cast<std::size_t>(n)) : "";
  while (!owner.empty() && (owner.back() == '\n' || owner.back() == '\0')) owner.pop_back();
  return owner;
}

}  // namespace

std::string DatabaseLock::lock_path(const std::string& db_path) { return db_path + ".lock"; }

DatabaseLock::DatabaseLock(const std::string& db_path, Mode mode, const std::string& owner) {
  const std::string path = lock_path(db_path);
  fd_ = ::open(path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0) {
    throw std::runtime_error(
        fmt::format("{}: cannot open the lock file: {}", path, std::strerror(errno)));
  }
  const int operation = (mode == Mode::kExclusive ? LOCK_EX : LOCK_SH) | LOCK_NB;
  int rc = 0;
  do {
    rc = ::flock(fd_, operation);
  } while (rc != 0 && errno == EINTR);
  if (rc != 0) {
    const int error = errno;
    const std::string holder = recorded_owner(fd_);
    ::close(fd_);
    fd_ = -1;
    if (error != EWOULDBLOCK) {
      throw std::runtime_error(fmt::format("{}: cannot lock: {}", path, std::strerror(error)));
    }
    if (mode == Mode::kShared) {
      throw DatabaseBusy(fmt::format(
          "{}: a station daemon owns this database ({}); queue the run with `calstand submit` "
          "instead",
          db_path, holder.empty() ? "calstandd" : holder));
    }
    throw DatabaseBusy(fmt::format(
        "{}: in use by another calstandd or by a foreground `calstand run` (lock {}); one "
        "process drives a database's station at a time",
        db_path, path));
  }
  if (mode == Mode::kExclusive) {
    const std::string text = owner + "\n";
    if (::ftruncate(fd_, 0) == 0) {
      [[maybe_unused]] const ssize_t n = ::pwrite(fd_, text.data(), text.size(), 0);
    }
  }
}

DatabaseLock::~DatabaseLock() {
  if (fd_ >= 0) ::close(fd_);  // closing the last descriptor releases the flock
}

}  // namespace calstand::store
