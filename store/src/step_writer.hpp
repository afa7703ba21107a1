#pragma once
// Private: writes whole completed steps with their samples in one go (imports and derived runs,
// not the run engine's live capture): the step row, exact-encoded sample chunks, one table row
// per sample linked to the step, and the step means. The caller owns the transaction.

#include <SQLiteCpp/Database.h>
#include <SQLiteCpp/Statement.h>

#include <cstdint>
#include <functional>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "core/imu_sample.hpp"
#include "step_stats.hpp"
#include "store/sample_codec.hpp"
#include "store/step_data.hpp"

namespace calstand::store::detail {

/// A completed step as written (attempt 1, good attempt 1).
struct StepRow {
  std::size_t index = 0;
  std::string kind = "capture";
  std::string label;
  nlohmann::json commanded;
  std::string origin;
  double first_s = 0.0;  ///< station clock of the first sample [s]
  double last_s = 0.0;
};

class StepWriter {
 public:
  explicit StepWriter(SQLite::Database& db);
  /// Inserts the step and its samples (table[i] belongs to samples[i]; `table` empty: no table
  /// rows, the step's orientation is not known); returns the step id.
  std::int64_t write(std::int64_t run, const StepRow& step, const std::string& device,
                     std::span<const core::ImuSample> samples, std::span<const TableSample> table);

 private:
  SQLite::Database& db_;
  SQLite::Statement step_;
  SQLite::Statement chunk_;
  SQLite::Statement table_;
  SQLite::Statement means_;
};

/// One step written as its samples arrive (a streamed import): the step row first, the samples
/// in exact chunks as they come, then the step's time span and means. No table rows (the
/// orientation is not known). The caller owns the transaction.
class StepStreamWriter {
 public:
  StepStreamWriter(SQLite::Database& db, std::int64_t run, const StepRow& step, std::string device);
  /// Appends samples in order; full chunks are written at once.
  void append(std::span<const core::ImuSample> samples);
  /// Writes the last chunk, the step's first and last sample time and its means; returns the
  /// step id.
  std::int64_t finish();

 private:
  void insert_chunk();

  SQLite::Database& db_;
  std::int64_t run_;
  std::int64_t step_id_ = 0;
  std::string device_;
  SQLite::Statement chunk_;
  ChunkEncoder enc_;
  StepStats stats_;
  double min_s_ = std::numeric_limits<double>::infinity();
  double max_s_ = -std::numeric_limits<double>::infinity();
};

/// Steps written as their samples arrive, the steps' samples in any interleaving (a streamed
/// calstand-import folder: rows are grouped by their step value, which may come back later in
/// the file). One chunk is open at a time: a sample of another step than the last closes it, so
/// that memory does not grow with the number of steps, and contiguous steps are chunked exactly
/// as StepWriter chunks them. The caller owns the transaction.
class StepsStreamWriter {
 public:
  /// `table`: each sample comes with its table state (one table row per sample).
  StepsStreamWriter(SQLite::Database& db, std::int64_t run, std::string device, bool table);
  StepsStreamWriter(const StepsStreamWriter&) = delete;
  StepsStreamWriter& operator=(const StepsStreamWriter&) = delete;

  /// Inserts a step's row (its times and commanded state may be updated by finish()); returns
  /// its handle for append(), 0, 1, ... in the order of the calls.
  std::size_t begin(const StepRow& step);
  /// Appends sample `s` of step `handle`, with its table state when the writer has a table.
  void append(std::size_t handle, const core::ImuSample& s, const TableSample& table);
  /// Writes the open chunk and, for each step, its time span, `commanded(handle)` (when given)
  /// and its means.
  void finish(const std::function<nlohmann::json(std::size_t)>& commanded = {});

 private:
  struct Step {
    std::int64_t id = 0;
    StepStats stats;
    double min_s = std::numeric_limits<double>::infinity();
    double max_s = -std::numeric_limits<double>::infinity();
  };
  void close_chunk();

  SQLite::Database& db_;
  std::int64_t run_;
  std::string device_;
  bool table_;
  SQLite::Statement step_insert_;
  SQLite::Statement chunk_;
  SQLite::Statement table_insert_;
  ChunkEncoder enc_;
  std::vector<Step> steps_;
  std::size_t open_ = 0;  // the step of the open chunk
};

}  // namespace calstand::store::detail
