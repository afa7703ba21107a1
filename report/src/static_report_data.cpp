// What the page of a static record shows, gathered from the database: the run, its site and
// source, and the noise of its record at rest, read once.
#include <fmt/format.h>

#include <algorithm>

#include "analysis/noise_json.hpp"
#include "analysis/run_model.hpp"
#include "analysis/table_free_fit.hpp"
#include "core/error.hpp"
#include "noise/model_figures.hpp"
#include "report/static_report.hpp"
#include "store/run_store.hpp"
#include "store/sample_reader.hpp"

namespace calstand::analysis {
namespace {

// "MCAP, topic /imu/data (sensor_msgs/msg/Imu, cdr); site: default: ..." from the parameters an
// import of a recording stores, or the folder an import/2 came from.
std::string source_of(const nlohmann::json& parameters) {
  if (!parameters.is_object()) return "";
  std::string out = parameters.value("source", "");
  const nlohmann::json recording = parameters.value("recording", nlohmann::json::object());
  if (recording.is_object() && recording.contains("format")) {
    out = fmt::format("{} {}, topic {} ({}, {}); site: {}", recording.value("format", ""), out,
                      recording.value("topic", "-"), recording.value("type", "-"),
                      recording.value("encoding", "-"), recording.value("site", "-"));
  }
  return out;
}

// The longest static pose the table-free detector finds in a run that moves, as a record of
// its own: its samples and a label; none when the detector finds none (or refuses the run).
struct PoseRecord {
  std::vector<core::ImuSample> samples;
  std::string label;
};
std::optional<PoseRecord> longest_pose(store::Database& db, std::int64_t run,
                                       const std::string& device, std::string& why) {
  TableFreeFitRequest request;
  request.device = device;
  try {
    TableFreePoses poses = table_free_poses(db, run, request);
    const auto& intervals = poses.detection.intervals;
    const auto longest = std::max_element(
        intervals.begin(), intervals.end(),
        [](const auto& a, const auto& b) { return a.duration_s() < b.duration_s(); });
    if (longest == intervals.end()) {
      why = "the detector finds no static pose in it";
      return std::nullopt;
    }
    PoseRecord out;
    out.samples.assign(poses.samples.begin() + static_cast<std::ptrdiff_t>(longest->begin),
                       poses.samples.begin() + static_cast<std::ptrdiff_t>(longest->end));
    out.label = fmt::format("the longest of its {} static poses, {:.1f} s to {:.1f} s{}",
                            intervals.size(), longest->start_s, longest->end_s,
                            longest->initial_rest ? " (the initial rest)" : "");
    return out;
  } catch (const core::InputError& e) {
    why = e.what();
    return std::nullopt;
  }
}

}  // namespace

StaticRecordNoise analyse_static_record(std::span<const core::ImuSample> samples, std::int64_t run,
                                        const std::string& device, std::size_t step,
                                        const std::string& step_label,
                                        const std::optional<solver::NoiseIdOptions>& noise_id) {
  solver::RunNoiseOptions options;
  options.device = device;
  options.allan.taus = solver::TauSet::parse("dense");  // as `calstand noise`
  StaticRecordNoise out;
  out.noise = solver::analyse_noise_samples(samples, options);
  out.noise.run = run;
  out.noise.device = device;
  out.noise.step = step;
  out.noise.step_label = step_label;
  out.record_needs = solver::record_length_needs(out.noise);
  try {
    // At the octave averaging times the stability's floor rules are made for, as `calstand
    // analyze stability` reads them: the same samples, analysed again, not read again.
    solver::RunNoiseOptions octave;
    octave.device = device;
    solver::RunNoise at_octaves = solver::analyse_noise_samples(samples, octave);
    at_octaves.run = run;
    at_octaves.device = device;
    at_octaves.step = step;
    at_octaves.step_label = step_label;
    out.stability = stability_of(at_octaves, octave.min_tau_samples);
  } catch (const core::InputError& e) {
    out.stability_note = e.what();
  }
  if (!noise_id) {
    for (const solver::ImuChannel c : solver::kAllChannels) {
      out.models.push_back({c, std::nullopt, "not asked for (--no-noise-model)"});
    }
  } else {
    // The models `calstand noise` gives (the same shortest scale and record length).
    solver::ModelFigureOptions model_options;
    model_options.id = *noise_id;
    for (solver::ChannelModelFigures& m :
         solver::channel_noise_models(samples, out.noise, model_options)) {
      out.models.push_back({m.channel, std::move(m.model), std::move(m.note)});
    }
  }
  return out;
}

StaticReportData gather_static_report(store::Database& db, const ReportRequest& request,
                                      const std::string& no_fit_reason) {
  StaticReportData r;
  r.request = request;
  r.no_fit_reason = no_fit_reason;
  r.device = choose_fit_device(db, request.run, request.device);  // RunNotFound, bad device
  const store::RunRecord record = store::RunStore(db).load_run(request.run);
  r.procedure = record.summary.procedure_name;
  r.run = record.summary;
  r.site = record.station_snapshot.is_object()
               ? record.station_snapshot.value("site", nlohmann::json())
               : nlohmann::json();
  r.source = source_of(record.parameters);
  std::optional<solver::NoiseIdOptions> noise_id;
  if (request.noise_model) {
    noise_id.emplace();
  }
  std::optional<std::size_t> step;
  std::string why_no_step;
  try {
    step = solver::choose_noise_step(db, request.run, std::nullopt);
  } catch (const core::InputError& e) {
    why_no_step = e.what();
  }
  try {
    if (step) {
      std::string label;
      for (const auto& s : record.steps) {
        if (s.index == *step) label = s.label;
      }
      const std::vector<core::ImuSample> samples =
          store::read_samples(db, request.run, *step, r.device);
      if (samples.empty()) {
        r.noise_note = fmt::format("step {} holds no samples of {}", *step, r.device);
        return r;
      }
      r.record_label = fmt::format("step {}{}", *step, label.empty() ? "" : " (" + label + ")");
      r.record = analyse_static_record(samples, request.run, r.device, *step, label, noise_id);
      return r;
    }
    std::string why_no_pose;
    const std::optional<PoseRecord> pose = longest_pose(db, request.run, r.device, why_no_pose);
    if (!pose) {
      r.noise_note = fmt::format("no record at rest: {}; {}", why_no_step, why_no_pose);
      return r;
    }
    r.record_label = pose->label;
    r.record =
        analyse_static_record(pose->samples, request.run, r.device, 0, pose->label, noise_id);
  } catch (const core::InputError& e) {
    r.noise_note = e.what();
    r.record.reset();
  }
  return r;
}

}  // namespace calstand::analysis
