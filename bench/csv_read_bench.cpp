// Reading a numeric CSV file (issue 15): the reader of `calstand import` and `calstand allan
// --csv` (core::CsvReader: large blocks, fast_float) against the std::getline plus
// std::stringstream reader `allan --csv` had, on a generated file of 2 million IMU rows
// (t,gx,gy,gz,ax,ay,az; 14 million numbers, about 150 MB, written once to the temp folder and
// read from the page cache).
//
//   build/bench/calstand_bench --benchmark_filter=Csv
//
// samples_per_s counts rows; numbers_per_s the values parsed. BM_ParseNumbers compares the two
// number parsers alone (std::from_chars, fast_float when its header is installed) on the same
// fields held in memory: why CsvReader uses fast_float is in core/csv_reader.hpp.
#include <benchmark/benchmark.h>
#include <fmt/format.h>
#include <unistd.h>

#include <charconv>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "core/csv_reader.hpp"

#if __has_include(<fast_float/fast_float.h>)
#include <fast_float/fast_float.h>
#define CALSTAND_HAVE_FAST_FLOAT 1
#endif

namespace calstand::core {
namespace {

constexpr std::size_t kRows = 2'000'000;
constexpr std::size_t kColumns = 7;

// The file, written once per process and removed at exit.
struct BenchFile {
  std::filesystem::path path;
  BenchFile() {
    path = std::filesystem::temp_directory_path() /
           ("calstand-csv-bench-" + std::to_string(::getpid()) + ".csv");
    std::mt19937_64 rng(1);
    std::normal_distribution<double> noise(0.0, 1.0);
    std::FILE* f = std::fopen(path.c_str(), "wb");
    std::fputs("t,gx,gy,gz,ax,ay,az\n", f);
    fmt::memory_buffer line;
    for (std::size_t i = 0; i < kRows; ++i) {
      line.clear();
      // As an IMU logger writes: 9 significant digits, gyro near zero, accel near 1 g.
      fmt::format_to(std::back_inserter(line), "{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g},{:.9g}\n",
                     0.01 * static_cast<double>(i), 1e-3 * noise(rng), 1e-3 * noise(rng),
                     1e-3 * noise(rng), 0.01 * noise(rng), 0.01 * noise(rng),
                     9.80665 + 0.01 * noise(rng));
      std::fwrite(line.data(), 1, line.size(), f);
    }
    std::fclose(f);
  }
  ~BenchFile() {
    std::error_code ec;
    std::filesystem::remove(path, ec);
  }
};

const std::filesystem::path& bench_file() {
  static const BenchFile file;
  return file.path;
}

void count(benchmark::State& state, std::size_t rows) {
  state.counters["samples_per_s"] =
      benchmark::Counter(static_cast<double>(rows) * static_cast<double>(state.iterations()),
                         benchmark::Counter::kIsRate);
  state.counters["numbers_per_s"] = benchmark::Counter(
      static_cast<double>(rows * kColumns) * static_cast<double>(state.iterations()),
      benchmark::Counter::kIsRate);
}

// The baseline, as `calstand allan --csv` read before: std::getline per line, a
// std::stringstream split into std::string fields, each trimmed and parsed.
void BM_CsvBaselineGetlineStringstream(benchmark::State& state) {
  const auto& path = bench_file();
  std::size_t rows = 0;
  for (auto _ : state) {
    std::ifstream in(path);
    std::string line;
    std::getline(in, line);  // header
    std::vector<double> values;
    values.reserve(kRows * kColumns);
    rows = 0;
    while (std::getline(in, line)) {
      std::vector<std::string> fields;
      std::stringstream ss(line);
      std::string f;
      while (std::getline(ss, f, ',')) {
        const auto a = f.find_first_not_of(" \t\r\"");
        const auto b = f.find_last_not_of(" \t\r\"");
        fields.push_back(a == std::string::npos ? "" : f.substr(a, b - a + 1));
      }
      for (const std::string& field : fields) {
        double v = 0.0;
        std::from_chars(field.data(), field.data() + field.size(), v);
        values.push_back(v);
      }
      ++rows;
    }
    benchmark::DoNotOptimize(values.data());
  }
  count(state, rows);
}

// core::CsvReader, every field parsed as `calstand import` does.
void BM_CsvReader(benchmark::State& state) {
  const auto& path = bench_file();
  std::size_t rows = 0;
  for (auto _ : state) {
    CsvReader csv(path);
    std::vector<double> values;
    values.reserve(kRows * kColumns);
    rows = 0;
    while (csv.next()) {
      for (std::size_t i = 0; i < kColumns; ++i) values.push_back(csv.number(i));
      ++rows;
    }
    benchmark::DoNotOptimize(values.data());
  }
  count(state, rows);
}

// core::CsvReader, one column parsed (`calstand allan --csv --column gx`).
void BM_CsvReaderOneColumn(benchmark::State& state) {
  const auto& path = bench_file();
  std::size_t rows = 0;
  for (auto _ : state) {
    CsvReader csv(path);
    std::vector<double> values;
    values.reserve(kRows);
    rows = 0;
    while (csv.next()) {
      values.push_back(csv.number(1));
      ++rows;
    }
    benchmark::DoNotOptimize(values.data());
  }
  count(state, rows);
}

// CsvReader::remaining_numbers, what `calstand allan --csv` calls: one column, the rest of the
// file on state.range(0) threads (1: one field per row on the calling thread; 2: two byte
// ranges). Real time is the figure: the threads' CPU time is not in Google Benchmark's CPU time.
void BM_CsvReaderRemainingNumbers(benchmark::State& state) {
  const auto& path = bench_file();
  std::size_t rows = 0;
  for (auto _ : state) {
    CsvReader csv(path);
    const std::vector<double> values =
        csv.remaining_numbers(1, static_cast<unsigned>(state.range(0)));
    rows = values.size();
    benchmark::DoNotOptimize(values.data());
  }
  count(state, rows);
}

// The fields of the first 500,000 rows, in memory, for the number parsers alone.
struct Fields {
  std::string text;
  std::vector<std::pair<std::size_t, std::size_t>> spans;
  Fields() {
    CsvReader csv(bench_file());
    while (csv.next() && spans.size() < 500'000 * kColumns) {
      for (std::size_t i = 0; i < kColumns; ++i) {
        spans.emplace_back(text.size(), csv.field(i).size());
        text += csv.field(i);
      }
    }
  }
};

const Fields& fields() {
  static const Fields f;
  return f;
}

template <typename Parse>
void parse_numbers(benchmark::State& state, Parse parse) {
  const Fields& f = fields();
  for (auto _ : state) {
    double sum = 0.0;
    for (const auto& [at, size] : f.spans) sum += parse(f.text.data() + at, size);
    benchmark::DoNotOptimize(sum);
  }
  state.counters["numbers_per_s"] = benchmark::Counter(
      static_cast<double>(f.spans.size()) * static_cast<double>(state.iterations()),
      benchmark::Counter::kIsRate);
}

void BM_ParseNumbersFromChars(benchmark::State& state) {
  parse_numbers(state, [](const char* p, std::size_t n) {
    double v = 0.0;
    std::from_chars(p, p + n, v);
    return v;
  });
}
BENCHMARK(BM_CsvBaselineGetlineStringstream)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CsvReader)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CsvReaderOneColumn)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_CsvReaderRemainingNumbers)
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(BM_ParseNumbersFromChars)->Unit(benchmark::kMillisecond);

#ifdef CALSTAND_HAVE_FAST_FLOAT
void BM_ParseNumbersFastFloat(benchmark::State& state) {
  parse_numbers(state, [](const char* p, std::size_t n) {
    double v = 0.0;
    fast_float::from_chars(p, p + n, v);
    return v;
  });
}
BENCHMARK(BM_ParseNumbersFastFloat)->Unit(benchmark::kMillisecond);
#endif

}  // namespace
}  // namespace calstand::core
