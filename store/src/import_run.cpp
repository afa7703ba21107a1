#include <SQLiteCpp/Statement.h>
#include <SQLiteCpp/Transaction.h>
#include <fmt/format.h>

#include <cmath>
#include <map>
#include <numbers>
#include <tuple>
#include <utility>

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

/// The label and commanded state of one imported step (store/import_export.hpp lists them).
std::pair<std::string, nlohmann::json> describe_step(const detail::ImportMeta& meta,
                                                     const detail::ImportSamples& samples,
                                                     const StepRows& step) {
  if (samples.has_table && samples.has_step) {
    return {fmt::format("step {}", step.value), commanded_state(step)};
  }
  nlohmann::json j;
  if (samples.has_step) j["import_step"] = step.value;
  j["mode"] = "recording";
  if (!samples.has_table) j["orientation"] = "unknown";
  std::string label = samples.has_step ? fmt::format("step {}", step.value) : "recording";
  if (const auto it = meta.sections.find(step.value); it != meta.sections.end()) {
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

/// Writes the run row of an import.
std::int64_t insert_import_run(SQLite::Database& db, const detail::ImportMeta& meta,
                               const std::filesystem::path& dir, double first_s, double last_s) {
  SQLite::Statement st(db,
                       "INSERT INTO runs (procedure_name, procedure_text, procedure_sha256, "
                       "parameters, station_snapshot, status, created_utc, started_clock_s, "
                       "ended_clock_s) VALUES (?, ?, ?, ?, ?, 'imported', ?, ?, ?)");
  st.bind(1, std::string(meta.version == 2 ? detail::kImportFormat2 : detail::kImportFormat));
  st.bind(2, meta.text);
  st.bind(3, sha256_hex(meta.text));
  st.bind(4, nlohmann::json{{"source", std::filesystem::absolute(dir).string()}}.dump());
  st.bind(5, meta.doc.dump());
  st.bind(6, utc_now_iso8601());
  st.bind(7, first_s);
  st.bind(8, last_s);
  st.exec();
  return db.getLastInsertRowid();
}

void write_import_step(detail::StepWriter& writer, std::int64_t run, std::size_t index,
                       const detail::ImportMeta& meta, const detail::ImportSamples& samples_in,
                       const StepRows& s, const std::string& file) {
  detail::StepRow row;
  row.index = index;
  std::tie(row.label, row.commanded) = describe_step(meta, samples_in, s);
  row.origin = fmt::format("{}:{}", file, s.rows.front()->line);
  row.first_s = s.rows.front()->t_s;
  row.last_s = row.first_s;
  std::vector<core::ImuSample> samples;
  std::vector<TableSample> table;
  std::uint32_t sequence = 0;
  for (const auto* r : s.rows) {
    row.first_s = std::min(row.first_s, r->t_s);
    row.last_s = std::max(row.last_s, r->t_s);
    samples.push_back(to_sample(*r, sequence++));
    if (samples_in.has_table) {
      table.push_back({r->outer_deg, r->inner_deg, r->outer_rate_dps, r->inner_rate_dps});
    }
  }
  writer.write(run, row, kImportDevice, samples, table);
}

}  // namespace

ImportResult import_run(Database& db, const std::filesystem::path& dir) {
  // Validate both files completely before the first write.
  const detail::ImportMeta meta = detail::read_import_meta(dir / "meta.json");
  const detail::ImportSamples samples =
      detail::read_import_samples(dir / "samples.csv", meta, dir / "meta.json");
  const std::vector<ImportRow>& rows = samples.rows;
  const std::vector<StepRows> steps = group_by_step(rows);
  double first = rows.front().t_s;
  double last = first;
  for (const auto& r : rows) {
    first = std::min(first, r.t_s);
    last = std::max(last, r.t_s);
  }

  return detail::guarded("import " + dir.string(), [&] {
    SQLite::Transaction tx(db.sql(), SQLite::TransactionBehavior::IMMEDIATE);
    detail::StepWriter writer(db.sql());
    ImportResult result;
    result.run = insert_import_run(db.sql(), meta, dir, first, last);
    const std::string csv = (dir / "samples.csv").string();
    for (std::size_t i = 0; i < steps.size(); ++i)
      write_import_step(writer, result.run, i, meta, samples, steps[i], csv);
    tx.commit();
    result.steps = steps.size();
    result.samples = rows.size();
    return result;
  });
}

}  // namespace calstand::store
