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
#include "store/step_data.hpp"

namespace calstand::store {
namespace {

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
    const double hz =
        static_cast<double>(q.getColumn(0).getInt64() - 1) / q.getColumn(1).getDouble();
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
  meta["units"] = {{"gyro", "deg/s"}, {"accel", "m/s^2"},      {"angle", "deg"},
                   {"rate", "deg/s"}, {"temperature", "degC"}, {"time", "s"}};
  return nlohmann::json::parse(meta.dump());
}

// The meta.json of a /2 run's export: the imported one, its samples now in the store's units
// (counts were converted with the nominal on import, so the nominal goes).
nlohmann::json meta_2_for_export(const nlohmann::json& imported) {
  nlohmann::json meta = imported;
  meta["units"]["gyro"] = "deg/s";
  meta["units"]["accel"] = "m/s^2";
  meta.erase("nominal");
  return meta;
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
  const std::string device = choose_device(db, run, options.device);
  const std::string format = record.station_snapshot.value("format", "");
  const bool v2 = format == detail::kImportFormat2;
  const nlohmann::json meta =
      v2 ? meta_2_for_export(record.station_snapshot)
      : format == detail::kImportFormat
          ? record.station_snapshot
          : detail::guarded("read run for export", [&] {
              return meta_from_station(db, run, record.station_snapshot, device);
            });
  // A /2 folder has the columns its import had: step when the steps came from one, the table
  // columns with a table, temp_c with a temperature unit.
  bool has_step = true;
  if (v2) {
    has_step = false;
    for (const StepRecord& s : record.steps)
      has_step = has_step || s.commanded.contains("import_step");
  }
  const bool has_table = !v2 || meta.contains("table");
  const bool has_temperature = !v2 || meta["units"].contains("temperature");

  std::error_code ec;
  std::filesystem::create_directories(out_dir, ec);
  if (ec)
    throw std::runtime_error(out_dir.string() + ": cannot create the folder: " + ec.message());

  // One step at a time: a long run's CSV (a gigabyte for an hour of two 1 kHz IMUs) never
  // sits in memory whole. Written under a temporary name and renamed when whole, meta.json
  // last: a failure leaves no folder that looks complete.
  const std::filesystem::path csv_path = out_dir / "samples.csv";
  const std::filesystem::path part_path = out_dir / "samples.csv.part";
  try {
    std::ofstream out(part_path, std::ios::binary | std::ios::trunc);
    if (v2) {
      out << "t" << (has_step ? ",step" : "")
          << (has_table ? ",outer_deg,inner_deg,outer_rate_dps,inner_rate_dps" : "")
          << (has_temperature ? ",temp_c" : "") << ",gx,gy,gz,ax,ay,az\n";
    } else {
      out << detail::kImportCsvHeader << "\n";
    }
    fmt::memory_buffer csv;
    for_each_step_data(db, run, device, [&](const StepData& data) {
      const auto& c = data.step.commanded;
      const std::int64_t step_value =
          c.contains("import_step") && c["import_step"].is_number_integer()
              ? c["import_step"].get<std::int64_t>()
              : static_cast<std::int64_t>(data.step.index);
      csv.clear();
      for (std::size_t i = 0; i < data.samples.size(); ++i) {
        const core::ImuSample& s = data.samples[i];
        const TableSample& t = data.table[i];
        if (v2) {
          auto it = std::back_inserter(csv);
          fmt::format_to(it, "{:.17g}", s.receive_time_s);
          if (has_step) fmt::format_to(it, ",{}", step_value);
          if (has_table) {
            fmt::format_to(it, ",{:.17g},{:.17g},{:.17g},{:.17g}", t.outer_deg, t.inner_deg,
                           t.outer_rate_dps, t.inner_rate_dps);
          }
          if (has_temperature) fmt::format_to(it, ",{:.17g}", s.temperature_c);
          fmt::format_to(it, ",{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g}\n", s.gyro_dps.x(),
                         s.gyro_dps.y(), s.gyro_dps.z(), s.accel_mps2.x(), s.accel_mps2.y(),
                         s.accel_mps2.z());
          continue;
        }
        fmt::format_to(std::back_inserter(csv),
                       "{:.17g},{},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},{:.17g},"
                       "{:.17g},{:.17g},{:.17g}\n",
                       s.receive_time_s, step_value, t.outer_deg, t.inner_deg, t.outer_rate_dps,
                       t.inner_rate_dps, s.temperature_c, s.gyro_dps.x(), s.gyro_dps.y(),
                       s.gyro_dps.z(), s.accel_mps2.x(), s.accel_mps2.y(), s.accel_mps2.z());
      }
      out.write(csv.data(), static_cast<std::streamsize>(csv.size()));
    });
    out.close();
    if (!out) throw std::runtime_error(csv_path.string() + ": cannot write the file");
    std::filesystem::rename(part_path, csv_path);
  } catch (...) {
    std::filesystem::remove(part_path, ec);
    throw;
  }
  write_file(out_dir / "meta.json", meta.dump(2) + "\n");
}

}  // namespace calstand::store
