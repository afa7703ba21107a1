#pragma once

#include <cstdint>
#include <optional>
#include <string>

namespace calstand::store {

/// Bytes free to an unprivileged writer on the filesystem holding `db_path` (its folder is
/// asked, so the database need not exist yet). Throws StoreError when the folder cannot be
/// asked.
std::uint64_t free_bytes_beside(const std::string& db_path);

/// free_bytes_beside() plus the bytes of the database's write-ahead log (`<db>-wal`), which
/// SQLite gives back when the last connection to the database closes. Whoever closes last (a
/// reader, not the daemon) decides when that is, so a comparison of free space across a run's
/// end counts the log as free on both sides: its deletion is then not taken for space freed.
std::uint64_t free_bytes_counting_wal(const std::string& db_path);

/// Why a run cannot start on `db_path` for lack of space: "only 12.3 MB free on the database's
/// filesystem (/var/lib/calstand); a run needs at least 64 MB ..." when fewer than
/// `min_free_mb` MB are free; none when there is enough.
std::optional<std::string> disk_space_shortfall(const std::string& db_path, double min_free_mb);

/// Space held beside the database while a run goes (`<db>-reserve-<run>`, blocks allocated on
/// disk), given back when the disk fills: SQLite then still has room to write the run's end
/// (status interrupted and why) instead of leaving it `running`. A reserve that cannot be made
/// (the disk is already that full) holds nothing; the run goes on without it. A process killed
/// outright leaves its file; the run's resume takes it over.
class DiskReserve {
 public:
  /// Makes the reserve of `bytes` (0: none) for run `run_id`.
  DiskReserve(const std::string& db_path, std::int64_t run_id, std::uint64_t bytes);
  /// Removes the reserve file.
  ~DiskReserve();
  DiskReserve(const DiskReserve&) = delete;
  DiskReserve& operator=(const DiskReserve&) = delete;

  /// Gives the space back (removes the file); true when there was any to give.
  bool release();
  std::uint64_t held_bytes() const { return held_bytes_; }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::uint64_t held_bytes_ = 0;
};

/// True when `what` (an exception's text) says the disk or the database is full (SQLite's
/// SQLITE_FULL, or ENOSPC from the system).
bool says_disk_full(const std::string& what);

}  // namespace calstand::store
