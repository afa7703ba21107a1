// Reading and importing a recording (issue 32), per format: samples per second of the reader
// alone (decompress and decode) and of the whole import into a database file (read, decode,
// store), and the peak resident memory after each. A plain program:
//
//   calstand_recording_import_bench RECORDING [RECORDING...] [--topic NAME]
//
// Recordings as tests/support/write_recordings.py or bench/import_bench.py write them.

#include <fmt/format.h>
#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "store/database.hpp"
#include "store/import_recording.hpp"
#include "store/recording_reader.hpp"

namespace {

double peak_rss_mb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_maxrss) / 1024.0;
}

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

int main(int argc, char** argv) {
  using namespace calstand;
  std::vector<std::string> files;
  std::string topic;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--topic" && i + 1 < argc) {
      topic = argv[++i];
    } else {
      files.push_back(a);
    }
  }
  if (files.empty()) {
    std::fprintf(stderr, "usage: %s RECORDING [RECORDING...] [--topic NAME]\n", argv[0]);
    return 2;
  }
  try {
    for (const std::string& f : files) {
      auto reader = store::open_recording(f);
      std::string name = topic;
      if (name.empty()) {
        for (const auto& t : reader->topics()) {
          if (t.imu) name = t.name;
        }
      }
      auto t0 = std::chrono::steady_clock::now();
      reader->select(name);
      std::vector<store::ImuRecord> batch;
      std::uint64_t n = 0;
      double check = 0.0;
      while (reader->read(batch, 8192)) {
        n += batch.size();
        for (const auto& r : batch) check += r.gyro_rad_s.x();
      }
      const double read_s = seconds_since(t0);
      const double read_rss = peak_rss_mb();

      const std::filesystem::path db_path =
          std::filesystem::temp_directory_path() / "calstand-recording-import-bench.db";
      for (const char* suffix : {"", "-wal", "-shm"}) {
        std::filesystem::remove(db_path.string() + suffix);
      }
      t0 = std::chrono::steady_clock::now();
      {
        store::Database db(db_path.string());
        store::RecordingImportOptions o;
        o.topic = name;
        o.latitude_deg = 45.0;
        o.height_m = 0.0;
        store::import_recording(db, f, o);
      }
      const double import_s = seconds_since(t0);
      for (const char* suffix : {"", "-wal", "-shm"}) {
        std::filesystem::remove(db_path.string() + suffix);
      }
      std::printf(
          "%s (%s, %s): %llu samples; read %.3f s (%.2f M samples/s, peak %.0f MB); "
          "import %.3f s (%.2f M samples/s, peak %.0f MB)%s\n",
          f.c_str(), reader->format().c_str(), name.c_str(), static_cast<unsigned long long>(n),
          read_s, static_cast<double>(n) / read_s / 1e6, read_rss, import_s,
          static_cast<double>(n) / import_s / 1e6, peak_rss_mb(), check == 12345.678 ? "!" : "");
    }
  } catch (const core::InputError& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
  return 0;
}
