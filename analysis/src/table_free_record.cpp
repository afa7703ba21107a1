// The calibration record of a run without a table.
#include "analysis/table_free_record.hpp"

#include <cmath>

#include "solver/calibration_record.hpp"
#include "solver/run_setup.hpp"
#include "store/run_store.hpp"
#include "store/stamp.hpp"

namespace calstand::analysis {
namespace {

nlohmann::json number_or_null(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json();
}

}  // namespace

nlohmann::json table_free_calibration_record(store::Database& db, const TableFreeFit& fit) {
  const store::RunRecord run = store::RunStore(db).load_run(fit.run);
  const solver::UnitIdentity unit = solver::unit_identity(run, fit.device);
  const TableFreeQuality q = table_free_quality(fit);

  nlohmann::ordered_json r;
  r["format"] = solver::kCalibrationFormat;
  r["device"] = {{"name", fit.device}, {"model", unit.model}, {"serial", unit.serial}};
  r["station"] = run.station_snapshot.value("name", "");
  r["runs"] = {fit.run};
  r["procedure"] = {{"name", run.summary.procedure_name}, {"sha256", run.procedure_sha256}};
  r["method"] = fit.method;
  r["frame"] = solver::kAccelTriadFrameText;
  const nlohmann::json terms = table_free_model_terms(fit.terms);
  r["model"] = terms;
  r["custom_terms"] = nlohmann::json::array();
  r["parameters"] = nlohmann::json::array();
  r["unidentifiable"] = nlohmann::json::array();
  for (const solver::TriadEstimate& e : table_free_parameters(fit)) {
    if (e.status == solver::EstimateStatus::kUndetermined) {
      r["unidentifiable"].push_back(
          {{"name", e.name}, {"reason", "the poses and turns of this run do not determine it"}});
      continue;
    }
    r["parameters"].push_back(
        {{"name", e.name}, {"value", e.value}, {"sigma", e.sigma}, {"unit", e.unit}});
  }
  nlohmann::json quality = {{"chi2_dof", number_or_null(q.chi2_per_dof)},
                            {"dof", q.dof},
                            {"rms_norm_residual_mps2", q.rms_norm_residual_mps2}};
  if (q.rms_turn_residual_deg) quality["rms_turn_residual_deg"] = *q.rms_turn_residual_deg;
  nlohmann::json summary = nlohmann::json::array();
  if (fit.accel) summary.push_back(fit.accel->summary);
  if (fit.gyro) summary.push_back(fit.gyro->summary);
  if (fit.ferraris) summary.push_back(fit.ferraris->summary);
  quality["summary"] = summary;
  r["fit"] = quality;
  // No thermal term is fitted: the reference temperature is the recording's mean, or unknown.
  r["temperature_ref_c"] = number_or_null(0.5 * (fit.min_temperature_c + fit.max_temperature_c));
  r["valid_temperature_c"] = {{"min", number_or_null(fit.min_temperature_c)},
                              {"max", number_or_null(fit.max_temperature_c)}};
  r["created_utc"] = store::utc_now_iso8601();
  r["software"] = solver::kSoftwareVersion;
  return nlohmann::json::parse(r.dump());
}

}  // namespace calstand::analysis
