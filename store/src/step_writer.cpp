#include "step_writer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "step_stats.hpp"
#include "store/sample_codec.hpp"

namespace calstand::store::detail {

StepWriter::StepWriter(SQLite::Database& db)
    : db_(db),
      step_(db,
            "INSERT INTO steps (run_id, idx, kind, label, commanded, origin, status, "
            "attempts, good_attempt, started_clock_s, ended_clock_s) VALUES (?, ?, ?, ?, ?, "
            "?, 'completed', 1, 1, ?, ?)"),
      chunk_(db,
             "INSERT INTO sample_chunks (run_id, step_id, attempt, device, "
             "first_receive_time_s, last_receive_time_s, count, encoding, data) VALUES "
             "(?, ?, 1, ?, ?, ?, ?, ?, ?)"),
      table_(db,
             "INSERT INTO table_telemetry (run_id, step_id, time_s, outer_deg, inner_deg, "
             "outer_rate_dps, inner_rate_dps) VALUES (?, ?, ?, ?, ?, ?, ?)"),
      means_(db,
             "INSERT INTO step_means (run_id, step_id, attempt, device, count, "
             "first_receive_time_s, last_receive_time_s, gx_dps, gy_dps, gz_dps, ax_mps2, "
             "ay_mps2, az_mps2, temperature_c, std_gx_dps, std_gy_dps, std_gz_dps, "
             "std_ax_mps2, std_ay_mps2, std_az_mps2, std_temperature_c) VALUES (?, ?, 1, ?, "
             "?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)") {}

std::int64_t StepWriter::write(std::int64_t run, const StepRow& step, const std::string& device,
                               std::span<const core::ImuSample> samples,
                               std::span<const TableSample> table) {
  if (!table.empty() && table.size() != samples.size()) {
    throw std::logic_error("StepWriter::write: one table state per sample, or none");
  }
  step_.reset();
  step_.bind(1, run);
  step_.bind(2, static_cast<std::int64_t>(step.index));
  step_.bind(3, step.kind);
  step_.bind(4, step.label);
  step_.bind(5, step.commanded.dump());
  step_.bind(6, step.origin);
  step_.bind(7, step.first_s);
  step_.bind(8, step.last_s);
  step_.exec();
  const std::int64_t step_id = db_.getLastInsertRowid();

  const auto insert_chunk = [&](const ChunkEncoder& enc) {
    chunk_.reset();
    chunk_.bind(1, run);
    chunk_.bind(2, step_id);
    chunk_.bind(3, device);
    chunk_.bind(4, enc.first_receive_time_s());
    chunk_.bind(5, enc.last_receive_time_s());
    chunk_.bind(6, static_cast<std::int64_t>(enc.count()));
    chunk_.bind(7, static_cast<int>(enc.encoding()));
    const auto blob = enc.bytes();
    chunk_.bindNoCopy(8, blob.data(), static_cast<int>(blob.size()));
    chunk_.exec();
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
    table_.reset();
    table_.bind(1, run);
    table_.bind(2, step_id);
    table_.bind(3, samples[i].receive_time_s);
    table_.bind(4, table[i].outer_deg);
    table_.bind(5, table[i].inner_deg);
    table_.bind(6, table[i].outer_rate_dps);
    table_.bind(7, table[i].inner_rate_dps);
    table_.exec();
  }
  if (enc.count() > 0) insert_chunk(enc);

  means_.reset();
  means_.bind(1, run);
  means_.bind(2, step_id);
  means_.bind(3, device);
  means_.bind(4, static_cast<std::int64_t>(stats.count()));
  means_.bind(5, stats.first_time_s());
  means_.bind(6, stats.last_time_s());
  for (int c = 0; c < StepStats::kChannels; ++c) {
    means_.bind(7 + c, stats.mean(c));
    const double sd = stats.stddev(c);
    if (std::isfinite(sd)) {
      means_.bind(14 + c, sd);
    } else {
      means_.bind(14 + c);
    }
  }
  means_.exec();
  return step_id;
}

namespace {

constexpr const char* kStepMeansInsert =
    "INSERT INTO step_means (run_id, step_id, attempt, device, count, "
    "first_receive_time_s, last_receive_time_s, gx_dps, gy_dps, gz_dps, ax_mps2, "
    "ay_mps2, az_mps2, temperature_c, std_gx_dps, std_gy_dps, std_gz_dps, "
    "std_ax_mps2, std_ay_mps2, std_az_mps2, std_temperature_c) VALUES (?, ?, 1, ?, "
    "?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?)";

}  // namespace

StepStreamWriter::StepStreamWriter(SQLite::Database& db, std::int64_t run, const StepRow& step,
                                   std::string device)
    : db_(db),
      run_(run),
      device_(std::move(device)),
      chunk_(db,
             "INSERT INTO sample_chunks (run_id, step_id, attempt, device, "
             "first_receive_time_s, last_receive_time_s, count, encoding, data) VALUES "
             "(?, ?, 1, ?, ?, ?, ?, ?, ?)"),
      enc_(SampleEncoding::kExact) {
  SQLite::Statement st(db_,
                       "INSERT INTO steps (run_id, idx, kind, label, commanded, origin, status, "
                       "attempts, good_attempt, started_clock_s, ended_clock_s) VALUES (?, ?, ?, "
                       "?, ?, ?, 'completed', 1, 1, ?, ?)");
  st.bind(1, run);
  st.bind(2, static_cast<std::int64_t>(step.index));
  st.bind(3, step.kind);
  st.bind(4, step.label);
  st.bind(5, step.commanded.dump());
  st.bind(6, step.origin);
  st.bind(7, step.first_s);
  st.bind(8, step.last_s);
  st.exec();
  step_id_ = db_.getLastInsertRowid();
}

void StepStreamWriter::insert_chunk() {
  chunk_.reset();
  chunk_.bind(1, run_);
  chunk_.bind(2, step_id_);
  chunk_.bind(3, device_);
  chunk_.bind(4, enc_.first_receive_time_s());
  chunk_.bind(5, enc_.last_receive_time_s());
  chunk_.bind(6, static_cast<std::int64_t>(enc_.count()));
  chunk_.bind(7, static_cast<int>(enc_.encoding()));
  const auto blob = enc_.bytes();
  chunk_.bindNoCopy(8, blob.data(), static_cast<int>(blob.size()));
  chunk_.exec();
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
  means.bind(1, run_);
  means.bind(2, step_id_);
  means.bind(3, device_);
  means.bind(4, static_cast<std::int64_t>(stats_.count()));
  means.bind(5, stats_.first_time_s());
  means.bind(6, stats_.last_time_s());
  for (int c = 0; c < StepStats::kChannels; ++c) {
    means.bind(7 + c, stats_.mean(c));
    const double sd = stats_.stddev(c);
    if (std::isfinite(sd)) {
      means.bind(14 + c, sd);
    } else {
      means.bind(14 + c);
    }
  }
  means.exec();
  return step_id_;
}

StepsStreamWriter::StepsStreamWriter(SQLite::Database& db, std::int64_t run, std::string device,
                                     bool table)
    : db_(db),
      run_(run),
      device_(std::move(device)),
      table_(table),
      step_insert_(db,
                   "INSERT INTO steps (run_id, idx, kind, label, commanded, origin, status, "
                   "attempts, good_attempt, started_clock_s, ended_clock_s) VALUES (?, ?, ?, ?, "
                   "?, ?, 'completed', 1, 1, ?, ?)"),
      chunk_(db,
             "INSERT INTO sample_chunks (run_id, step_id, attempt, device, "
             "first_receive_time_s, last_receive_time_s, count, encoding, data) VALUES "
             "(?, ?, 1, ?, ?, ?, ?, ?, ?)"),
      table_insert_(db,
                    "INSERT INTO table_telemetry (run_id, step_id, time_s, outer_deg, inner_deg, "
                    "outer_rate_dps, inner_rate_dps) VALUES (?, ?, ?, ?, ?, ?, ?)"),
      enc_(SampleEncoding::kExact) {}

std::size_t StepsStreamWriter::begin(const StepRow& step) {
  step_insert_.reset();
  step_insert_.bind(1, run_);
  step_insert_.bind(2, static_cast<std::int64_t>(step.index));
  step_insert_.bind(3, step.kind);
  step_insert_.bind(4, step.label);
  step_insert_.bind(5, step.commanded.dump());
  step_insert_.bind(6, step.origin);
  step_insert_.bind(7, step.first_s);
  step_insert_.bind(8, step.last_s);
  step_insert_.exec();
  steps_.push_back({});
  steps_.back().id = db_.getLastInsertRowid();
  return steps_.size() - 1;
}

void StepsStreamWriter::close_chunk() {
  if (enc_.empty()) return;
  chunk_.reset();
  chunk_.bind(1, run_);
  chunk_.bind(2, steps_[open_].id);
  chunk_.bind(3, device_);
  chunk_.bind(4, enc_.first_receive_time_s());
  chunk_.bind(5, enc_.last_receive_time_s());
  chunk_.bind(6, static_cast<std::int64_t>(enc_.count()));
  chunk_.bind(7, static_cast<int>(enc_.encoding()));
  const auto blob = enc_.bytes();
  chunk_.bindNoCopy(8, blob.data(), static_cast<int>(blob.size()));
  chunk_.exec();
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
  table_insert_.reset();
  table_insert_.bind(1, run_);
  table_insert_.bind(2, step.id);
  table_insert_.bind(3, s.receive_time_s);
  table_insert_.bind(4, table.outer_deg);
  table_insert_.bind(5, table.inner_deg);
  table_insert_.bind(6, table.outer_rate_dps);
  table_insert_.bind(7, table.inner_rate_dps);
  table_insert_.exec();
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
    means.reset();
    means.bind(1, run_);
    means.bind(2, step.id);
    means.bind(3, device_);
    means.bind(4, static_cast<std::int64_t>(step.stats.count()));
    means.bind(5, step.stats.first_time_s());
    means.bind(6, step.stats.last_time_s());
    for (int c = 0; c < StepStats::kChannels; ++c) {
      means.bind(7 + c, step.stats.mean(c));
      const double sd = step.stats.stddev(c);
      if (std::isfinite(sd)) {
        means.bind(14 + c, sd);
      } else {
        means.bind(14 + c);
      }
    }
    means.exec();
  }
}

}  // namespace calstand::store::detail
