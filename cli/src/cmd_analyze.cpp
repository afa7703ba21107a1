// `calstand analyze KIND`: the datasheet analyses of the seed's test catalogue on a stored run.
// Kinds so far: stability (in-run bias stability of a long static capture), bandwidth (gain and
// phase of oscillate steps).
#include <fmt/format.h>

#include <optional>
#include <string>

#include "analysis/bandwidth.hpp"
#include "analysis/stability.hpp"
#include "commands.hpp"
#include "core/error.hpp"
#include "core/file_output.hpp"
#include "open_database.hpp"

namespace calstand::cli {
namespace {

struct AnalyzeOptions {
  std::string kind;
  std::string db;
  std::int64_t run = 0;
  std::string device;
  std::optional<std::size_t> step;
  bool as_json = false;
  std::string html;  ///< bandwidth: the gain-curve page
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
    fmt::print(
        "{:<8} {}{:>15.4g} {:<5} {:>11.4g} .. {:<9.4g} {:>8.0f} s  {:>10.4g} {:<5} {:>10.3g} s{}\n",
        ch.channel, ch.floor_resolved ? " " : "<", ch.bias_instability, unit,
        ch.bias_instability_lo, ch.bias_instability_hi, ch.min_tau_s, ch.variation_sigma, unit,
        ch.correlation_time_s, ch.correlation_resolved ? "" : "  (not resolved)");
  }
  fmt::print(
      "< : no floor inside the record (the deviation still falls at its longest averaging time): "
      "a bound.\nnot resolved: the correlation time is outside what the record shows.\n");
}

void print_bandwidth(const analysis::BandwidthAnalysis& b) {
  fmt::print("run {} {}: gyro against the table encoder\n", b.run, b.device);
  fmt::print("{:<5} {:>10} {:>9} {:>9} {:>11}\n", "axis", "f [Hz]", "gain", "[dB]", "phase [deg]");
  for (const auto& p : b.points) {
    fmt::print("{:<5} {:>10.4g} {:>9.4f} {:>9.2f} {:>11.2f}\n", static_cast<char>('x' + p.axis),
               p.frequency_hz, p.gain, p.gain_db, p.phase_deg);
  }
  for (std::size_t a = 0; a < 3; ++a) {
    const auto& fc = b.bandwidth_hz[a];
    const auto& tau = b.delay_s[a];
    if (!fc && !tau) continue;
    fmt::print("{}: bandwidth {}, delay {}{}\n", static_cast<char>('x' + a),
               fc ? fmt::format("{:.4g} Hz", *fc) : "beyond the frequencies tested",
               tau ? fmt::format("{:.3g} ms", *tau * 1e3) : "-",
               b.low_pass_order[a] > 0
                   ? fmt::format(" (after a order-{} low-pass's phase)", b.low_pass_order[a])
                   : "");
  }
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

void run_analyze(const AnalyzeOptions& opt) {
  if (opt.kind == "bandwidth") return run_bandwidth(opt);
  if (opt.kind != "stability") {
    throw core::InputError("KIND", "'" + opt.kind +
                                       "' is not an analysis calstand has (stability, bandwidth); "
                                       "repeatability, warmup and hysteresis follow "
                                       "with their procedures");
  }
  store::Database db = open_existing_database(opt.db);
  const analysis::StabilityAnalysis s =
      analysis::analyse_stability(db, opt.run, opt.device, opt.step);
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
      "with its correlation time, from a long static capture); bandwidth (gyro gain and "
      "phase against the encoder from oscillate steps, -3 dB bandwidth and delay)");
  cmd->add_option("kind", opt->kind, "stability | bandwidth")->required();
  cmd->add_option("--db", opt->db, "Database file")->required();
  cmd->add_option("--run", opt->run, "Run id")->required();
  cmd->add_option("--device", opt->device, "IMU (default: the run's first)");
  cmd->add_option("--step", opt->step, "Static capture step (default: the longest)");
  cmd->add_flag("--json", opt->as_json, "Print the analysis as JSON");
  cmd->add_option("--html", opt->html, "bandwidth: write the gain curves to this HTML file");
  cmd->callback([opt] { run_analyze(*opt); });
}

}  // namespace calstand::cli
