#include "factory/acceptance_validation.hpp"

#include <fmt/format.h>

#include "analysis/calibrate.hpp"
#include "analysis/fit_request.hpp"
#include "analysis/run_model.hpp"
#include "analysis/table_free_fit.hpp"
#include "core/error.hpp"
#include "solver/calibration_record.hpp"
#include "store/units.hpp"

namespace calstand::analysis {

ValidationFit fit_validation_run(store::Database& db, const store::CalibrationRow& calibration,
                                 std::int64_t validation_run, const ValidationSpec& spec) {
  const std::string where = fmt::format("--validation-run {}", validation_run);
  // Every check before anything is written: the corrected run is only made for a run that
  // measured this unit.
  if (validation_run == calibration.run) {
    // Corrected with its own fit, a run leaves nothing by construction: no evidence at all.
    throw core::InputError(where,
                           "is the run the record was fitted on; a validation run "
                           "measures the unit again");
  }
  const std::string device = choose_fit_device(db, validation_run, calibration.imu);
  if (needs_table_free_fit(db, validation_run)) {
    throw core::InputError(where,
                           "was recorded without a table; a validation run must be on a table");
  }
  const std::string serial = store::unit_of_run(db, validation_run, device).serial;
  if (!calibration.serial.empty() && !serial.empty() && serial != calibration.serial) {
    throw core::InputError(
        where, fmt::format("holds unit {} in {}, not {}", serial, device, calibration.serial));
  }
  const std::string name = fmt::format("calibration {}", calibration.id);
  const solver::Calibration record = solver::read_calibration(calibration.record, name);
  const solver::Model model = spec.model.empty() ? record.model : model_from_lists(spec.model, {});

  ValidationFit out;
  out.run = validation_run;
  out.corrected_run = apply_calibration(db, validation_run, device, record, name).run;
  FitRequest request;
  request.model = model;
  request.device = device;
  request.history_command = "accept";
  const FitOutcome fit = fit_request(db, out.corrected_run, request);
  out.model = fit.fit.model;
  // What judge_limits() reads of a record: parameters, unidentifiable, fit.
  nlohmann::json parameters = nlohmann::json::array();
  for (const auto& p : fit.fit.parameters) {
    parameters.push_back(
        {{"name", p.name}, {"value", p.value}, {"sigma", p.sigma}, {"unit", p.unit}});
  }
  nlohmann::json unidentifiable = nlohmann::json::array();
  for (const auto& u : fit.fit.unidentifiable) {
    unidentifiable.push_back({{"name", u.name}, {"reason", u.reason}});
  }
  const nlohmann::json fit_json = solver::fit_to_json(fit.fit);
  out.residual_record = {{"parameters", parameters},
                         {"unidentifiable", unidentifiable},
                         {"fit",
                          {{"chi2_dof", fit_json.value("chi2_dof", nlohmann::json())},
                           {"residual_rms", fit_json.value("residual_rms", nlohmann::json())}}}};
  return out;
}

}  // namespace calstand::analysis
