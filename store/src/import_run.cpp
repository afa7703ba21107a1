#include <SQLiteCpp/Statement.h>
#include <SQLiteCpp/Transaction.h>
#include <fmt/format.h>

#include <cmath>
#include <map>
#include <numbers>

#include "import_format.hpp"
#include "sql_util.hpp"
#include "step_stats.hpp"
#include "store/hash.hpp"
#include "store/import_export.hpp"
#include "store/sample_codec.hpp"
#include "store/stamp.hpp"

namespace calstand::store {
namespace {

using detail::ImportRow;

// A step is a rate step when a mean axis rate reaches this; the error-model format has no mode
// column, and encoder rates at rest read zero up to noise far below it [deg/s].
constexpr double kRateStepThresholdDps = 1e-3;

/// The rows of one `step` value, in file order.
struct StepRows {
  std::int64_t value = 0;
  std::vector<const ImportRow*> rows;
};

std::vector<StepRows> group_by_step(const std::vector<ImportRow>& rows) {
  std::vector<StepRows> steps;
  std::map<std::int64_t, std::size_t> index;
  for (const auto& r : rows) {
    auto [it, fresh] = index.emplace(r.step, steps.size());
    if (fresh) steps.push_back({r.step, {}});
    steps[it->second].rows.push_back(&r);
  }
  return steps;
}

// Mean of angles that may wrap (e.g. 179.99 and -179.99) [deg].
double circular_mean_deg(const std::vector<const ImportRow*>& rows, double ImportRow::*angle) {
  double s = 0.0;
  double c = 0.0;
  for (const auto* r : rows) {
    const double a = r->*angle * std::numbers::pi / 180.0;
    s += std::sin(a);
    c += std::cos(a);
  }
  return std::atan2(s, c) * 180.0 / std::numbers::pi;
}

nlohmann::json commanded_state(const StepRows& step) {
  double outer_rate = 0.0;
  double inner_rate = 0.0;
  for (const auto* r : step.rows) {
    outer_rate += r->outer_rate_dps;
    inner_rate += r->inner_rate_dps;
  }
  outer_rate /= static_cast<double>(step.rows.size());
  inner_rate /= static_cast<double>(step.rows.size());
  nlohmann::json j;
  j["import_step"] = step.value;
  if (std::abs(outer_rate) >= kRateStepThresholdDps ||
      std::abs(inner_rate) >= kRateStepThresholdDps) {
    j["mode"] = "rate";
    j["outer_rate_dps"] = outer_rate;
    j["inner_rate_dps"] = inner_rate;
    j["outer_start_deg"] = step.rows.front()->outer_deg;
    j["inner_start_deg"] = step.rows.front()->inner_deg;
  } else {
    j["mode"] = "position";
    j["outer_deg"] = circular_mean_deg(step.rows, &ImportRow::outer_deg);
    j["inner_deg"] = circular_mean_deg(step.rows, &ImportRow::inner_deg);
  }
  return j;
}

core::ImuSample to_sample(const ImportRow& r, std::uint32_t sequence) {
  core::ImuSample s;
  s.receive_time_s = r.t_s;
  s.device_time_s = r.t_s;
  s.sequence = sequence;
  s.gyro_dps = r.gyro_dps;
  s.accel_mps2 = r.accel_mps2;
  s.temperature_c = r.temp_c;
  return s;
}

/// Prepared inserts of one import transaction.
class ImportWriter {
 public:
  explicit ImportWriter(SQLite::Database& db)
      : db_(db),
        step_(db, "INSERT INTO steps (run_id, idx, kind, label, commanded, origin, status, "
                  "attempts, good_attempt, started_clock_s, ended_clock_s) VALUES (?, ?, "
                  "'capture', ?, ?, ?, 'completed', 1, 1, ?, ?)"),
        chunk_(db, "INSERT INTO sample_chunks (run_id, step_id, attempt, device, "
                   "first_receive_time_s, last_receive_time_s, count, encoding, data) VALUES "
                   "(?, ?, 1, ?, ?, ?, ?, ?, ?)"),
        table_(db, "INSERT INTO table_telemetry (run_id, step_id, time_s, outer_deg, inner_deg, "
                   "outer_rate_dps, inner_rate_dps) VALUES (?, ?, ?, ?, ?, ?, ?)") {}

  std::int64_t run(const detail::ImportMeta& meta, const std::filesystem::path& dir,
                   double first_s, double last_s) {
    SQLite::Statement st(db_,
                         "INSERT INTO runs (procedure_name, procedure_text, procedure_sha256, "
                         "parameters, station_snapshot, status, created_utc, started_clock_s, "
                         "ended_clock_s) VALUES (?, ?, ?, ?, ?, 'imported', ?, ?, ?)");
    st.bind(1, std::string(detail::kImportFormat));
    st.bind(2, meta.text);
    st.bind(3, sha256_hex(meta.text));
    st.bind(4, nlohmann::json{{"source", std::filesystem::absolute(dir).string()}}.dump());
    st.bind(5, meta.doc.dump());
    st.bind(6, utc_now_iso8601());
    st.bind(7, first_s);
    st.bind(8, last_s);
    st.exec();
    return db_.getLastInsertRowid();
  }

  void step(std::int64_t run, std::size_t index, const StepRows& s, const std::string& file) {
    double first = s.rows.front()->t_s;
    double last = first;
    for (const auto* r : s.rows) {
      first = std::min(first, r->t_s);
      last = std::max(last, r->t_s);
    }
    step_.reset();
    step_.bind(1, run);
    step_.bind(2, static_cast<std::int64_t>(index));
    step_.bind(3, fmt::format("step {}", s.value));
    step_.bind(4, commanded_state(s).dump());
    step_.bind(5, fmt::format("{}:{}", file, s.rows.front()->line));
    step_.bind(6, first);
    step_.bind(7, last);
    step_.exec();
    const std::int64_t step_id = db_.getLastInsertRowid();

    ChunkEncoder enc(SampleEncoding::kExact);
    StepStats stats;
    std::uint32_t sequence = 0;
    for (const auto* r : s.rows) {
      const core::ImuSample sample = to_sample(*r, sequence++);
      if (!enc.fits(sample)) {
        insert_chunk(run, step_id, enc);
        enc.clear();
      }
      enc.append(sample);
      stats.add(sample);
      table_.reset();
      table_.bind(1, run);
      table_.bind(2, step_id);
      table_.bind(3, r->t_s);
      table_.bind(4, r->outer_deg);
      table_.bind(5, r->inner_deg);
      table_.bind(6, r->outer_rate_dps);
      table_.bind(7, r->inner_rate_dps);
      table_.exec();
    }
    insert_chunk(run, step_id, enc);
    insert_means(run, step_id, stats);
  }

 private:
  void insert_chunk(std::int64_t run, std::int64_t step_id, const ChunkEncoder& enc) {
    chunk_.reset();
    chunk_.bind(1, run);
    chunk_.bind(2, step_id);
    chunk_.bind(3, std::string(kImportDevice));
    chunk_.bind(4, enc.first_receive_time_s());
    chunk_.bind(5, enc.last_receive_time_s());
    chunk_.bind(6, static_cast<std::int64_t>(enc.count()));
    chunk_.bind(7, static_cast<int>(enc.encoding()));
    const auto blob = enc.bytes();
    chunk_.bindNoCopy(8, blob.data(), static_cast<int>(blob.size()));
    chunk_.exec();
  }

  void insert_means(std::int64_t run, std::int64_t step_id, const StepStats& s) {
    SQLite::Statement st(
        db_,
        "INSERT INTO step_means (run_id, step_id, attempt, device, count, first_receive_time_s, "
        "last_receive_time_s, gx_dps, gy_dps, gz_dps, ax_mps2, ay_mps2, az_mps2, temperature_c, "
        "std_gx_dps, std_gy_dps, std_gz_dps, std_ax_mps2, std_ay_mps2, std_az_mps2, "
        "std_temperature_c) VALUES (?, ?, 1, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, ?, "
        "?)");
    st.bind(1, run);
    st.bind(2, step_id);
    st.bind(3, std::string(kImportDevice));
    st.bind(4, static_cast<std::int64_t>(s.count()));
    st.bind(5, s.first_time_s());
    st.bind(6, s.last_time_s());
    for (int c = 0; c < StepStats::kChannels; ++c) {
      st.bind(7 + c, s.mean(c));
      const double sd = s.stddev(c);
      if (std::isfinite(sd)) {
        st.bind(14 + c, sd);
      } else {
        st.bind(14 + c);
      }
    }
    st.exec();
  }

  SQLite::Database& db_;
  SQLite::Statement step_;
  SQLite::Statement chunk_;
  SQLite::Statement table_;
};

}  // namespace

ImportResult import_run(Database& db, const std::filesystem::path& dir) {
  // Validate both files completely before the first write.
  const detail::ImportMeta meta = detail::read_import_meta(dir / "meta.json");
  const std::vector<ImportRow> rows = detail::read_import_samples(dir / "samples.csv");
  const std::vector<StepRows> steps = group_by_step(rows);
  double first = rows.front().t_s;
  double last = first;
  for (const auto& r : rows) {
    first = std::min(first, r.t_s);
    last = std::max(last, r.t_s);
  }

  return detail::guarded("import " + dir.string(), [&] {
    SQLite::Transaction tx(db.sql(), SQLite::TransactionBehavior::IMMEDIATE);
    ImportWriter writer(db.sql());
    ImportResult result;
    result.run = writer.run(meta, dir, first, last);
    const std::string csv = (dir / "samples.csv").string();
    for (std::size_t i = 0; i < steps.size(); ++i) writer.step(result.run, i, steps[i], csv);
    tx.commit();
    result.steps = steps.size();
    result.samples = rows.size();
    return result;
  });
}

}  // namespace calstand::store
