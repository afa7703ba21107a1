#pragma once
// What `calstand report` shows, gathered from the database and the solver; no HTML, no plots.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "analysis/run_model.hpp"
#include "solver/diagnose.hpp"
#include "solver/run_noise.hpp"
#include "solver/step_summary.hpp"
#include "store/database.hpp"
#include "store/fit_history.hpp"

namespace calstand::analysis {

/// The request, as the command line gives it.
struct ReportRequest {
  std::string db;  ///< the database's name as the page shows it (a file name)
  std::int64_t run = 0;
  std::string model = kDefaultModel;  ///< comma-separated terms (Model::parse)
  std::vector<std::string> customs;
  std::string device;  ///< "" = the run's only IMU
  std::string sensor = "both";
};

/// One condition kind of the steps, used to colour them in the plots.
struct StepGrouping {
  std::string kind;                  ///< "plateau", "orientation", ...
  std::vector<std::string> of_step;  ///< the value of each step (by position in the fit)
  std::vector<std::string> values;   ///< distinct values, in order of first appearance
  /// Position of `of_step[i]` in `values`.
  std::size_t value_index(std::size_t step) const;
};

struct ReportData {
  ReportRequest request;
  std::string procedure;
  std::string device;
  std::vector<store::FitRecord> history;    ///< oldest first, this report's fit last
  std::vector<std::string> history_labels;  ///< per fit: the model, or the terms it added
  solver::Diagnosis diagnosis;
  std::vector<solver::StepSummary> steps;  ///< summaries of the diagnosed model, in fit order
  StepGrouping grouping;
  double longest_static_s = 0.0;          ///< longest static step [s]
  std::optional<solver::RunNoise> noise;  ///< Allan curves and noise fit, static runs only
  std::string noise_note;                 ///< why there is no Allan section, or ""
};

/// Fits and diagnoses the model, records the fit in the run's history (command "report"),
/// reads the history and, for a static run (a static step of kMinNoiseRecordS or more, or the
/// static-allan procedure), analyses the noise of its longest static step. Throws RunNotFound,
/// NothingToFit or core::InputError for a bad request (as `calstand diagnose`).
ReportData gather_report(store::Database& db, const ReportRequest& request);

/// Short labels of the fits of a history: the first fit's model, then what each fit added
/// ("+gyro_temp_bias") or removed relative to the one before.
std::vector<std::string> history_labels(const std::vector<store::FitRecord>& fits);

/// Colours steps by the condition kind of the worst group of the diagnosis, or else by the
/// first kind (plateau, orientation, rate, direction, axis, time) that tells steps apart.
StepGrouping choose_grouping(const solver::Diagnosis& d,
                             const std::vector<solver::StepSummary>& steps);

/// The step means of a diagnosis signal ("temperature_rate", "rate_x^2", "abs(force_z)"),
/// or nothing for a name it does not know.
std::optional<std::vector<double>> signal_series(const std::vector<solver::StepSummary>& steps,
                                                 const std::string& signal);

}  // namespace calstand::analysis
