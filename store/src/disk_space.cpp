#include "store/disk_space.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <filesystem>
#include <system_error>

#include "store/error.hpp"

namespace calstand::store {
namespace {

namespace fs = std::filesystem;

fs::path folder_of(const std::string& db_path) {
  const fs::path parent = fs::absolute(fs::path(db_path)).parent_path();
  return parent.empty() ? fs::current_path() : parent;
}

constexpr double kBytesPerMb = 1024.0 * 1024.0;

}  // namespace

std::uint64_t free_bytes_beside(const std::string& db_path) {
  std::error_code ec;
  const fs::path folder = folder_of(db_path);
  const fs::space_info info = fs::space(folder, ec);
  if (ec) throw StoreError("free space of " + folder.string(), ec.message());
  return info.available;
}

std::uint64_t free_bytes_counting_wal(const std::string& db_path) {
  std::error_code ec;
  const fs::path wal = fs::path(db_path + "-wal");
  // A log removed between the two readings is counted in the free space the second one sees.
  const std::uint64_t wal_bytes = fs::is_regular_file(wal, ec) ? fs::file_size(wal, ec) : 0;
  return free_bytes_beside(db_path) + (ec ? 0 : wal_bytes);
}

std::optional<std::string> disk_space_shortfall(const std::string& db_path, double min_free_mb) {
  const double free_mb = static_cast<double>(free_bytes_beside(db_path)) / kBytesPerMb;
  if (free_mb >= min_free_mb) return std::nullopt;
  return fmt::format(
      "disk full: only {:.1f} MB free on the database's filesystem ({}); a run needs at least "
      "{:.0f} MB (station policy min_free_disk_mb) to start or resume",
      free_mb, folder_of(db_path).string(), min_free_mb);
}

DiskReserve::DiskReserve(const std::string& db_path, std::int64_t run_id, std::uint64_t bytes)
    : path_(fmt::format("{}-reserve-{}", db_path, run_id)) {
  if (bytes == 0) {
    ::unlink(path_.c_str());
    return;
  }
  const int fd = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return;
  // posix_fallocate allocates blocks (a sparse file would give nothing back when removed).
  const int err = ::posix_fallocate(fd, 0, static_cast<off_t>(bytes));
  const bool synced = err == 0 && ::fsync(fd) == 0;
  ::close(fd);
  if (err != 0 || !synced) {
    ::unlink(path_.c_str());
    return;
  }
  held_bytes_ = bytes;
}

DiskReserve::~DiskReserve() { release(); }

bool DiskReserve::release() {
  // Removed even when empty: a reserve left by a killed process is given back too.
  const bool had = held_bytes_ > 0;
  ::unlink(path_.c_str());
  held_bytes_ = 0;
  return had;
}

bool says_disk_full(const std::string& what) {
  return what.find("database or disk is full") != std::string::npos ||
         what.find("No space left on device") != std::string::npos;
}

}  // namespace calstand::store
