#include <SQLiteCpp/Statement.h>
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <stdexcept>

#include "core/error.hpp"
#include "import_format.hpp"
#include "sql_util.hpp"
#include "store/import_export.hpp"
#include "store/run_store.hpp"
#include "store/sample_reader.hpp"

namespace calstand::store {
namespace {

/// Table columns of one exported row.
struct TableRow {
  double time_s = 0.0;
  double outer_deg = 0.0;
  double inner_deg = 0.0;
  double outer_rate_dps = 0.0;
  double inner_rate_dps = 0.0;
};

std::vector<TableRow> read_table(SQLite::Database& db, const char* where, std::int64_t id) {
  SQLite::Statement q(db, fmt::format("SELECT time_s, outer_deg, inner_deg, outer_rate_dps, "
                                      "inner_rate_dps FROM table_telemetry WHERE {} = ? "
                                      "ORDER BY {}",
                                      where, std::string_view(where) == "step_id" ? "id" : "time_s, id"));
  q.bind(1, id);
  std::vector<TableRow> out;
  while (q.executeStep()) {
    out.push_back({q.getColumn(0).getDouble(), q.getColumn(1).getDouble(),
                   q.getColumn(2).getDouble(), q.getColumn(3).getDouble(),
                   q.getColumn(4).getDouble()});
  }
  return out;
}

double wrap180(double deg) {
  double w = std::fmod(deg + 180.0, 360.0);
  if (w < 0.0) w += 360.0;
  return w - 180.0;
}

// Table state at `t_s` from time-ordered telemetry: linear between neighbours (angles along the
// shorter arc), the nearest row outside the recorded span.
TableRow interpolate(const std::vector<TableRow>& rows, double t_s) {
  const auto after = std::lower_bound(rows.begin(), rows.end(), t_s,
                                      [](const TableRow& r, double t) { return r.time_s < t; });
  if (after == rows.begin()) return *after;
  if (after == rows.end()) return rows.back();
  const TableRow& a = *std::prev(after);
  const TableRow& b = *after;
  const double span = b.time_s - a.time_s;
  const double f = span > 0.0 ? (t_s - a.time_s) / span : 0.0;
  TableRow r;
  r.time_s = t_s;
  r.outer_deg = wrap180(a.outer_deg + f * wrap180(b.outer_deg - a.outer_deg));
  r.inner_deg = wrap180(a.inner_deg + f * wrap180(b.inner_deg - a.inner_deg));
  r.outer_rate_dps = a.outer_rate_dps + f * (b.outer_rate_dps - a.outer_rate_dps);
  r.inner_rate_dps = a.inner_rate_dps + f * (b.inner_rate_dps - a.inner_rate_dps);
  return r;
}

TableRow commanded_table(const nlohmann::json& c) {
  TableRow r;
  r.outer_deg = c.value("outer_deg", c.value("outer_start_deg", 0.0));
  r.inner_deg = c.value("inner_deg", c.value("inner_start_deg", 0.0));
  r.outer_rate_dps = c.value("outer_rate_dps", 0.0);
  r.inner_rate_dps = c.value("inner_rate_dps", 0.0);
  return r;
}

std::string choose_device(Database& db, std::int64_t run, const ExportOptions& options) {
  const std::vector<std::string> devices = sample_devices(db, run);
  const std::string where = "run " + std::to_string(run);
  if (!options.device.empty()) {
    if (std::find(devices.begin(), devices.end(), options.device) == devices.end()) {
      throw core::InputError(where, "has no samples of device '" + options.device + "'");
    }
    return options.device;
  }
  if (devices.empty()) throw core::InputError(where, "has no samples to export");
  if (devices.size() > 1) {
    throw core::InputError(where, fmt::format("has samples of several IMUs ({}): choose one",
                                              fmt::join(devices, ", ")));
  }
  return devices.front();
}

// Samples per second of the longest step, rounded to 6 significant digits (a recorded run's
// station snapshot does not state the IMU's rate).
double estimated_rate_hz(Database& db, std::int64_t run, const std::string& device) {
  SQLite::Statement q(db.sql(),
                      "SELECT count, last_receive_time_s - first_receive_time_s FROM step_means "
                      "m JOIN steps s ON s.id = m.step_id AND m.attempt = s.good_attempt WHERE "
                      "s.run_id = ? AND m.device = ? ORDER BY count DESC LIMIT 1");
  q.bind(1, run);
  q.bind(2, device);
  if (q.executeStep() && q.getColumn(1).getDouble() > 0.0) {
    const double hz = static_cast<double>(q.getColumn(0).getInt64() - 1) / q.getColumn(1).getDouble();
    return std::stod(fmt::format("{:.6g}", hz));
  }
  return 1.0;
}

nlohmann::json meta_from_station(Database& db, std::int64_t run, const nlohmann::json& station,
                                 const std::string& device) {
  nlohmann::ordered_json meta;
  meta["format"] = detail::kImportFormat;
  const auto& site = station.at("site");
  meta["site"]["latitude_deg"] = site.at("latitude_deg");
  meta["site"]["height_m"] = site.at("height_m");
  if (site.contains("gravity_mps2")) meta["site"]["gravity_mps2"] = site["gravity_mps2"];
  meta["table"]["outer_axis"] = station.at("table").at("outer_axis");
  meta["table"]["inner_axis"] = station.at("table").at("inner_axis");
  for (const auto& imu : station.value("imus", nlohmann::json::array())) {
    if (imu.value("name", "") == device && imu.contains("mount_rpy_deg")) {
      meta["mount_rpy_deg"] = imu["mount_rpy_deg"];
    }
  }
  meta["sample_rate_hz"] = estimated_rate_hz(db, run, device);
  meta["units"] = {{"gyro", "deg/s"},      {"accel", "m/s^2"},      {"angle", "deg"},
                   {"rate", "deg/s"},      {"temperature", "degC"}, {"time", "s"}};
  return nlohmann::json::parse(meta.dump());
}

void write_file(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(text.data(), static_cast<std::streamsize>(text.size()));
  out.close();
  if (!out) throw std::runtime_error(path.string() + ": cannot write the file");
}

}  // namespace

void export_run(Database& db, std::int64_t run, const std::filesystem::path& out_dir,
                const ExportOptions& options) {
  RunStore runs(db);
  const RunRecord record = runs.load_run(run);
  const std::string device = choose_device(db, run, options);
  const nlohmann::json meta =
      record.station_snapshot.value("format", "") == detail::kImportFormat
          ? record.station_snapshot
          : detail::guarded("read run for export",
                            [&] { return meta_from_station(db, run, record.station_snapshot, device); });

  fmt::memory_buffer csv;
  fmt::format_to(std::back_inserter(csv), "{}\n", detail::kImportCsvHeader);
  const std::vector<TableRow> run_table =
      detail::guarded("read table telemetry", [&] { return read_table(db.sql(), "run_id", run); });
  for (const StepRecord& step : record.steps) {
    if (step.status != StepStatus::kCompleted) continue;
    const std::vector<core::ImuSample> samples = read_samples(db, run, step.index, device);
    if (samples.empty()) continue;
    const std::vector<TableRow> step_table = detail::guarded(
        "read table telemetry", [&] { return read_table(db.sql(), "step_id", step.id); });
    // Imported runs hold one table row per sample, in sample order.
    const bool per_sample = step_table.size() == samples.size();
    const auto& c = step.commanded;
    const std::int64_t step_value = c.contains("import_step") && c["import_step"].is_number_integer()
                                        ? c["import_step"].get<std::int64_t>()
                                        : static_cast<std::int64_t>(step.index);
    for (std::size_t i = 0; i < samples.size(); ++i) {
      const core::ImuSample& s = samples[i];
      const TableRow t = per_sample           ? step_table[i]
                         : !run_table.empty() ? interpolate(run_table, s.receive_time_s)
                                              : commanded_table(c);
      fmt::format_to(std::back_inserter(csv),
                     "{:.17g},{},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},"
                     "{:.17g},{:.17g},{:.17g}\n",
                     s.receive_time_s, step_value, t.outer_deg, t.inner_deg, t.outer_rate_dps,
                     t.inner_rate_dps, s.temperature_c, s.gyro_dps.x(), s.gyro_dps.y(),
                     s.gyro_dps.z(), s.accel_mps2.x(), s.accel_mps2.y(), s.accel_mps2.z());
    }
  }

  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (ec) throw std::runtime_error(out_dir.string() + ": cannot create the folder: " + ec.message());
  write_file(out_dir / "meta.json", meta.dump(2) + "\n");
  write_file(out_dir / "samples.csv", fmt::to_string(csv));
}

}  // namespace calstand::store
