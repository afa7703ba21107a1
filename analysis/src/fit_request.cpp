#include "analysis/fit_request.hpp"

#include "analysis/fit_history.hpp"
#include "analysis/noise_run.hpp"
#include "analysis/run_model.hpp"
#include "solver/noise_estimate.hpp"

namespace calstand::analysis {
namespace {

/// How the request's noise model is had for `data`: white alone, the wander of a static run,
/// or estimated from the run.
solver::NoiseEstimateOptions noise_options_of(store::Database& db, const FitRequest& request,
                                              const solver::RunData& data) {
  solver::NoiseEstimateOptions options;
  options.estimate_wander = !request.white_noise;
  if (request.noise_run && !request.white_noise) {
    options.known_wander = noise_run_wander(db, *request.noise_run, request.device, data);
  }
  return options;
}

}  // namespace

FitOutcome fit_request(store::Database& db, std::int64_t run, const FitRequest& request) {
  solver::FitOptions fit_options;
  fit_options.rows = parse_sensor_rows(request.sensor);
  const solver::RunData data = load_fit_data(db, run, request.device);
  const solver::NoiseEstimateOptions noise_options = noise_options_of(db, request, data);
  FitOutcome out;
  out.run = run;
  out.procedure = data.setup.procedure_name;
  out.device = data.setup.device;
  out.fit = solver::fit_run(data, request.model, fit_options, noise_options, &out.steps);
  if (!request.history_command.empty()) {
    out.history_id = record_history(db, run, out.device, request.history_command, request.model,
                                    out.fit, request.sensor);
  }
  out.groups = solver::group_quality(out.fit, out.steps);
  out.worst = solver::worst_steps(out.fit);
  return out;
}

nlohmann::json to_json(const FitOutcome& outcome) {
  nlohmann::json j = solver::fit_to_json(outcome.fit);
  solver::add_groups_json(j, outcome.groups, outcome.worst);
  return j;
}

DiagnoseOutcome diagnose_request(store::Database& db, std::int64_t run, const FitRequest& request) {
  solver::FitOptions options;
  options.rows = parse_sensor_rows(request.sensor);
  const solver::RunData data = load_fit_data(db, run, request.device);
  DiagnoseOutcome out;
  out.run = run;
  out.procedure = data.setup.procedure_name;
  out.device = data.setup.device;
  solver::DiagnoseOptions diagnose_options;
  if (request.noise_run) {
    diagnose_options.noise.known_wander =
        noise_run_wander(db, *request.noise_run, request.device, data);
  }
  out.diagnosis = solver::diagnose(data, request.model, options, diagnose_options);
  if (!request.history_command.empty()) {
    out.history_id = record_history(db, run, out.device, request.history_command, request.model,
                                    out.diagnosis.fit, request.sensor);
  }
  return out;
}

nlohmann::json to_json(const DiagnoseOutcome& outcome) {
  return solver::diagnosis_to_json(outcome.diagnosis);
}

PlateauFitOutcome plateau_fit_request(store::Database& db, std::int64_t run,
                                      const FitRequest& request, int order) {
  solver::ThermalFitOptions options;
  options.fit.rows = parse_sensor_rows(request.sensor);
  const solver::RunData data = load_fit_data(db, run, request.device);
  options.temperature_ref_c = data.setup.temperature_ref_c;
  const solver::NoiseEstimateOptions noise_options = noise_options_of(db, request, data);
  PlateauFitOutcome out;
  out.run = run;
  out.procedure = data.setup.procedure_name;
  out.device = data.setup.device;
  // Each plateau's fit is weighed with the run's own noise model, like the whole-run fit.
  out.result = solver::fit_per_plateau(
      solver::summarize_steps(data, request.model), request.model, order,
      solver::estimate_run_noise(data, request.model, options.fit.rows, noise_options), options);
  return out;
}

}  // namespace calstand::analysis
