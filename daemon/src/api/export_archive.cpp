#include "daemon/api/export_archive.hpp"

#include <fmt/format.h>
#include <stdlib.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "daemon/api/ustar_writer.hpp"
#include "store/import_export.hpp"

namespace calstand::daemon::api {
namespace {

// A private temporary directory, removed with everything in it when the guard goes.
struct TempDir {
  std::filesystem::path path;
  TempDir() {
    std::string pattern = (std::filesystem::temp_directory_path() / "calstandd-export-XXXXXX").string();
    if (mkdtemp(pattern.data()) == nullptr) throw std::runtime_error("export: cannot create a temporary directory");
    path = pattern;
  }
  ~TempDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path, ignored);
  }
};

std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error("export: cannot read " + path.string());
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

}  // namespace

std::string export_run_archive(store::Database& db, std::int64_t run, const std::string& device) {
  // export_run() writes files; it goes through a private directory so the archive holds
  // exactly what `calstand export` would write.
  TempDir dir;
  store::export_run(db, run, dir.path, store::ExportOptions{device});
  const auto mtime_s = std::chrono::duration_cast<std::chrono::seconds>(
                           std::chrono::system_clock::now().time_since_epoch()).count();
  UstarWriter tar;
  const std::string folder = fmt::format("run-{}/", run);
  for (const char* name : {"meta.json", "samples.csv"}) {
    tar.add_file(folder + name, read_file(dir.path / name), mtime_s);
  }
  return std::move(tar).finish();
}

}  // namespace calstand::daemon::api
