// `calstand analyze KIND`: the datasheet analyses of the seed's test catalogue on a stored run.
// Kinds: stability (in-run bias stability of a long static capture), repeatability (turn-on
// bias across power cycles), warmup (the power-on transient), hysteresis (up and down a
// temperature staircase), bandwidth (gain and phase of oscillate steps); all (the default):
// every one the run's steps support (analysis/run_analyses.hpp), as the report shows them.
#include <fmt/format.h>

#include <cmath>
#include <optional>
#include <string>

#include "commands.hpp"
#include "core/error.hpp"
#include "core/file_output.hpp"
#include "datasheet/bandwidth.hpp"
#include "datasheet/hysteresis.hpp"
#include "datasheet/repeatability.hpp"
#include "datasheet/run_analyses.hpp"
#include "datasheet/stability.hpp"
#include "datasheet/warmup.hpp"
#include "open_database.hpp"

namespace calstand::cli {
namespace {

struct AnalyzeOptions {
  std::string kind = "all";
  std::string db;
  std::int64_t run = 0;
  std::string device;
  std::optional<std::size_t> step;
  /// warmup: settled when within this of the final gyro bias
  double band_deg_per_h = analysis::DatasheetOptions{}.warmup_band_deg_per_h;
  /// warmup: ... and of the final accelerometer bias
  double band_ug = analysis::DatasheetOptions{}.warmup_band_ug;
  bool as_json = false;
  bool no_noise_model = false;  ///< stability: skip the composite noise model
  std::string html;             ///< bandwidth: the gain-curve page
};

void print_stability(const analysis::StabilityAnalysis& s) {
  fmt::print("run {} {}, step {} \"{}\": {:.0f} s static\n", s.run, s.device, s.step, s.step_label,
             s.duration_s);
  fmt::print("{:<8} {:>22} {:>24} {:>10}  {:>16} {:>14}\n", "channel", "bias instability",
             fmt::format("{:.0f} % interval", 100.0 * s.confidence), "at tau", "bias variation",
             "correlation");
  for (std::size_t c = 0; c < s.channels.size(); ++c) {
    const auto& ch = s.channels[c];
    const char* unit = c < 3 ? "deg/h" : "ug";
    const std::string variation =
        ch.variation_sigma
            ? fmt::format("{:>10.4g} {:<5} {:>10.3g} s{}", *ch.variation_sigma, unit,
                          *ch.correlation_time_s, ch.correlation_resolved ? "" : "  (not resolved)")
            : fmt::format("{:>10} {:<5} {:>10}", "-", "", "-");
    fmt::print("{:<8} {}{:>15.4g} {:<5} {:>11.4g} .. {:<9.4g} {:>8.0f} s  {}\n", ch.channel,
               ch.floor_resolved ? " " : "<", ch.bias_instability, unit, ch.bias_instability_lo,
               ch.bias_instability_hi, ch.min_tau_s, variation);
  }
  fmt::print(
      "< : no floor inside the record (the deviation still falls at its longest averaging time): "
      "a bound.\nnot resolved: the correlation time is outside what the record shows.\n"
      "bias model per channel (a bias variation is stated only for a Gauss-Markov bias):\n");
  for (std::size_t c = 0; c < s.channels.size(); ++c) {
    const auto& ch = s.channels[c];
    const std::string fitted = ch.flicker_b
                                   ? fmt::format(" B fitted {:.4g} +- {:.2g} {};", *ch.flicker_b,
                                                 ch.flicker_b_sigma, c < 3 ? "deg/h" : "ug")
                                   : "";
    fmt::print("  {:<4} {}:{} {}\n", ch.channel, solver::to_string(ch.bias_model), fitted,
               ch.bias_model_reason);
  }
  if (s.models.empty()) return;
  fmt::print(
      "the identified composite noise model (estimator gmwm, as calstand noise-id; 95 % "
      "intervals) beside the Allan floor and the Allan-line bias model above:\n");
  for (std::size_t c = 0; c < s.models.size(); ++c) {
    const solver::ChannelModelFigures& m = s.models[c];
    const char* unit = c < 3 ? "deg/h" : "ug";
    const double k = c < 3 ? 3600.0 : 1e6 / 9.80665;  // deg/s -> deg/h; m/s^2 -> ug (g0)
    if (!m.model) {
      fmt::print("  {:<4} no model: {}\n", solver::to_string(m.channel), m.note);
      continue;
    }
    std::string line;
    for (std::size_t i = 0; i < m.figures.size(); ++i) {
      const solver::ModelFigure& f = m.figures[i];
      if (f.estimator != solver::kGmwmEstimator) continue;
      if (f.name == "bias_instability") {
        line += fmt::format(" flicker B {:.4g} [{:.4g}, {:.4g}] {};", k * f.value, k * f.lo,
                            k * f.hi, unit);
      } else if (f.name == "gauss_markov_sigma" && i + 1 < m.figures.size()) {
        const solver::ModelFigure& t = m.figures[i + 1];
        line += fmt::format(
            " Gauss-Markov sigma {:.4g} [{:.4g}, {:.4g}] {}, tau {:.3g} [{:.3g}, {:.3g}] s;",
            k * f.value, k * f.lo, k * f.hi, unit, t.value, t.lo, t.hi);
      }
    }
    fmt::print("  {:<4}{}\n", solver::to_string(m.channel),
               line.empty() ? " no bias instability or Gauss-Markov term selected" : line);
  }
}

void print_repeatability(const analysis::RepeatabilityAnalysis& r) {
  fmt::print("run {} {}: {} power cycles, {} position{} each ({} degrees of freedom)\n", r.run,
             r.device, r.cycles, r.positions, r.positions == 1 ? "" : "s", r.dof);
  fmt::print("{:<8} {:>16} {:>26} {:>14} {:>16}\n", "channel", "repeatability",
             fmt::format("{:.0f} % interval", 100.0 * r.confidence), "spread", "noise of a mean");
  for (std::size_t c = 0; c < r.channels.size(); ++c) {
    const auto& ch = r.channels[c];
    const char* unit = c < 3 ? "deg/h" : "ug";
    fmt::print("{:<8} {:>10.4g} {:<5} {:>11.4g} .. {:<11.4g} {:>14.4g} {:>16.4g}\n", ch.channel,
               ch.repeatability, unit, ch.repeatability_lo, ch.repeatability_hi, ch.spread,
               ch.noise_of_means);
  }
  fmt::print("repeatability = sqrt(spread^2 - noise of a mean^2), 1 sigma across power-ups\n");
  bool header = false;
  for (std::size_t a = 0; a < r.gyro_scale.size(); ++a) {
    const auto& s = r.gyro_scale[a];
    if (!s.measured) continue;
    if (!header) {
      fmt::print("\ngyro scale factor, from turns both ways in each cycle:\n");
      fmt::print("{:<8} {:>16} {:>26} {:>14} {:>16}  {}\n", "axis", "repeatability",
                 fmt::format("{:.0f} % interval", 100.0 * r.confidence), "spread", "noise of one",
                 "rates");
      header = true;
    }
    std::string rates;
    for (double rate : s.rates_dps) rates += fmt::format("{}{:g}", rates.empty() ? "" : ", ", rate);
    fmt::print("{:<8} {:>10.4g} {:<5} {:>11.4g} .. {:<11.4g} {:>14.4g} {:>16.4g}  {} deg/s\n",
               fmt::format("g{}", "xyz"[a]), s.repeatability_ppm, "ppm", s.repeatability_lo_ppm,
               s.repeatability_hi_ppm, s.spread_ppm, s.noise_of_estimates_ppm, rates);
  }
}

void print_warmup(const analysis::WarmupAnalysis& w) {
  fmt::print(
      "run {} {}, step {} \"{}\": {:.0f} s from power-up, bins of {:.3g} s; the IMU warmed "
      "by {:.2f} degC\n",
      w.run, w.device, w.step, w.step_label, w.duration_s, w.bin_s, w.temperature_rise_c);
  fmt::print("{:<8} {:>24} {:>16} {:>22}\n", "channel", "transient amplitude", "time constant",
             "time to band");
  for (std::size_t c = 0; c < w.channels.size(); ++c) {
    const auto& ch = w.channels[c];
    const bool gyro = c < 3;
    fmt::print("{:<8} {:>10.4g} +- {:<7.2g} {:<5} {:>12.4g} s {:>12.0f} s (+-{:g} {}){}\n",
               ch.channel, ch.amplitude, ch.amplitude_sigma, gyro ? "deg/h" : "ug",
               ch.time_constant_s, ch.time_to_band_s, gyro ? w.band_deg_per_h : w.band_ug,
               gyro ? "deg/h" : "ug",
               ch.resolved ? (ch.temperature_term ? "  (with a temperature term)" : "")
                           : "  (no transient resolved)");
  }
}

void print_hysteresis(const analysis::HysteresisAnalysis& h) {
  fmt::print("run {} {}: {} at each set point, on the way up and down\n", h.run, h.device, h.model);
  fmt::print("{:>8}  {:<16} {:>22} {:>22} {:>22} {:>7}\n", "degC", "parameter", "up", "down",
             "up - down", "z");
  for (const auto& p : h.points) {
    fmt::print("{:>8g}  {:<16} {:>22} {:>22} {:>22} {:>7.1f} {}{}\n", p.temperature_c, p.parameter,
               fmt::format("{:.5g} +- {:.2g}", p.up, p.up_sigma),
               fmt::format("{:.5g} +- {:.2g}", p.down, p.down_sigma),
               fmt::format("{:.3g} +- {:.2g}", p.difference, p.difference_sigma), p.z, p.unit,
               std::abs(p.z) > 4.0 ? "  <- hysteresis" : "");
  }
  fmt::print("|z| > 4: the difference is far beyond both fits' uncertainty\n");
}

void print_bandwidth(const analysis::BandwidthAnalysis& b) {
  fmt::print("run {} {}: gyro against the table encoder\n", b.run, b.device);
  fmt::print("{:<5} {:>10} {:>9} {:>9} {:>9} {:>11} {:>9}\n", "axis", "f [Hz]", "gain", "sigma",
             "[dB]", "phase [deg]", "sigma");
  for (const auto& p : b.points) {
    fmt::print("{:<5} {:>10.4g} {:>9.4f} {:>9.2g} {:>9.2f} {:>11.2f} {:>9.2g}\n",
               static_cast<char>('x' + p.axis), p.frequency_hz, p.gain, p.gain_sigma, p.gain_db,
               p.phase_deg, p.phase_sigma_deg);
  }
  for (std::size_t a = 0; a < 3; ++a) {
    const auto& fc = b.bandwidth_hz[a];
    const auto& tau = b.delay_s[a];
    if (!fc && !tau) continue;
    const auto& fc_interval = b.bandwidth_interval_hz[a];
    const auto& tau_interval = b.delay_interval_s[a];
    fmt::print(
        "{}: bandwidth {}{}, delay {}{}{}\n", static_cast<char>('x' + a),
        fc ? fmt::format("{:.4g} Hz", *fc) : "beyond the frequencies tested",
        fc_interval ? fmt::format(" [{:.4g} .. {:.4g}]", (*fc_interval)[0], (*fc_interval)[1]) : "",
        tau ? fmt::format("{:.3g} ms", *tau * 1e3) : "-",
        tau_interval
            ? fmt::format(" [{:.3g} .. {:.3g}]", (*tau_interval)[0] * 1e3, (*tau_interval)[1] * 1e3)
            : "",
        b.low_pass_order[a] > 0
            ? fmt::format(" (after a order-{} low-pass's phase)", b.low_pass_order[a])
            : "");
  }
  fmt::print(
      "sigma: 1 sigma from the scatter of segments of whole periods; [..]: {:.0f} % intervals "
      "(bootstrap over the points' sigmas)\n",
      100.0 * b.confidence);
}

void run_bandwidth(const AnalyzeOptions& opt) {
  store::Database db = open_existing_database(opt.db);
  const analysis::BandwidthAnalysis b = analysis::analyse_bandwidth(db, opt.run, opt.device);
  if (!opt.html.empty()) {
    core::write_file_whole(opt.html,
                           "<!doctype html><meta charset=utf-8><title>bandwidth</title>\n" +
                               analysis::bandwidth_svg(b) + "\n");
  }
  if (opt.as_json) {
    fmt::print("{}\n", analysis::to_json(b).dump(2));
  } else {
    print_bandwidth(b);
  }
}

void run_all(const AnalyzeOptions& opt) {
  if (opt.step) {
    throw core::InputError("--step", "picks the capture of one analysis: give its KIND");
  }
  store::Database db = open_existing_database(opt.db);
  const analysis::DatasheetAnalyses a =
      analysis::run_datasheet_analyses(db, opt.run, opt.device, {opt.band_deg_per_h, opt.band_ug});
  if (opt.as_json) {
    fmt::print("{}\n", analysis::to_json(a).dump(2));
    return;
  }
  fmt::print("run {} {}: the datasheet analyses its steps support\n", a.run, a.device);
  for (const auto& ap : a.applicability) {
    const std::string_view kind = analysis::to_string(ap.kind);
    if (!ap.applies) {
      fmt::print("  {:<14} not applicable: {}\n", kind, ap.evidence);
    } else if (a.has_result(ap.kind)) {
      fmt::print("  {:<14} applies: {}\n", kind, ap.evidence);
    } else {
      fmt::print("  {:<14} missing: {}, but the analysis refused it: {}\n", kind, ap.evidence,
                 a.failure_of(ap.kind));
    }
  }
  if (a.repeatability) fmt::print("\n"), print_repeatability(*a.repeatability);
  if (a.warmup) fmt::print("\n"), print_warmup(*a.warmup);
  if (a.stability) fmt::print("\n"), print_stability(*a.stability);
  if (a.hysteresis) fmt::print("\n"), print_hysteresis(*a.hysteresis);
  if (a.bandwidth) fmt::print("\n"), print_bandwidth(*a.bandwidth);
}

void run_analyze(const AnalyzeOptions& opt) {
  if (opt.kind == "all") return run_all(opt);
  if (opt.kind == "bandwidth") return run_bandwidth(opt);
  if (opt.kind != "stability" && opt.kind != "repeatability" && opt.kind != "warmup" &&
      opt.kind != "hysteresis") {
    throw core::InputError("KIND", "'" + opt.kind +
                                       "' is not an analysis calstand has (stability, "
                                       "repeatability, warmup, hysteresis, bandwidth, all)");
  }
  store::Database db = open_existing_database(opt.db);
  if (opt.kind == "hysteresis") {
    const auto h = analysis::analyse_hysteresis(db, opt.run, opt.device);
    if (opt.as_json) {
      fmt::print("{}\n", analysis::to_json(h).dump(2));
    } else {
      print_hysteresis(h);
    }
    return;
  }
  if (opt.kind == "warmup") {
    const auto w = analysis::analyse_warmup(db, opt.run, opt.device, opt.step, opt.band_deg_per_h,
                                            opt.band_ug);
    if (opt.as_json) {
      fmt::print("{}\n", analysis::to_json(w).dump(2));
    } else {
      print_warmup(w);
    }
    return;
  }
  if (opt.kind == "repeatability") {
    const auto r = analysis::analyse_repeatability(db, opt.run, opt.device);
    if (opt.as_json) {
      fmt::print("{}\n", analysis::to_json(r).dump(2));
    } else {
      print_repeatability(r);
    }
    return;
  }
  const analysis::StabilityAnalysis s =
      analysis::analyse_stability(db, opt.run, opt.device, opt.step, !opt.no_noise_model);
  if (opt.as_json) {
    fmt::print("{}\n", analysis::to_json(s).dump(2));
  } else {
    print_stability(s);
  }
}

}  // namespace

void register_analyze(CLI::App& app) {
  auto opt = std::make_shared<AnalyzeOptions>();
  auto* cmd = app.add_subcommand(
      "analyze",
      "Datasheet analyses of a run: stability (bias instability and bias variation "
      "with its correlation time, from a long static capture); repeatability (turn-on bias "
      "spread over power cycles); warmup (the bias transient after power-up); hysteresis (up "
      "and down a temperature staircase); bandwidth (gyro gain and phase against the encoder "
      "from oscillate steps, -3 dB bandwidth and delay); all (the default): each one the run's "
      "steps support, and why the others do not apply");
  cmd->add_option("kind", opt->kind,
                  "stability | repeatability | warmup | hysteresis | bandwidth | all")
      ->capture_default_str();
  cmd->add_option("--db", opt->db, "Database file")->required();
  cmd->add_option("--run", opt->run, "Run id")->required();
  cmd->add_option("--device", opt->device, "IMU (default: the run's first)");
  cmd->add_option("--step", opt->step, "Static capture step (default: the longest)");
  cmd->add_option("--band-deg-per-h", opt->band_deg_per_h,
                  "warmup: a gyro bias within this of its settled value is settled")
      ->capture_default_str();
  cmd->add_option("--band-ug", opt->band_ug,
                  "warmup: an accelerometer bias within this of its settled value is settled")
      ->capture_default_str();
  cmd->add_flag("--no-noise-model", opt->no_noise_model,
                "stability: skip the composite noise model (GMWM, about 1 s per channel and "
                "2^19 samples)");
  cmd->add_flag("--json", opt->as_json, "Print the analysis as JSON");
  cmd->add_option("--html", opt->html, "bandwidth: write the gain curves to this HTML file");
  cmd->callback([opt] { run_analyze(*opt); });
}

}  // namespace calstand::cli
