// Printing a table-free calibration and its static poses.
#include "table_free_printer.hpp"

#include <fmt/format.h>

#include <fstream>
#include <sstream>

#include "core/error.hpp"
#include "core/site.hpp"

namespace calstand::cli {
namespace {

void print_estimates(const std::vector<solver::TriadEstimate>& estimates) {
  fmt::print("{:<30} {:>14} {:>12}  {:<6} {}\n", "parameter", "value", "sigma", "unit", "");
  for (const auto& e : estimates) {
    const bool estimated = e.status == solver::EstimateStatus::kEstimated;
    fmt::print("{:<30} {:>14.6g} {:>12}  {:<6} {}\n", e.name, e.value,
               estimated ? fmt::format("{:.3g}", e.sigma) : "-", e.unit,
               estimated ? "" : solver::estimate_status_name(e.status));
  }
}

void print_list(const char* what, const std::vector<std::string>& names) {
  if (names.empty()) return;
  std::string joined;
  for (const auto& n : names) joined += (joined.empty() ? "" : ", ") + n;
  fmt::print("{}: {}\n", what, joined);
}

}  // namespace

void add_static_pose_options(CLI::App* cmd, StaticPoseOptions& opt) {
  auto& d = opt.request.detector;
  cmd->add_option("--static-intervals", opt.intervals_file,
                  "Runs without a table: the static poses as a CSV of start_s,end_s per line "
                  "(the first is the initial rest) instead of the detector's");
  cmd->add_option("--static-window", d.window_s, "Detector: variance window [s]")
      ->capture_default_str();
  cmd->add_option("--static-min", d.min_duration_s, "Detector: shortest static interval [s]")
      ->capture_default_str();
  cmd->add_option("--rest", d.initial_rest_s,
                  "Detector: length of the initial rest [s] (0: found from the data)")
      ->capture_default_str();
  cmd->add_option("--threshold-multiple", d.threshold_multiple,
                  "Detector: threshold as this multiple of the rest's variance (default: the "
                  "rest's own quantile)")
      ->each([&d](const std::string&) { d.rule = solver::ThresholdRule::kMultiple; });
  cmd->add_option("--false-alarm", d.false_alarm,
                  "Detector: chance per window that rest noise crosses the threshold")
      ->capture_default_str();
}

analysis::TableFreeFitRequest static_pose_request(const StaticPoseOptions& opt,
                                                  const std::string& device) {
  analysis::TableFreeFitRequest request = opt.request;
  request.device = device;
  if (opt.intervals_file.empty()) return request;
  std::ifstream in(opt.intervals_file);
  if (!in) throw core::InputError(opt.intervals_file, "cannot be read");
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    if (line.empty() || line[0] == '#') continue;
    double from = 0.0, to = 0.0;
    char comma = 0;
    std::istringstream fields(line);
    if (!(fields >> from >> comma >> to) || comma != ',' || !(fields >> std::ws).eof()) {
      throw core::InputError(fmt::format("{}:{}", opt.intervals_file, number),
                             fmt::format("\"{}\" is not start_s,end_s", line));
    }
    request.intervals_s.emplace_back(from, to);
  }
  if (request.intervals_s.empty()) throw core::InputError(opt.intervals_file, "holds no interval");
  return request;
}

void print_static_poses(const analysis::TableFreePoses& poses) {
  const auto& d = poses.detection;
  if (poses.given) {
    fmt::print("static poses: {} intervals given by the operator\n", d.intervals.size());
  } else {
    fmt::print("static poses (detector): {} intervals of {:g} s or more; window {:g} s; {}\n",
               d.intervals.size(), d.min_duration_s, d.window_s, d.rule_text);
    if (d.has_initial_rest) {
      fmt::print(
          "  initial rest {:.2f} to {:.2f} s ({}), threshold {:.3g} (m/s^2)^2 = {:.3g} x "
          "its level{}\n",
          d.rest_start_s, d.rest_end_s, d.rest_from_data ? "found from the data" : "given",
          d.threshold_mps2_sq, d.threshold_multiple,
          d.rejected_short > 0 ? fmt::format("; {} shorter runs left out", d.rejected_short)
                               : std::string());
    }
  }
  fmt::print("{:>4}  {:>10} {:>10} {:>8}  {:>30}\n", "pose", "start [s]", "end [s]", "length",
             "mean accel x y z [m/s^2]");
  for (std::size_t i = 0; i < d.intervals.size(); ++i) {
    const auto& iv = d.intervals[i];
    fmt::print("{:>4}  {:>10.2f} {:>10.2f} {:>8.2f}  {:>9.4f} {:>9.4f} {:>9.4f}{}\n", i, iv.start_s,
               iv.end_s, iv.duration_s(), iv.mean_accel_mps2.x(), iv.mean_accel_mps2.y(),
               iv.mean_accel_mps2.z(), iv.initial_rest ? "  initial rest" : "");
  }
}

void print_table_free_fit(const analysis::TableFreeFit& fit) {
  fmt::print("run {}, device {}: no table (orientation unknown); g = {:.5f} m/s^2\n", fit.run,
             fit.device, fit.gravity_mps2);
  fmt::print("model: {}\n", analysis::table_free_model_text(fit.terms));
  for (const auto& n : fit.notes) fmt::print("  note: {}\n", n);
  fmt::print("frame: {}\n\n", solver::kAccelTriadFrameText);
  if (fit.ferraris) {
    const auto& f = *fit.ferraris;
    fmt::print("Ferraris method: six labelled holds and three labelled turns\n");
    print_estimates(f.parameters);
    fmt::print("\n{}\n", f.summary);
    for (const auto& n : f.notes) fmt::print("  note: {}\n", n);
    return;
  }
  print_static_poses(*fit.poses);
  fmt::print("\nAccelerometers by the gravity norm (|calibrated f| = g at every pose)\n");
  print_estimates(fit.accel->parameters);
  print_list("not determined by these poses", fit.accel->undetermined);
  fmt::print("{}\n", fit.accel->summary);
  fmt::print("\nGyros by integration between consecutive poses (bias from the initial rest)\n");
  print_estimates(fit.gyro->parameters);
  print_list("not determined by these turns", fit.gyro->undetermined);
  print_list("moves with an undetermined accelerometer parameter", fit.gyro->frame_open);
  fmt::print("{}\n", fit.gyro->summary);
  if (fit.gyro->earth_rate_modelled) {
    fmt::print(
        "earth_rate is no term here: modelled in the integration (latitude {:.4f} deg; North at "
        "the initial rest {:.1f} +- {:.1f} deg about gravity{}).\n",
        fit.gyro->latitude_deg, fit.gyro->rest_north_azimuth_deg,
        fit.gyro->rest_north_azimuth_sigma_deg,
        fit.gyro->heading_determined ? "" : ", not determined by these turns");
  } else {
    fmt::print("earth_rate is not modelled: the run has no site latitude.\n");
  }
  print_table_free_quality(fit);
}

void print_table_free_quality(const analysis::TableFreeFit& fit) {
  const analysis::TableFreeQuality q = analysis::table_free_quality(fit);
  fmt::print(
      "\nfit quality: chi2/dof {} against the white noise (the turns: their noise model; {:.1f} "
      "over {} degrees of freedom){}, {} parameters; |f| - g rms {:.3g} mg{}\n",
      q.dof > 0 ? fmt::format("{:.3g}", q.chi2_per_dof) : std::string("-"), q.chi2, q.dof,
      q.accel_chi2_per_dof_noise_model
          ? fmt::format("; accel {:.3g} against its noise model", *q.accel_chi2_per_dof_noise_model)
          : std::string(),
      q.parameters, q.rms_norm_residual_mps2 / analysis::kMgInMps2,
      q.rms_turn_residual_deg ? fmt::format(", gravity direction after the turns {:.3g} deg rms",
                                            *q.rms_turn_residual_deg)
                              : std::string());
}

void print_table_free_diagnosis(const analysis::TableFreeDiagnosis& d) {
  const analysis::TableFreeFit& fit = d.fit;
  fmt::print("run {}, device {}: no table (orientation unknown), method {}\n", fit.run, fit.device,
             fit.method);
  fmt::print("model: {}\n", analysis::table_free_model_text(fit.terms));
  for (const auto& n : fit.notes) fmt::print("  note: {}\n", n);
  print_table_free_quality(fit);
  if (!d.worst.empty()) {
    fmt::print("\nwhere the model fails most (residual against its noise):\n");
    for (const auto& w : d.worst) {
      fmt::print("  {:<16} {:>9.2f} to {:>9.2f} s  {:>+10.3g} {:<4} z = {:+.1f}\n", w.what,
                 w.start_s, w.end_s, w.residual, w.unit, w.z);
    }
  }
  fmt::print("\ncandidates (each added in turn, best first):\n");
  if (d.candidates.empty())
    fmt::print("  none\n");
  else
    fmt::print("  {:<20} {:<6} {:>10} {:>9} {:>18}  {}\n", "term", "sensor", "delta BIC", "p",
               "chi2/dof before->after", "residual after");
  for (const auto& c : d.candidates) {
    fmt::print("  {:<20} {:<6} {:>10.1f} {:>9.2g} {:>10.3g} -> {:<6.3g}  {}\n", c.term, c.sensor,
               c.delta_bic, c.p_value, c.chi2_per_dof_before, c.chi2_per_dof_after,
               c.residual_after);
  }
  for (const auto& u : d.untestable) fmt::print("  not testable: {}\n", u);
  fmt::print("\n{}: {}\n", d.explained ? "explained" : "NOT explained", d.advice);
}

}  // namespace calstand::cli
