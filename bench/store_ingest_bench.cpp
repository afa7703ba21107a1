// Capture ingest: IMU samples per second through store::CaptureWriter into a WAL database on
// disk, against the plain one-row-per-sample INSERT baseline (prepared statement, 10k rows per
// transaction: the best case for rows), and database bytes per sample. Targets (issue 3):
// 2 million samples/s, at least 20x the baseline, under 40 bytes per sample.
//
//   build/bench/calstand_bench --benchmark_filter=Ingest
//
// Counters: items_per_second = samples/s (wall clock: the writer works on its own thread);
// bytes_per_sample = database file size after a checkpoint / samples stored; cpu_cores = process
// CPU time / wall time (how many cores the ingest kept busy); cpu_ns_per_sample = process CPU
// time per sample, all threads (1e9 / it is the rate one core would sustain, and it is less
// disturbed than wall time on a machine shared with other work).
#include <SQLiteCpp/Statement.h>
#include <SQLiteCpp/Transaction.h>
#include <benchmark/benchmark.h>
#include <sys/resource.h>
#include <unistd.h>

#include <filesystem>
#include <string>
#include <vector>

#include "store/capture_writer.hpp"
#include "store/database.hpp"
#include "store/run_store.hpp"

namespace calstand::store {
namespace {

constexpr std::size_t kBatch = 1000;  // samples per push: what a driver poll delivers

std::filesystem::path fresh_db(const char* name) {
  const auto path = std::filesystem::temp_directory_path() /
                    (std::string("calstand-bench-") + std::to_string(::getpid()) + "-" + name);
  for (const char* suffix : {"", "-wal", "-shm"}) std::filesystem::remove(path.string() + suffix);
  return path;
}

void remove_db(const std::filesystem::path& path) {
  for (const char* suffix : {"", "-wal", "-shm"}) std::filesystem::remove(path.string() + suffix);
}

double process_cpu_s() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

// A 1 kHz IMU at rest with noise-like variation in every channel (so nothing compresses).
std::vector<core::ImuSample> make_batch(std::uint32_t first) {
  std::vector<core::ImuSample> b(kBatch);
  for (std::size_t i = 0; i < kBatch; ++i) {
    const auto n = first + static_cast<std::uint32_t>(i);
    auto& s = b[i];
    s.sequence = n;
    s.receive_time_s = 1e-3 * n;
    s.device_time_s = 1e-3 * n + 0.5;
    s.gyro_dps = {1e-3 * (n % 97), -2e-3 * (n % 89), 4e-3 + 1e-5 * (n % 83)};
    s.accel_mps2 = {1e-4 * (n % 79), 2e-4 * (n % 73), 9.79 + 1e-5 * (n % 71)};
    s.temperature_c = 25.0 + 1e-3 * (n % 67);
  }
  return b;
}

double file_bytes(Database& db) {
  db.sql().exec("PRAGMA wal_checkpoint(TRUNCATE)");
  return static_cast<double>(std::filesystem::file_size(db.path()));
}

void BM_IngestCaptureWriter(benchmark::State& state) {
  const auto samples_per_step = static_cast<std::uint32_t>(state.range(0));
  const auto path = fresh_db("writer.db");
  double bytes = 0.0;
  std::uint64_t total = 0;
  double cpu = 0.0;
  double wall = 0.0;
  {
    Database db(path.string());
    RunStore runs(db);
    const auto run = runs.create_run({});
    std::vector<NewStep> steps(2000, NewStep{"capture", "c", {}, "steps[0]"});
    const auto step_ids = runs.add_steps(run, steps);
    std::vector<std::vector<core::ImuSample>> batches;
    for (std::uint32_t k = 0; k < samples_per_step / kBatch; ++k) {
      batches.push_back(make_batch(k * static_cast<std::uint32_t>(kBatch)));
    }
    std::size_t step = 0;
    {
      // Room for a whole step: the engine's queue is sized for its stalls; here the producer
      // outruns the disk on purpose, and a refusal would be a recorded fault, not back-pressure.
      CaptureWriterOptions options;
      options.queue_capacity = 2 * samples_per_step;
      CaptureWriter writer(path.string(), options);
      for (auto _ : state) {
        const double cpu0 = process_cpu_s();
        const auto t0 = std::chrono::steady_clock::now();
        const auto sid = step_ids.at(step++ % step_ids.size());
        const auto stream = writer.open_stream(run, sid, 1, "imu0");
        for (const auto& b : batches) {
          if (!writer.push(stream, b)) break;  // reported below
        }
        total += writer.commit_step(sid, 1).samples;
        wall += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        cpu += process_cpu_s() - cpu0;
      }
      if (writer.counters().dropped_queue_full != 0) {
        state.SkipWithError("samples were refused (queue full)");  // never in this benchmark
      }
    }
    bytes = file_bytes(db);
  }
  remove_db(path);
  state.SetItemsProcessed(static_cast<std::int64_t>(total));
  state.counters["bytes_per_sample"] = bytes / static_cast<double>(total);
  state.counters["cpu_cores"] = cpu / wall;
  state.counters["cpu_ns_per_sample"] = 1e9 * cpu / static_cast<double>(total);
}
BENCHMARK(BM_IngestCaptureWriter)
    ->Arg(1 << 20)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond)
    ->MinTime(3.0);

void BM_IngestRowPerSampleBaseline(benchmark::State& state) {
  const auto n = static_cast<std::uint32_t>(state.range(0));
  const auto path = fresh_db("rows.db");
  double bytes = 0.0;
  std::uint64_t total = 0;
  double cpu = 0.0;
  {
    Database db(path.string());
    db.sql().exec(
        "CREATE TABLE samples (step_id INTEGER NOT NULL, device TEXT NOT NULL, "
        "receive_time_s REAL, device_time_s REAL, sequence INTEGER, gx REAL, gy REAL, gz REAL, "
        "ax REAL, ay REAL, az REAL, temperature_c REAL)");
    std::vector<std::vector<core::ImuSample>> batches;
    for (std::uint32_t k = 0; k < n / kBatch; ++k) {
      batches.push_back(make_batch(k * static_cast<std::uint32_t>(kBatch)));
    }
    SQLite::Statement ins(db.sql(),
                          "INSERT INTO samples VALUES (?, 'imu0', ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)");
    std::int64_t step = 0;
    for (auto _ : state) {
      const double cpu0 = process_cpu_s();
      ++step;
      for (std::size_t k = 0; k < batches.size(); k += 10) {
        SQLite::Transaction tx(db.sql());
        for (std::size_t j = k; j < std::min(k + 10, batches.size()); ++j) {
          for (const auto& s : batches[j]) {
            ins.reset();
            ins.bind(1, step);
            ins.bind(2, s.receive_time_s);
            ins.bind(3, s.device_time_s);
            ins.bind(4, s.sequence);
            for (int i = 0; i < 3; ++i) {
              ins.bind(5 + i, s.gyro_dps[i]);
              ins.bind(8 + i, s.accel_mps2[i]);
            }
            ins.bind(11, s.temperature_c);
            ins.exec();
            ++total;
          }
        }
        tx.commit();
      }
      cpu += process_cpu_s() - cpu0;
    }
    bytes = file_bytes(db);
  }
  remove_db(path);
  state.SetItemsProcessed(static_cast<std::int64_t>(total));
  state.counters["bytes_per_sample"] = bytes / static_cast<double>(total);
  state.counters["cpu_ns_per_sample"] = 1e9 * cpu / static_cast<double>(total);
}
BENCHMARK(BM_IngestRowPerSampleBaseline)
    ->Arg(1 << 17)
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond)
    ->MinTime(3.0);

}  // namespace
}  // namespace calstand::store
