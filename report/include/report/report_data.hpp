#pragma once
// What `calstand report` shows, gathered from the database and the solver; no HTML, no plots.

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "analysis/run_model.hpp"
#include "datasheet/run_analyses.hpp"
#include "noise/run_noise.hpp"
#include "solver/diagnose.hpp"
#include "solver/step_summary.hpp"
#include "store/database.hpp"
#include "store/fit_history.hpp"
#include "store/records.hpp"

namespace calstand::analysis {

struct StaticRecordNoise;  // static_report.hpp

/// The request, as the command line gives it.
struct ReportRequest {
  std::string db;  ///< the database's name as the page shows it (a file name)
  std::int64_t run = 0;
  std::string model = kDefaultModel;  ///< comma-separated terms (Model::parse)
  std::vector<std::string> customs;
  std::string device;  ///< "" = the run's only IMU
  std::string sensor = "both";
  /// The page of a record at rest identifies each channel's composite noise model (GMWM:
  /// seconds a channel on a 12 min record at 100 Hz, minutes on hours at 400 Hz); false skips it.
  bool noise_model = true;
  /// The wander from this static run of the same unit (analysis/noise_run.hpp) instead of one
  /// estimated from the run's own step means; a run with a table only.
  std::optional<std::int64_t> noise_run;
};

/// One condition kind of the steps, used to colour them in the plots.
struct StepGrouping {
  std::string kind;                  ///< "plateau", "orientation", ...
  std::vector<std::string> of_step;  ///< the value of each step (by position in the fit)
  std::vector<std::string> values;   ///< distinct values, in order of first appearance
  /// Position of `of_step[i]` in `values`.
  std::size_t value_index(std::size_t step) const;
};

/// The warm-up capture binned as the analysis bins it, for its plot against the fit.
struct WarmupSeries {
  std::vector<double> t_s;  ///< mean time of each bin from the capture's first sample [s]
  /// Per channel (gx .. az), each bin's mean less the channel's settled value, in datasheet
  /// units (deg/h, ug).
  std::array<std::vector<double>, 6> deviation;
  /// Per channel, the fit less the settled value at each bin: A exp(-t / tau), plus the
  /// temperature's share k (T - T_end) where the channel has that term; empty for a channel
  /// without a resolved transient (its tau means nothing).
  std::array<std::vector<double>, 6> fitted;
};

struct ReportData {
  ReportRequest request;
  std::string procedure;
  std::string device;
  store::RunSummary run;  ///< state, steps done, times
  /// Completed steps of each kind, in order of first appearance ("capture", 12).
  std::vector<std::pair<std::string, std::size_t>> step_kinds;
  /// Why the page shows no error model ("" when it does). Only when it does are `history`,
  /// `diagnosis` and `grouping` set; `steps` is set either way.
  std::string no_fit_reason;
  std::vector<store::FitRecord> history;    ///< oldest first, this report's fit last
  std::vector<std::string> history_labels;  ///< per fit: the model, or the terms it added
  solver::Diagnosis diagnosis;
  std::vector<solver::StepSummary> steps;  ///< summaries of the diagnosed model, in fit order
  StepGrouping grouping;
  double longest_static_s = 0.0;          ///< longest static step [s]
  std::optional<solver::RunNoise> noise;  ///< Allan curves and noise fit, static runs only
  /// For a static run without an error model (a static-allan run): the record-length advice and
  /// the composite noise models of the same record, as the page of a record at rest has them
  /// (static_report.hpp); `noise` is its noise.
  std::shared_ptr<const StaticRecordNoise> static_record;
  std::string noise_note;                     ///< why there is no Allan section, or ""
  DatasheetAnalyses datasheet;                ///< the datasheet analyses that apply, and why not
  std::optional<WarmupSeries> warmup_series;  ///< with datasheet.warmup

  bool fitted() const { return no_fit_reason.empty(); }
};

/// Fits and diagnoses the model, records the fit in the run's history (command "report"),
/// reads the history and, for a static run (a static step of kMinNoiseRecordS or more, or the
/// static-allan procedure), analyses the noise of its longest static step; makes the datasheet
/// analyses that apply (run_analyses.hpp). A run whose steps are all one condition (one pose at
/// rest at one temperature: a repeatability, warm-up or static-allan run), or whose steps the
/// solver cannot fit the model to, gets no fit: `no_fit_reason` says why, and nothing is added
/// to its history. Throws RunNotFound, NothingToFit or core::InputError for a bad request (a
/// model that does not parse, an unknown device).
ReportData gather_report(store::Database& db, const ReportRequest& request);

/// Why `steps` (summaries in step order) determine no error model: they are all one condition
/// (the same pose, at rest, at one temperature plateau), so their means only repeat one
/// measurement; "" when they differ.
std::string single_condition_reason(const std::vector<solver::StepSummary>& steps);

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
