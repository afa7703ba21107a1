#include <fmt/format.h>

#include "analysis/run_model.hpp"
#include "analysis/step_residuals.hpp"
#include "core/error.hpp"
#include "factory/certificate.hpp"
#include "solver/calibration_record.hpp"
#include "solver/noise_estimate.hpp"
#include "store/calibrations.hpp"
#include "store/run_store.hpp"
#include "store/stamp.hpp"

namespace calstand::analysis {

std::int64_t calibration_of_unit(store::Database& db, std::int64_t run, const std::string& device) {
  std::optional<store::CalibrationRow> newest;
  std::string units;
  for (store::CalibrationRow& row : store::calibrations_of_run(db, run)) {
    if (!device.empty() && row.imu != device) continue;
    if (newest && newest->imu != row.imu && device.empty()) {
      throw core::InputError(fmt::format("run {}", run),
                             fmt::format("has records of several units ({} and {}): give --device",
                                         newest->imu, row.imu));
    }
    newest = std::move(row);  // oldest first: the last one is the newest
  }
  if (!newest) {
    throw core::InputError(fmt::format("run {}", run),
                           fmt::format("has no calibration{}: run calstand calibrate first",
                                       device.empty() ? "" : " of " + device));
  }
  return newest->id;
}

namespace {

std::vector<EquipmentStatus> equipment_of(const nlohmann::json& snapshot,
                                          const std::string& run_ended_utc) {
  std::vector<EquipmentStatus> out;
  const std::string run_date = run_ended_utc.substr(0, 10);  // YYYY-MM-DD
  for (const auto& e : snapshot.value("equipment", nlohmann::json::array())) {
    EquipmentStatus s;
    s.name = e.value("name", "");
    s.id = e.value("id", "");
    s.calibrated = e.value("calibrated", "");
    s.due = e.value("due", "");
    s.certificate = e.value("certificate", "");
    // ISO dates compare as text; an expiry on the run's own day still covers it.
    s.overdue = !run_date.empty() && !s.due.empty() && s.due < run_date;
    out.push_back(std::move(s));
  }
  return out;
}

}  // namespace

CertificateData certificate_data(store::Database& db, std::int64_t calibration) {
  const store::CalibrationRow row = store::load_calibration(db, calibration);
  const store::RunRecord run = store::RunStore(db).load_run(row.run);
  CertificateData d;
  d.calibration = row.id;
  d.run = row.run;
  d.record = row.record;
  d.device = row.imu;
  const nlohmann::json device = row.record.value("device", nlohmann::json::object());
  d.model = device.value("model", "");
  d.serial = device.value("serial", "");
  d.station = row.record.value("station", "");
  const nlohmann::json& snapshot = run.station_snapshot;
  d.site = snapshot.value("site", nlohmann::json::object());
  d.procedure = run.summary.procedure_name;
  d.procedure_sha256 = run.procedure_sha256;
  d.run_started_utc = run.summary.started_utc;
  d.run_ended_utc = run.summary.ended_utc;
  d.equipment = equipment_of(snapshot, d.run_ended_utc);
  d.acceptance = store::latest_acceptance(db, row.id);
  d.number = fmt::format("{}-{:06}", d.station.empty() ? "calstand" : d.station, row.id);
  d.issued_utc = store::utc_now_iso8601();
  // The residual plot needs the fit on the table's steps; a record without a table has none.
  const std::string method = row.record.value("method", "table");
  if (method == "table") {
    if (const auto stored = store::load_calibration_residuals(db, row.id)) {
      d.residuals = step_residuals_from_json(*stored, fmt::format("calibration {}", row.id));
    } else {
      // A record stored before its residuals were (schema version 7): the same model on the
      // same data gives the same residuals, at the cost of reading the run again.
      const solver::Calibration cal = solver::read_calibration(row.record, d.number);
      d.residuals = solver::fit_run(load_fit_data(db, row.run, row.imu), cal.model).steps;
      d.residuals_refitted = true;
    }
  }
  return d;
}

}  // namespace calstand::analysis
