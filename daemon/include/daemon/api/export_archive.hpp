#pragma once

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "store/database.hpp"

namespace calstand::daemon::api {

/// Run `run` as a `calstand-import/1` folder packed in a ustar archive: `run-ID/meta.json` and
/// `run-ID/samples.csv`, exactly as `calstand export` writes them. The folder is written to a
/// private temporary directory under `work_dir` (removed with the object; beside the
/// database, not in a /tmp that may live in memory) and the archive is read out of it piece by
/// piece at any offset (HTTP ranges), so a long run's export never sits in memory whole.
class ExportArchive {
 public:
  /// Exports the run (`device` picks the IMU; empty: the run's only one). Throws as
  /// store::export_run(), std::runtime_error when `work_dir` takes no temporary directory.
  ExportArchive(store::Database& db, std::int64_t run, const std::string& device,
                const std::filesystem::path& work_dir);
  ~ExportArchive();
  ExportArchive(const ExportArchive&) = delete;
  ExportArchive& operator=(const ExportArchive&) = delete;

  /// The whole archive's size [bytes].
  std::uint64_t size() const;
  /// Up to `max_bytes` of the archive from byte `offset` (fewer at the end of a piece: a
  /// header, a file, its padding, the end blocks); empty at or past the end. Throws
  /// std::runtime_error when a file cannot be read.
  std::string read_at(std::uint64_t offset, std::size_t max_bytes = kChunkBytes);

  static constexpr std::size_t kChunkBytes = 1 << 20;

 private:
  struct Entry {
    std::string name;  ///< in the archive
    std::filesystem::path path;
    std::uint64_t size = 0;
    std::uint64_t offset = 0;  ///< of its header in the archive
  };
  std::filesystem::path dir_;
  std::vector<Entry> entries_;
  std::int64_t mtime_s_ = 0;
  std::ifstream file_;  // the entry last read, kept open for sequential reads
  std::size_t open_entry_ = 0;
  bool file_open_ = false;
};

/// The whole archive in memory (small runs, tests).
std::string export_run_archive(store::Database& db, std::int64_t run, const std::string& device,
                               const std::filesystem::path& work_dir);

}  // namespace calstand::daemon::api
