#pragma once
// Private: writes whole completed steps with their samples in one go (imports and derived runs,
// not the run engine's live capture): the step row, exact-encoded sample chunks, one table row
// per sample linked to the step, and the step means. The caller owns the transaction.

#include <SQLiteCpp/Database.h>
#include <SQLiteCpp/Statement.h>

#include <cstdint>
#include <span>
#include <string>

#include "core/imu_sample.hpp"
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

}  // namespace calstand::store::detail
