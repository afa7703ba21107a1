#include "step_writer.hpp"

#include <cmath>
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

}  // namespace calstand::store::detail
