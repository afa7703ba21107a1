#include "store/sample_reader.hpp"

#include <SQLiteCpp/Statement.h>

#include <atomic>
#include <limits>

#include "core/error.hpp"
#include "sql_util.hpp"

namespace calstand::store {

using detail::guarded;

namespace {
// Relaxed: a tally for tests and benchmarks, ordered with nothing else.
std::atomic<std::uint64_t> decoded_samples{0};
}  // namespace

std::uint64_t samples_decoded() { return decoded_samples.load(std::memory_order_relaxed); }

std::optional<int> data_attempt(Database& db, std::int64_t run, std::size_t index) {
  struct Row {
    bool found = false;
    std::optional<int> attempt;
  };
  const Row row = guarded("find data attempt", [&] {
    SQLite::Statement q(db.sql(),
                        "SELECT s.good_attempt, (SELECT MAX(attempt) FROM sample_chunks c "
                        "WHERE c.step_id = s.id) FROM steps s WHERE s.run_id = ? AND s.idx = ?");
    q.bind(1, run);
    q.bind(2, static_cast<std::int64_t>(index));
    Row r;
    if (!q.executeStep()) return r;
    r.found = true;
    if (!q.getColumn(0).isNull()) {
      r.attempt = q.getColumn(0).getInt();
    } else if (!q.getColumn(1).isNull()) {
      r.attempt = q.getColumn(1).getInt();
    }
    return r;
  });
  if (!row.found) {
    throw core::InputError("run " + std::to_string(run) + " step " + std::to_string(index),
                           "no such step in " + db.path());
  }
  return row.attempt;
}

void for_each_chunk(
    Database& db, std::int64_t run, std::size_t index, const std::string& device,
    const std::function<void(const ChunkInfo&, std::span<const core::ImuSample>)>& fn) {
  const auto attempt = data_attempt(db, run, index);
  if (!attempt) return;
  std::vector<core::ImuSample> samples;
  guarded("read sample chunks", [&] {
    SQLite::Statement q(db.sql(),
                        "SELECT c.id, c.step_id, c.attempt, c.device, c.first_receive_time_s, "
                        "c.last_receive_time_s, c.count, c.encoding, c.data FROM sample_chunks c "
                        "JOIN steps s ON s.id = c.step_id WHERE s.run_id = ? AND s.idx = ? AND "
                        "c.attempt = ? AND c.device = ? ORDER BY c.id");
    q.bind(1, run);
    q.bind(2, static_cast<std::int64_t>(index));
    q.bind(3, *attempt);
    q.bind(4, device);
    while (q.executeStep()) {
      ChunkInfo info;
      info.id = q.getColumn(0).getInt64();
      info.step_id = q.getColumn(1).getInt64();
      info.attempt = q.getColumn(2).getInt();
      info.device = q.getColumn(3).getString();
      info.first_receive_time_s = q.getColumn(4).getDouble();
      info.last_receive_time_s = q.getColumn(5).getDouble();
      info.count = static_cast<std::uint32_t>(q.getColumn(6).getInt64());
      info.encoding = static_cast<SampleEncoding>(q.getColumn(7).getInt());
      const SQLite::Column data = q.getColumn(8);
      const auto* bytes = static_cast<const std::uint8_t*>(data.getBlob());
      samples.clear();
      decode_chunk(std::span<const std::uint8_t>(bytes, static_cast<std::size_t>(data.getBytes())),
                   samples);
      decoded_samples.fetch_add(samples.size(), std::memory_order_relaxed);
      fn(info, samples);
    }
  });
}

std::vector<core::ImuSample> read_samples(Database& db, std::int64_t run, std::size_t index,
                                          const std::string& device) {
  std::vector<core::ImuSample> out;
  for_each_chunk(db, run, index, device, [&](const ChunkInfo&, std::span<const core::ImuSample> s) {
    out.insert(out.end(), s.begin(), s.end());
  });
  return out;
}

std::vector<std::string> sample_devices(Database& db, std::int64_t run) {
  return guarded("list sample devices", [&] {
    SQLite::Statement q(db.sql(),
                        "SELECT DISTINCT device FROM sample_chunks WHERE run_id = ? ORDER BY 1");
    q.bind(1, run);
    std::vector<std::string> out;
    while (q.executeStep()) out.push_back(q.getColumn(0).getString());
    return out;
  });
}

std::vector<StepMean> read_step_means(Database& db, std::int64_t run) {
  return guarded("read step means", [&] {
    SQLite::Statement q(
        db.sql(),
        "SELECT s.idx, m.attempt, m.device, m.count, m.first_receive_time_s, "
        "m.last_receive_time_s, m.gx_dps, m.gy_dps, m.gz_dps, m.ax_mps2, m.ay_mps2, m.az_mps2, "
        "m.temperature_c, m.std_gx_dps, m.std_gy_dps, m.std_gz_dps, m.std_ax_mps2, "
        "m.std_ay_mps2, m.std_az_mps2, m.std_temperature_c FROM step_means m JOIN steps s ON "
        "s.id = m.step_id AND m.attempt = s.good_attempt WHERE s.run_id = ? AND "
        "s.status = 'completed' ORDER BY s.idx, m.device");
    q.bind(1, run);
    std::vector<StepMean> out;
    while (q.executeStep()) {
      StepMean m;
      m.step_index = static_cast<std::size_t>(q.getColumn(0).getInt64());
      m.attempt = q.getColumn(1).getInt();
      m.device = q.getColumn(2).getString();
      m.count = q.getColumn(3).getInt64();
      m.first_receive_time_s = q.getColumn(4).getDouble();
      m.last_receive_time_s = q.getColumn(5).getDouble();
      // NULL (SQLite's NaN: a step without temperature, a spread of one sample) reads NaN.
      const auto real = [&q](int column) {
        const SQLite::Column c = q.getColumn(column);
        return c.isNull() ? std::numeric_limits<double>::quiet_NaN() : c.getDouble();
      };
      for (int i = 0; i < 3; ++i) {
        m.gyro_dps[i] = real(6 + i);
        m.accel_mps2[i] = real(9 + i);
        m.gyro_std_dps[i] = real(13 + i);
        m.accel_std_mps2[i] = real(16 + i);
      }
      m.temperature_c = real(12);
      m.temperature_std_c = real(19);
      out.push_back(std::move(m));
    }
    return out;
  });
}

}  // namespace calstand::store
