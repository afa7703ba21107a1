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
/// private temporary directory (removed with the object) and the archive is read out of it
/// piece by piece, so a long run's export never sits in memory whole.
class ExportArchive {
 public:
  /// Exports the run (`device` picks the IMU; empty: the run's only one). Throws as
  /// store::export_run().
  ExportArchive(store::Database& db, std::int64_t run, const std::string& device);
  ~ExportArchive();
  ExportArchive(const ExportArchive&) = delete;
  ExportArchive& operator=(const ExportArchive&) = delete;

  /// The next piece of the archive (a header, up to kChunkBytes of a file, its padding, the
  /// end blocks); empty once the whole archive has been given. Throws std::runtime_error when a
  /// file cannot be read.
  std::string next_chunk();
  /// The whole archive's size [bytes].
  std::uint64_t size() const;

  static constexpr std::size_t kChunkBytes = 1 << 20;

 private:
  struct Entry {
    std::string name;  ///< in the archive
    std::filesystem::path path;
    std::uint64_t size = 0;
  };
  std::filesystem::path dir_;
  std::vector<Entry> entries_;
  std::int64_t mtime_s_ = 0;
  // Where next_chunk() is: entry index, and within it the header, the content or the padding.
  std::size_t entry_ = 0;
  enum class Part { kHeader, kContent, kPadding, kEnd, kDone } part_ = Part::kHeader;
  std::ifstream file_;
  std::uint64_t sent_of_file_ = 0;
};

/// The whole archive in memory (small runs, tests).
std::string export_run_archive(store::Database& db, std::int64_t run, const std::string& device);

}  // namespace calstand::daemon::api
