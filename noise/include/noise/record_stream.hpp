#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "noise/deviation_stream.hpp"
#include "noise/run_noise.hpp"
#include "store/database.hpp"

namespace calstand::solver {

/// Feeds column `column` of the CSV file `path` (a header line; blank lines anywhere and
/// quotes dropped, as `calstand allan --csv` reads it) into `stream`, in blocks read on two
/// threads (core::CsvReader::for_each_number_block): memory does not grow with the file.
/// Throws core::InputError naming the file for a column the header lacks or names twice, and
/// `FILE:LINE: column C: ...` for a bad row (the values before it have been pushed).
void stream_csv_column(const std::string& path, const std::string& column, DeviationStream& stream);

/// Column `column` of the CSV file `path` whole, read as stream_csv_column() reads it (two
/// threads, core::CsvReader::remaining_numbers), for the kinds that need the whole record in
/// memory. Throws as stream_csv_column().
std::vector<double> read_csv_column(const std::string& path, const std::string& column);

/// What stream_stored_channel() fed.
struct StoredStream {
  std::size_t samples = 0;
  double sample_rate_hz = 0.0;  ///< from the device clock, as sample_rate_of()
};

/// Feeds `channel` (in its unit, channel_unit()) of `device`'s samples in step `step` of `run`
/// into `stream`, chunk by chunk as stored (store::for_each_chunk): memory does not grow with
/// the step. Throws core::InputError naming the step when it holds none of `device`'s samples,
/// as sample_rate_of() for fewer than 2 or a clock that does not advance, and as
/// store::for_each_chunk.
StoredStream stream_stored_channel(store::Database& db, std::int64_t run, std::size_t step,
                                   const std::string& device, ImuChannel channel,
                                   DeviationStream& stream);

}  // namespace calstand::solver
