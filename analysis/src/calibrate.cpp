#include "analysis/calibrate.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <limits>

#include "analysis/fit_history.hpp"
#include "analysis/noise_json.hpp"
#include "analysis/run_model.hpp"
#include "core/json_schema.hpp"
#include "core/schemas.hpp"
#include "solver/noise_estimate.hpp"
#include "store/calibrations.hpp"
#include "store/derived_run.hpp"
#include "store/run_store.hpp"

namespace calstand::analysis {

// A record is fitted past its temperature range by this much before `apply` warns [degC]: the
// range is that of the step means, and samples scatter around them.
constexpr double kValidRangeMarginC = 1.0;

CalibrationOutcome calibrate_run(store::Database& db, std::int64_t run, const solver::Model& model,
                                 const std::string& device) {
  const solver::RunData data = load_fit_data(db, run, device);
  std::vector<solver::StepSummary> steps;
  CalibrationOutcome out;
  out.run = run;
  out.procedure = data.setup.procedure_name;
  out.device = data.setup.device;
  out.fit = solver::fit_run(data, model, {}, {}, &steps);
  out.steps = steps.size();
  out.history_id = record_history(db, run, out.device, "calibrate", model, out.fit, "both");
  out.record = solver::make_calibration_record(data.setup, model, out.fit, steps,
                                               calibration_noise_figures(db, run, out.device));
  // Check our own output against the published schema before anything is stored.
  core::validate_or_throw(core::schema("calibration.schema.json"), out.record,
                          "calibration record");
  return out;
}

std::int64_t store_calibration(store::Database& db, const CalibrationOutcome& c) {
  return store::insert_calibration(db, c.run, c.device, c.fit.model, c.record);
}

std::string default_calibration_file(std::int64_t run, const std::string& device) {
  return fmt::format("calibration-run{}-{}.json", run, device);
}

ApplyOutcome apply_calibration(store::Database& db, std::int64_t run, const std::string& device,
                               const solver::Calibration& calibration,
                               const std::string& record_name) {
  solver::RunData data = load_fit_data(db, run, device);
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
  out.steps = derived.steps.size();
  out.run = store::write_derived_run(db, derived);
  out.outside_valid_range = out.min_temperature_c < calibration.valid_min_c - kValidRangeMarginC ||
                            out.max_temperature_c > calibration.valid_max_c + kValidRangeMarginC;
  return out;
}

}  // namespace calstand::analysis
