#pragma once
// The page of `calstand report` (and GET /runs/{id}/report) for a run that holds a record at rest
// and nothing to calibrate from: an imported bag or CSV at rest, an import with a few poses but
// fewer than a table-free calibration needs. What a lab engineer reads off such a record: the
// run and its site, the record's length, the Allan deviation of every channel with its
// intervals, the noise figures (N, B, K) with the estimator of each, the composite noise model
// (`calstand noise-id`), what the record is long enough for, and the stability figures.

#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/imu_sample.hpp"
#include "datasheet/stability.hpp"
#include "noise/composite_noise.hpp"
#include "noise/record_length.hpp"
#include "noise/run_noise.hpp"
#include "report/report_data.hpp"
#include "store/database.hpp"
#include "store/records.hpp"

namespace calstand::analysis {

/// One channel's composite noise model (`calstand noise-id` on the same record), or why none.
struct ChannelNoiseModel {
  solver::ImuChannel channel = solver::ImuChannel::kGx;
  std::optional<solver::NoiseModel> model;
  std::string note;  ///< why there is no model ("" when there is)
};

/// The noise of one record at rest, every figure the static page shows, from one read of it.
struct StaticRecordNoise {
  /// Allan curves at `calstand noise`'s averaging times (dense), noise terms, datasheet figures.
  solver::RunNoise noise;
  std::vector<solver::FigureRecordNeed> record_needs;  ///< solver::record_length_needs()
  /// stability_of() the same samples at octave averaging times (as `calstand analyze
  /// stability`).
  std::optional<StabilityAnalysis> stability;
  std::string stability_note;             ///< why none ("" when there is)
  std::vector<ChannelNoiseModel> models;  ///< gx .. az
};

/// Analyses `samples` (one record at rest of one IMU, in time order): the noise as
/// `calstand noise` gives it, the record-length advice, the stability (records of
/// kMinNoiseRecordS or more) and, when `noise_id` is given, each channel's composite noise model
/// as `calstand noise-id` gives it with those options. `noise.run`, `device`, `step` and
/// `step_label` are set from the arguments. Throws core::InputError as
/// solver::analyse_noise_samples().
StaticRecordNoise analyse_static_record(std::span<const core::ImuSample> samples, std::int64_t run,
                                        const std::string& device, std::size_t step,
                                        const std::string& step_label,
                                        const std::optional<solver::NoiseIdOptions>& noise_id);

/// Section "record-length": what each figure needs against what the record has.
std::string record_length_section(const StaticRecordNoise& s);

/// Section "noise-model": each channel's composite noise model with its 95 % intervals, or why
/// it has none.
std::string noise_model_section(const StaticRecordNoise& s);

struct StaticReportData {
  ReportRequest request;
  std::string procedure;
  std::string device;
  store::RunSummary run;
  /// The run's site as recorded (latitude_deg, height_m, gravity_mps2), or null.
  nlohmann::json site;
  /// Where the run came from, for an imported recording: "MCAP, topic /imu/data
  /// (sensor_msgs/msg/Imu); site: default: ..." or the source folder; "" when unknown.
  std::string source;
  /// Why the page holds no calibration: the table-free fit's refusal ("9 static poses are
  /// needed ..., found 3"), or that the run lies at rest throughout.
  std::string no_fit_reason;
  /// The record analysed: a static step, or the longest static pose the detector found.
  std::string record_label;
  std::optional<StaticRecordNoise> record;
  std::string noise_note;  ///< why there is no noise analysis ("" when there is)
};

/// Gathers the page of `request.run`, whose calibration is refused for `no_fit_reason`. The
/// record: the longest completed static step (solver::choose_noise_step), read once; else, for a
/// run that moves, the longest static pose the table-free detector finds. Throws RunNotFound for
/// an unknown run and core::InputError for an unknown device; a run without any static record
/// gets `noise_note` instead.
StaticReportData gather_static_report(store::Database& db, const ReportRequest& request,
                                      const std::string& no_fit_reason);

/// The whole page (inline CSS and SVG). Draws its plots with gnuplot: throws core::InputError
/// naming gnuplot when it is missing or fails.
std::string render_static_report_html(const StaticReportData& r);

}  // namespace calstand::analysis
