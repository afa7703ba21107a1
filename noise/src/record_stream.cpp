// Long records fed to a DeviationStream without holding them: a CSV column read in blocks, or a
// stored step's channel chunk by chunk.
#include "noise/record_stream.hpp"

#include <fmt/format.h>

#include <span>
#include <vector>

#include "core/csv_reader.hpp"
#include "core/error.hpp"
#include "store/sample_reader.hpp"

namespace calstand::solver {

namespace {

// Opens the CSV file `path` as `calstand allan --csv` reads it (a header line; blank lines
// anywhere and quotes dropped) and calls fn(reader, index of `column`).
template <class Fn>
auto with_csv_column(const std::string& path, const std::string& column, Fn fn) {
  core::CsvOptions options;
  options.blank_lines_anywhere = true;
  options.unquote = true;
  core::CsvReader csv(path, options);
  const auto index = csv.column(column);
  if (!index) {
    throw core::InputError(path,
                           fmt::format("no column '{}' in the header ({})", column, csv.header()));
  }
  csv.require_unique_columns();
  return fn(csv, *index);
}

}  // namespace

void stream_csv_column(const std::string& path, const std::string& column,
                       DeviationStream& stream) {
  with_csv_column(path, column, [&](core::CsvReader& csv, std::size_t index) {
    csv.for_each_number_block(index, [&](std::span<const double> block) { stream.push(block); });
  });
}

std::vector<double> read_csv_column(const std::string& path, const std::string& column) {
  return with_csv_column(path, column, [](core::CsvReader& csv, std::size_t index) {
    return csv.remaining_numbers(index, 2);
  });
}

StoredStream stream_stored_channel(store::Database& db, std::int64_t run, std::size_t step,
                                   const std::string& device, ImuChannel channel,
                                   DeviationStream& stream) {
  StoredStream out;
  double first_s = 0.0, last_s = 0.0;
  std::vector<double> values;
  const auto axis = static_cast<Eigen::Index>(static_cast<int>(channel) % 3);
  const bool gyro = is_gyro(channel);
  store::for_each_chunk(db, run, step, device,
                        [&](const store::ChunkInfo&, std::span<const core::ImuSample> samples) {
                          if (samples.empty()) return;
                          if (out.samples == 0) first_s = samples.front().device_time_s;
                          last_s = samples.back().device_time_s;
                          out.samples += samples.size();
                          values.clear();
                          for (const core::ImuSample& s : samples) {
                            values.push_back(gyro ? s.gyro_dps(axis) : s.accel_mps2(axis));
                          }
                          stream.push(values);
                        });
  if (out.samples == 0) {
    throw core::InputError(
        "--step", fmt::format("step {} of run {} holds no samples of '{}'", step, run, device));
  }
  // As sample_rate_of(): (n - 1) over the time the device clock spans.
  if (out.samples < 2) {
    throw core::InputError("samples",
                           fmt::format("{} samples; a sample rate needs 2", out.samples));
  }
  const double span = last_s - first_s;
  if (!(span > 0.0) || !std::isfinite(span)) {
    throw core::InputError("samples", "the device clock does not advance over the samples");
  }
  out.sample_rate_hz = static_cast<double>(out.samples - 1) / span;
  return out;
}

}  // namespace calstand::solver
