#include "daemon/api/export_archive.hpp"

#include <fmt/format.h>
#include <stdlib.h>

#include <algorithm>
#include <chrono>
#include <stdexcept>

#include "daemon/api/ustar_writer.hpp"
#include "store/import_export.hpp"

namespace calstand::daemon::api {

ExportArchive::ExportArchive(store::Database& db, std::int64_t run, const std::string& device) {
  std::string pattern = (std::filesystem::temp_directory_path() / "calstandd-export-XXXXXX").string();
  if (mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("export: cannot create a temporary directory");
  dir_ = pattern;
  try {
    // export_run() writes files; the archive holds exactly what `calstand export` would write.
    store::export_run(db, run, dir_, store::ExportOptions{device});
    const std::string folder = fmt::format("run-{}/", run);
    for (const char* name : {"meta.json", "samples.csv"}) {
      const auto path = dir_ / name;
      entries_.push_back({folder + name, path, std::filesystem::file_size(path)});
    }
  } catch (...) {
    std::error_code ignored;
    std::filesystem::remove_all(dir_, ignored);
    throw;
  }
  mtime_s_ = std::chrono::duration_cast<std::chrono::seconds>(
                 std::chrono::system_clock::now().time_since_epoch()).count();
}

ExportArchive::~ExportArchive() {
  file_.close();
  std::error_code ignored;
  std::filesystem::remove_all(dir_, ignored);
}

std::uint64_t ExportArchive::size() const {
  std::uint64_t total = 2 * kUstarBlock;  // the end blocks
  for (const auto& e : entries_) total += kUstarBlock + e.size + ustar_padding(e.size);
  return total;
}

std::string ExportArchive::next_chunk() {
  for (;;) {
    switch (part_) {
      case Part::kHeader: {
        if (entry_ == entries_.size()) {
          part_ = Part::kEnd;
          continue;
        }
        const Entry& e = entries_[entry_];
        file_ = std::ifstream(e.path, std::ios::binary);
        if (!file_) throw std::runtime_error("export: cannot read " + e.path.string());
        sent_of_file_ = 0;
        part_ = Part::kContent;
        return ustar_header(e.name, e.size, mtime_s_);
      }
      case Part::kContent: {
        const Entry& e = entries_[entry_];
        if (sent_of_file_ == e.size) {
          part_ = Part::kPadding;
          continue;
        }
        std::string chunk(std::min<std::uint64_t>(kChunkBytes, e.size - sent_of_file_), '\0');
        file_.read(chunk.data(), static_cast<std::streamsize>(chunk.size()));
        if (static_cast<std::size_t>(file_.gcount()) != chunk.size()) {
          throw std::runtime_error("export: " + e.path.string() + " ended early");
        }
        sent_of_file_ += chunk.size();
        return chunk;
      }
      case Part::kPadding: {
        const std::size_t padding = ustar_padding(entries_[entry_].size);
        file_.close();
        ++entry_;
        part_ = Part::kHeader;
        if (padding > 0) return std::string(padding, '\0');
        continue;
      }
      case Part::kEnd:
        part_ = Part::kDone;
        return std::string(2 * kUstarBlock, '\0');
      case Part::kDone:
        return {};
    }
  }
}

std::string export_run_archive(store::Database& db, std::int64_t run, const std::string& device) {
  ExportArchive archive(db, run, device);
  std::string out;
  out.reserve(archive.size());
  for (std::string chunk; !(chunk = archive.next_chunk()).empty();) out += chunk;
  return out;
}

}  // namespace calstand::daemon::api
