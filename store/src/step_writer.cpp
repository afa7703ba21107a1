#include "step_writer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "step_stats.hpp"
#include "store/sample_codec.hpp"

namespace calstand::store::detail {

namespace {

// One row of each table a step writes, shared by the three writers below.
constexpr const char* kStepInsert =
    "INSERT INTO steps (run_id, idx, kind, label, commanded, origin, status, attempts, "
    "good_attempt, started_clock_s, ended_clock_s) VALUES (?, ?, ?, ?, ?, ?, 'completed', 1, 1, "
    "?, ?)";
constexpr const char* kChunkInsert =
    "INSERT INTO sample_chunks (run_id, step_id, attempt, device, first_receive_time_s, "
    "last_receive_time_s, count, encoding, data) VALUES (?, ?, 1, ?, ?, ?, ?, ?, ?)";
constexpr const char* kTableInsert =
    "INSERT INTO table_telemetry (run_id, step_id, time_s, outer_deg, inner_deg, "
    "outer_rate_dps, inner_rate_dps) VALUES (?, ?, ?, ?, ?, ?, ?)";
constexpr const char* kStepMeansInsert =
    "INSERT INTO step_means (run_id, step_id, attempt, device, count, "
    "first_receive_time_s, last_receive_time_s, gx_dps, gy_dps, gz_dps, ax_mps2, "
    "ay_mps2, az_mps2, temperature_c, std_gx_dps, std_gy_dps, std_gz_dps, "
    "std_ax_mps2, std_ay_mps2, std_az_mps2, std_temperature_c) VALUES (?, ?, 1, ?, "
    "?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)";

/// The step's row (kStepInsert); its id.
std::int64_t insert_step_row(SQLite::Database& db, SQLite::Statement& st, std::int64_t run,
                             const StepRow& step) {
  st.reset();
  st.bind(1, run);
  st.bind(2, static_cast<std::int64_t>(step.index));
  st.bind(3, step.kind);
  st.bind(4, step.label);
  st.bind(5, step.commanded.dump());
  st.bind(6, step.origin);
  st.bind(7, step.first_s);
  st.bind(8, step.last_s);
  st.exec();
  return db.getLastInsertRowid();
}

/// The encoder's samples as one chunk (kChunkInsert).
void insert_chunk_row(SQLite::Statement& st, std::int64_t run, std::int64_t step_id,
                      const std::string& device, const ChunkEncoder& enc) {
  st.reset();
  st.bind(1, run);
  st.bind(2, step_id);
  st.bind(3, device);
  st.bind(4, enc.first_receive_time_s());
  st.bind(5, enc.last_receive_time_s());
  st.bind(6, static_cast<std::int64_t>(enc.count()));
  st.bind(7, static_cast<int>(enc.encoding()));
  const auto blob = enc.bytes();
  st.bindNoCopy(8, blob.data(), static_cast<int>(blob.size()));
  st.exec();
}

/// One table state at a sample's time (kTableInsert).
void insert_table_row(SQLite::Statement& st, std::int64_t run, std::int64_t step_id, double time_s,
                      const TableSample& table) {
  st.reset();
  st.bind(1, run);
  st.bind(2, step_id);
  st.bind(3, time_s);
  st.bind(4, table.outer_deg);
  st.bind(5, table.inner_deg);
  st.bind(6, table.outer_rate_dps);
  st.bind(7, table.inner_rate_dps);
  st.exec();
}

/// The step's means and standard deviations (kStepMeansInsert; a deviation of one sample NULL).
void insert_means_row(SQLite::Statement& st, std::int64_t run, std::int64_t step_id,
                      const std::string& device, const StepStats& stats) {
  st.reset();
  st.bind(1, run);
  st.bind(2, step_id);
  st.bind(3, device);
  st.bind(4, static_cast<std::int64_t>(stats.count()));
  st.bind(5, stats.first_time_s());
  st.bind(6, stats.last_time_s());
  for (int c = 0; c < StepStats::kChannels; ++c) {
    st.bind(7 + c, stats.mean(c));
    const double sd = stats.stddev(c);
    if (std::isfinite(sd)) {
      st.bind(14 + c, sd);
    } else {
      st.bind(14 + c);
    }
  }
  st.exec();
}

}  // namespace

StepWriter::StepWriter(SQLite::Database& db)
    : db_(db),
      step_(db, kStepInsert),
      chunk_(db, kChunkInsert),
      table_(db, kTableInsert),
      means_(db, kStepMeansInsert) {}

std::int64_t StepWriter::write(std::int64_t run, const StepRow& step, const std::string& device,
                               std::span<const core::ImuSample> samples,
                               std::span<const TableSample> table) {
  if (!table.empty() && table.size() != samples.size()) {
    throw std::logic_error("StepWriter::write: one table state per sample, or none");
  }
  const std::int64_t step_id = insert_step_row(db_, step_, run, step);
  const auto insert_chunk = [&](const ChunkEncoder& enc) {
    insert_chunk_row(chunk_, run, step_id, device, enc);
  };
  ChunkEncoder enc(SampleEncoding::kExact);
  StepStats stats;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    if (!enc.fits(samples[i])) {
      insert_chunk(enc);
      enc.clear();
    }
    enc.append(samples[i]);
    stats.add(samples[i]);
    if (table.empty()) continue;  // no table state (orientation not known)
    insert_table_row(table_, run, step_id, samples[i].receive_time_s, table[i]);
  }
  if (enc.count() > 0) insert_chunk(enc);

  insert_means_row(means_, run, step_id, device, stats);
  return step_id;
}

StepStreamWriter::StepStreamWriter(SQLite::Database& db, std::int64_t run, const StepRow& step,
                                   std::string device)
    : db_(db),
      run_(run),
      device_(std::move(device)),
      chunk_(db, kChunkInsert),
      enc_(SampleEncoding::kExact) {
  SQLite::Statement st(db_, kStepInsert);
  step_id_ = insert_step_row(db_, st, run, step);
}

void StepStreamWriter::insert_chunk() {
  insert_chunk_row(chunk_, run_, step_id_, device_, enc_);
  enc_.clear();
}

void StepStreamWriter::append(std::span<const core::ImuSample> samples) {
  for (const core::ImuSample& s : samples) {
    if (!enc_.fits(s)) insert_chunk();
    enc_.append(s);
    stats_.add(s);
    min_s_ = std::min(min_s_, s.receive_time_s);
    max_s_ = std::max(max_s_, s.receive_time_s);
  }
}

std::int64_t StepStreamWriter::finish() {
  if (!enc_.empty()) insert_chunk();
  SQLite::Statement span(db_,
                         "UPDATE steps SET started_clock_s = ?, ended_clock_s = ? WHERE id = ?");
  span.bind(1, min_s_);
  span.bind(2, max_s_);
  span.bind(3, step_id_);
  span.exec();
  SQLite::Statement means(db_, kStepMeansInsert);
  insert_means_row(means, run_, step_id_, device_, stats_);
  return step_id_;
}

StepsStreamWriter::StepsStreamWriter(SQLite::Database& db, std::int64_t run, std::string device,
                                     bool table)
    : db_(db),
      run_(run),
      device_(std::move(device)),
      table_(table),
      step_insert_(db, kStepInsert),
      chunk_(db, kChunkInsert),
      table_insert_(db, kTableInsert),
      enc_(SampleEncoding::kExact) {}

std::size_t StepsStreamWriter::begin(const StepRow& step) {
  steps_.push_back({});
  steps_.back().id = insert_step_row(db_, step_insert_, run_, step);
  return steps_.size() - 1;
}

void StepsStreamWriter::close_chunk() {
  if (enc_.empty()) return;
  insert_chunk_row(chunk_, run_, steps_[open_].id, device_, enc_);
  enc_.clear();
}

void StepsStreamWriter::append(std::size_t handle, const core::ImuSample& s,
                               const TableSample& table) {
  if (handle != open_) {
    close_chunk();
    open_ = handle;
  }
  if (!enc_.fits(s)) close_chunk();
  enc_.append(s);
  Step& step = steps_[handle];
  step.stats.add(s);
  step.min_s = std::min(step.min_s, s.receive_time_s);
  step.max_s = std::max(step.max_s, s.receive_time_s);
  if (!table_) return;
  insert_table_row(table_insert_, run_, step.id, s.receive_time_s, table);
}

void StepsStreamWriter::finish(const std::function<nlohmann::json(std::size_t)>& commanded) {
  close_chunk();
  SQLite::Statement span(db_,
                         "UPDATE steps SET started_clock_s = ?, ended_clock_s = ? WHERE id = ?");
  SQLite::Statement update(db_, "UPDATE steps SET commanded = ? WHERE id = ?");
  SQLite::Statement means(db_, kStepMeansInsert);
  for (std::size_t h = 0; h < steps_.size(); ++h) {
    const Step& step = steps_[h];
    span.reset();
    span.bind(1, step.min_s);
    span.bind(2, step.max_s);
    span.bind(3, step.id);
    span.exec();
    if (commanded) {
      update.reset();
      update.bind(1, commanded(h).dump());
      update.bind(2, step.id);
      update.exec();
    }
    insert_means_row(means, run_, step.id, device_, step.stats);
  }
}

}  // namespace calstand::store::detail
