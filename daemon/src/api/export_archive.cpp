#include "daemon/api/export_archive.hpp"

#include <fmt/format.h>
#include <stdlib.h>

#include <algorithm>
#include <ctime>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include "daemon/api/ustar_writer.hpp"
#include "store/import_export.hpp"
#include "store/run_store.hpp"

namespace calstand::daemon::api {
namespace {

// "2026-12-01T16:07:00.914Z" (the store's UTC stamps) as Unix seconds; 0 when unreadable.
std::int64_t unix_seconds(const std::string& utc) {
  std::tm tm{};
  std::istringstream in(utc);
  in >> std::get_time(&tm, "%Y-%m-%dT%H:%M:%S");
  if (in.fail()) return 0;
  return static_cast<std::int64_t>(timegm(&tm));
}

}  // namespace

ExportArchive::ExportArchive(store::Database& db, std::int64_t run, const std::string& device,
                             const std::filesystem::path& work_dir) {
  std::string pattern = (work_dir / ".calstandd-export-XXXXXX").string();
  if (mkdtemp(pattern.data()) == nullptr) {
    throw std::runtime_error("export: cannot create a temporary directory in " + work_dir.string());
  }
  dir_ = pattern;
  try {
    // export_run() writes files; the archive holds exactly what `calstand export` would write.
    store::export_run(db, run, dir_, store::ExportOptions{device});
    const std::string folder = fmt::format("run-{}/", run);
    std::uint64_t offset = 0;
    for (const char* name : {"meta.json", "samples.csv"}) {
      const auto path = dir_ / name;
      const std::uint64_t size = std::filesystem::file_size(path);
      entries_.push_back({folder + name, path, size, offset});
      offset += kUstarBlock + size + ustar_padding(size);
    }
  } catch (...) {
    std::error_code ignored;
    std::filesystem::remove_all(dir_, ignored);
    throw;
  }
  // The files' time in the archive is the run's (its end, else its creation), not the request's:
  // two requests for the same run give the same bytes, so a download can go on by ranges.
  const store::RunSummary summary = store::RunStore(db).load_run(run).summary;
  mtime_s_ = unix_seconds(summary.ended_utc.empty() ? summary.created_utc : summary.ended_utc);
}

ExportArchive::~ExportArchive() {
  file_.close();
  std::error_code ignored;
  std::filesystem::remove_all(dir_, ignored);
}

std::uint64_t ExportArchive::size() const {
  const Entry& last = entries_.back();
  return last.offset + kUstarBlock + last.size + ustar_padding(last.size) + 2 * kUstarBlock;
}

std::string ExportArchive::read_at(std::uint64_t offset, std::size_t max_bytes) {
  // The archive: for each entry its header, its content, its padding; then two zero blocks.
  for (std::size_t i = 0; i < entries_.size(); ++i) {
    const Entry& e = entries_[i];
    const std::uint64_t content = e.offset + kUstarBlock;
    const std::uint64_t padding = content + e.size;
    const std::uint64_t next = padding + ustar_padding(e.size);
    if (offset >= next) continue;
    if (offset < content) {
      const std::string header = ustar_header(e.name, e.size, mtime_s_);
      const std::size_t from = static_cast<std::size_t>(offset - e.offset);
      return header.substr(from, std::min(max_bytes, header.size() - from));
    }
    if (offset < padding) {
      if (!file_open_ || open_entry_ != i) {
        file_.close();
        file_.clear();
        file_.open(e.path, std::ios::binary);
        if (!file_) throw std::runtime_error("export: cannot read " + e.path.string());
        open_entry_ = i;
        file_open_ = true;
      }
      std::string chunk(
          static_cast<std::size_t>(std::min<std::uint64_t>(max_bytes, padding - offset)), '\0');
      file_.seekg(static_cast<std::streamoff>(offset - content));
      file_.read(chunk.data(), static_cast<std::streamsize>(chunk.size()));
      if (static_cast<std::size_t>(file_.gcount()) != chunk.size()) {
        throw std::runtime_error("export: " + e.path.string() + " ended early");
      }
      return chunk;
    }
    return std::string(static_cast<std::size_t>(std::min<std::uint64_t>(max_bytes, next - offset)),
                       '\0');
  }
  const std::uint64_t end = size();
  if (offset >= end) return {};
  return std::string(static_cast<std::size_t>(std::min<std::uint64_t>(max_bytes, end - offset)),
                     '\0');
}

std::string export_run_archive(store::Database& db, std::int64_t run, const std::string& device,
                               const std::filesystem::path& work_dir) {
  ExportArchive archive(db, run, device, work_dir);
  std::string out;
  out.reserve(archive.size());
  for (std::string chunk; !(chunk = archive.read_at(out.size())).empty();) out += chunk;
  return out;
}

}  // namespace calstand::daemon::api
