#include "analysis/calibrate.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "analysis/fit_history.hpp"
#include "analysis/noise_json.hpp"
#include "analysis/noise_run.hpp"
#include "analysis/run_model.hpp"
#include "analysis/step_residuals.hpp"
#include "analysis/table_free_record.hpp"
#include "core/error.hpp"
#include "core/json_schema.hpp"
#include "core/schemas.hpp"
#include "solver/noise_estimate.hpp"
#include "store/calibrations.hpp"
#include "store/derived_run.hpp"
#include "store/run_store.hpp"
#include "store/sample_reader.hpp"
#include "store/step_data.hpp"

namespace calstand::analysis {

// A record is fitted past its temperature range by this much before `apply` warns [degC]: the
// range is that of the step means, and samples scatter around them.
constexpr double kValidRangeMarginC = 1.0;

namespace {

void check_record(const nlohmann::json& record) {
  // Check our own output against the published schema before anything is stored.
  core::validate_or_throw(core::schema("calibration.schema.json"), record, "calibration record");
}

CalibrationOutcome calibrate_table_free_run(store::Database& db, std::int64_t run,
                                            const solver::Model& model, const std::string& device,
                                            const TableFreeFitRequest& poses) {
  TableFreeFitRequest request = table_free_request(model, poses);
  request.device = device;
  request.history_command = "calibrate";
  CalibrationOutcome out;
  out.run = run;
  out.procedure = store::RunStore(db).load_run(run).summary.procedure_name;
  out.table_free = table_free_fit(db, run, request);
  out.device = out.table_free->device;
  out.steps = out.table_free->poses ? out.table_free->poses->detection.intervals.size() : 0;
  out.history_id = out.table_free->history_id.value_or(0);
  out.record = table_free_calibration_record(db, *out.table_free);
  check_record(out.record);
  return out;
}

}  // namespace

CalibrationOutcome calibrate_run(store::Database& db, std::int64_t run, const solver::Model& model,
                                 const std::string& device, const TableFreeFitRequest& poses,
                                 std::optional<std::int64_t> noise_run) {
  if (needs_table_free_fit(db, run)) {
    if (noise_run) throw_noise_run_on_table_free(run);
    return calibrate_table_free_run(db, run, model, device, poses);
  }
  const solver::RunData data = load_fit_data(db, run, device);
  solver::NoiseEstimateOptions noise;
  if (noise_run) noise.known_wander = noise_run_wander(db, *noise_run, device, data);
  std::vector<solver::StepSummary> steps;
  CalibrationOutcome out;
  out.run = run;
  out.procedure = data.setup.procedure_name;
  out.device = data.setup.device;
  out.fit = solver::fit_run(data, model, {}, noise, &steps);
  out.steps = steps.size();
  out.history_id = record_history(db, run, out.device, "calibrate", model, out.fit, "both");
  out.record = solver::make_calibration_record(data.setup, model, out.fit, steps,
                                               calibration_noise_figures(db, run, out.device));
  check_record(out.record);
  return out;
}

std::vector<std::string> units_to_calibrate(store::Database& db, std::int64_t run,
                                            const std::string& device) {
  if (!device.empty()) return {store::choose_device(db, run, device)};
  std::vector<std::string> devices = store::sample_devices(db, run);
  if (devices.empty()) {
    throw core::InputError("run " + std::to_string(run), "has no IMU samples to calibrate");
  }
  std::sort(devices.begin(), devices.end());
  return devices;
}

std::int64_t store_calibration(store::Database& db, const CalibrationOutcome& c) {
  const std::string model = c.table_free ? table_free_model_text(c.table_free->terms) : c.fit.model;
  // A table fit's step residuals go with the record: its certificate draws them.
  return store::insert_calibration(db, c.run, c.device, model, c.record,
                                   c.table_free ? nlohmann::json() : step_residuals_json(c.fit));
}

std::string default_calibration_file(std::int64_t run, const std::string& device) {
  return fmt::format("calibration-run{}-{}.json", run, device);
}

namespace {

// A run without a table: its steps as stored (table state NaN), and a setup with nothing but
// the device, after checking that the record needs nothing such a run lacks. The sensor terms
// correct from the measured rate and force alone; a term that needs the table's motion (the
// lever arm) or a temperature the recording does not have would turn every sample into NaN.
solver::RunData table_free_apply_data(store::Database& db, std::int64_t run,
                                      const std::string& device,
                                      const solver::Calibration& calibration,
                                      const std::string& record_name) {
  solver::RunData data;
  data.setup.run = run;
  data.setup.device = choose_fit_device(db, run, device);
  data.setup.temperature_ref_c = calibration.temperature_ref_c;
  data.steps = store::read_step_data(db, run, data.setup.device);
  bool temperature = true;
  for (const auto& step : data.steps) {
    for (const auto& s : step.samples) temperature = temperature && std::isfinite(s.temperature_c);
  }
  for (const auto& p : calibration.model.parameters()) {
    const bool thermal = p.term.find("_temp_") != std::string::npos;
    if (p.term == "accel_lever_arm" || (thermal && !temperature)) {
      throw core::InputError(
          record_name,
          fmt::format("the record's {} needs {}, which run {} (recorded without a table) does "
                      "not have",
                      p.term, thermal ? "the IMU temperature" : "the table's motion", run));
    }
  }
  return data;
}

}  // namespace

ApplyOutcome apply_calibration(store::Database& db, std::int64_t run, const std::string& device,
                               const solver::Calibration& calibration,
                               const std::string& record_name) {
  const bool table_free = needs_table_free_fit(db, run);
  solver::RunData data = table_free
                             ? table_free_apply_data(db, run, device, calibration, record_name)
                             : load_fit_data(db, run, device);
  const solver::Corrector corrector(calibration, data.setup);
  const double run_start_s = data.steps.front().samples.front().receive_time_s;
  ApplyOutcome out;
  out.source_run = run;
  out.min_temperature_c = std::numeric_limits<double>::infinity();
  out.max_temperature_c = -std::numeric_limits<double>::infinity();
  for (auto& step : data.steps) {
    for (const auto& s : step.samples) {
      out.min_temperature_c = std::min(out.min_temperature_c, s.temperature_c);
      out.max_temperature_c = std::max(out.max_temperature_c, s.temperature_c);
    }
    corrector.correct(step, run_start_s);
  }
  store::DerivedRun derived;
  derived.source_run = run;
  derived.procedure_name = "corrected " + store::RunStore(db).load_run(run).summary.procedure_name;
  derived.status = "corrected";
  derived.parameters = {{"calibration", record_name}};
  derived.device = data.setup.device;
  derived.steps = std::move(data.steps);
  // No table state to store for a run whose orientation is not known (the copy stays one).
  if (table_free) {
    for (auto& step : derived.steps) step.table.clear();
  }
  out.steps = derived.steps.size();
  out.run = store::write_derived_run(db, derived);
  out.outside_valid_range = out.min_temperature_c < calibration.valid_min_c - kValidRangeMarginC ||
                            out.max_temperature_c > calibration.valid_max_c + kValidRangeMarginC;
  return out;
}

}  // namespace calstand::analysis
