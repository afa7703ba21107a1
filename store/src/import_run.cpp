#include <SQLiteCpp/Statement.h>
#include <SQLiteCpp/Transaction.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <tuple>
#include <utility>

#include "batch_prefetch.hpp"
#include "import_format.hpp"
#include "sql_util.hpp"
#include "step_writer.hpp"
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

/// What the commanded state of one step value needs, accumulated over its rows in file order
/// (the same sums, in the same order, as over the whole step at once).
struct StepSums {
  std::int64_t value = 0;
  std::size_t first_line = 0;
  double first_outer_deg = 0.0;
  double first_inner_deg = 0.0;
  std::uint64_t count = 0;
  std::uint32_t next_sequence = 0;
  double outer_rate = 0.0;
  double inner_rate = 0.0;
  double outer_sin = 0.0;
  double outer_cos = 0.0;
  double inner_sin = 0.0;
  double inner_cos = 0.0;

  void add(const ImportRow& r) {
    ++count;
    outer_rate += r.outer_rate_dps;
    inner_rate += r.inner_rate_dps;
    const double o = r.outer_deg * std::numbers::pi / 180.0;
    const double i = r.inner_deg * std::numbers::pi / 180.0;
    outer_sin += std::sin(o);
    outer_cos += std::cos(o);
    inner_sin += std::sin(i);
    inner_cos += std::cos(i);
  }
};

// Mean of angles that may wrap (e.g. 179.99 and -179.99) [deg].
double circular_mean_deg(double sin_sum, double cos_sum) {
  return std::atan2(sin_sum, cos_sum) * 180.0 / std::numbers::pi;
}

nlohmann::json commanded_state(const StepSums& step) {
  const double outer_rate = step.outer_rate / static_cast<double>(step.count);
  const double inner_rate = step.inner_rate / static_cast<double>(step.count);
  nlohmann::json j;
  j["import_step"] = step.value;
  if (std::abs(outer_rate) >= kRateStepThresholdDps ||
      std::abs(inner_rate) >= kRateStepThresholdDps) {
    j["mode"] = "rate";
    j["outer_rate_dps"] = outer_rate;
    j["inner_rate_dps"] = inner_rate;
    j["outer_start_deg"] = step.first_outer_deg;
    j["inner_start_deg"] = step.first_inner_deg;
  } else {
    j["mode"] = "position";
    j["outer_deg"] = circular_mean_deg(step.outer_sin, step.outer_cos);
    j["inner_deg"] = circular_mean_deg(step.inner_sin, step.inner_cos);
  }
  return j;
}

/// The label and commanded state of one imported step (store/import_export.hpp lists them);
/// with a table and step column the commanded state needs the whole step (finish()).
std::pair<std::string, nlohmann::json> describe_step(const detail::ImportMeta& meta,
                                                     const detail::ImportSampleReader& samples,
                                                     std::int64_t value) {
  if (samples.has_table() && samples.has_step()) {
    return {fmt::format("step {}", value), nlohmann::json::object()};
  }
  nlohmann::json j;
  if (samples.has_step()) j["import_step"] = value;
  j["mode"] = "recording";
  if (!samples.has_table()) j["orientation"] = "unknown";
  std::string label = samples.has_step() ? fmt::format("step {}", value) : "recording";
  if (const auto it = meta.sections.find(value); it != meta.sections.end()) {
    j["mode"] = it->second.kind;
    j["section"] = it->second.to_json();
    label = it->second.label;
  }
  return {label, j};
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

/// Writes the run row of an import (its time span is set once the samples have been read).
std::int64_t insert_import_run(SQLite::Database& db, const detail::ImportMeta& meta,
                               const std::filesystem::path& dir) {
  SQLite::Statement st(db,
                       "INSERT INTO runs (procedure_name, procedure_text, procedure_sha256, "
                       "parameters, station_snapshot, status, created_utc) VALUES (?, ?, ?, ?, "
                       "?, 'imported', ?)");
  st.bind(1, std::string(meta.version == 2 ? detail::kImportFormat2 : detail::kImportFormat));
  st.bind(2, meta.text);
  st.bind(3, sha256_hex(meta.text));
  st.bind(4, nlohmann::json{{"source", std::filesystem::absolute(dir).string()}}.dump());
  st.bind(5, meta.doc.dump());
  st.bind(6, utc_now_iso8601());
  st.exec();
  return db.getLastInsertRowid();
}

}  // namespace

ImportResult import_run(Database& db, const std::filesystem::path& dir,
                        const ImportRunOptions& options) {
  // meta.json and the header of samples.csv are checked before the first write; the rows as
  // they are read, inside the one transaction, so that a refusal anywhere leaves nothing.
  const detail::ImportMeta meta = detail::read_import_meta(dir / "meta.json");
  detail::ImportSampleReader reader(dir / "samples.csv", meta, dir / "meta.json");
  const std::string csv = reader.file();
  const bool table_steps = reader.has_table() && reader.has_step();

  return detail::guarded("import " + dir.string(), [&] {
    SQLite::Transaction tx(db.sql(), SQLite::TransactionBehavior::IMMEDIATE);
    ImportResult result;
    result.run = insert_import_run(db.sql(), meta, dir);
    detail::StepsStreamWriter writer(db.sql(), result.run, kImportDevice, reader.has_table());
    std::vector<StepSums> steps;                  // by handle, in order of first appearance
    std::map<std::int64_t, std::size_t> handles;  // step value -> handle
    std::size_t last = 0;                         // the handle of the previous row
    double first = std::numeric_limits<double>::infinity();
    double end = -std::numeric_limits<double>::infinity();
    std::vector<ImportRow> batch;
    double fraction = 0.0;
    // The reader is not touched here again before the prefetch has ended.
    detail::BatchPrefetch<detail::ImportSampleReader, ImportRow> prefetch(reader, options.batch);
    while (prefetch.next(batch, fraction)) {
      for (const ImportRow& r : batch) {
        if (steps.empty() || steps[last].value != r.step) {
          auto [it, fresh] = handles.emplace(r.step, steps.size());
          if (fresh) {
            detail::StepRow row;
            row.index = steps.size();
            std::tie(row.label, row.commanded) = describe_step(meta, reader, r.step);
            row.origin = fmt::format("{}:{}", csv, r.line);
            row.first_s = row.last_s = r.t_s;
            writer.begin(row);
            StepSums& sums = steps.emplace_back();
            sums.value = r.step;
            sums.first_line = r.line;
            sums.first_outer_deg = r.outer_deg;
            sums.first_inner_deg = r.inner_deg;
          }
          last = it->second;
        }
        StepSums& sums = steps[last];
        sums.add(r);
        writer.append(last, to_sample(r, sums.next_sequence++),
                      {r.outer_deg, r.inner_deg, r.outer_rate_dps, r.inner_rate_dps});
        first = std::min(first, r.t_s);
        end = std::max(end, r.t_s);
      }
      result.samples += batch.size();
      if (options.progress) options.progress(fraction, result.samples);
    }
    if (table_steps) {
      writer.finish([&](std::size_t h) { return commanded_state(steps[h]); });
    } else {
      writer.finish();
    }
    SQLite::Statement span(db.sql(),
                           "UPDATE runs SET started_clock_s = ?, ended_clock_s = ? WHERE id = ?");
    span.bind(1, first);
    span.bind(2, end);
    span.bind(3, result.run);
    span.exec();
    tx.commit();
    result.steps = steps.size();
    return result;
  });
}

}  // namespace calstand::store
