// `calstand allan` (a deviation curve of one channel, from a run or a CSV file) and
// `calstand noise` (the fitted noise terms of a run's static step, all six channels, in
// datasheet units, optionally as a Kalibr imu.yaml).
#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <iostream>
#include <limits>
#include <memory>
#include <new>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <system_error>
#include <vector>

#include "analysis/noise_json.hpp"
#include "analysis/noise_model_json.hpp"
#include "commands.hpp"
#include "core/error.hpp"
#include "noise/allan.hpp"
#include "noise/composite_noise.hpp"
#include "noise/deviation_stream.hpp"
#include "noise/kalibr.hpp"
#include "noise/model_figures.hpp"
#include "noise/noise_fit.hpp"
#include "noise/record_length.hpp"
#include "noise/record_stream.hpp"
#include "noise/run_noise.hpp"
#include "noise/total_deviation.hpp"
#include "open_database.hpp"
#include "store/database.hpp"
#include "store/sample_reader.hpp"

namespace calstand::cli {
namespace {

using Json = nlohmann::ordered_json;

// Options arrive as text and are converted here, so that every bad value is an InputError
// naming the option (exit code 2), like the other commands' input.
struct AllanArgs {
  std::string db, run, step, channel, device, csv, column, rate, units;
  std::string taus = "octave";
  std::string kind = "adev";
  std::string confidence = "0.683";
  std::string alpha;  // empty: identified at each tau
  bool no_bias_correction = false;
  bool json = false;
};

struct NoiseArgs {
  std::string db, run, step, device, kalibr;
  std::string taus = "dense";
  std::string rostopic = "/imu0";
  bool json = false;
  bool no_noise_model = false;
};

std::int64_t parse_int(const std::string& text, const char* option, std::int64_t min) {
  std::int64_t v = 0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (text.empty() || ec != std::errc() || ptr != text.data() + text.size() || v < min) {
    throw core::InputError(option, fmt::format("expected an integer >= {}, got '{}'", min, text));
  }
  return v;
}

double parse_double(const std::string& text, const char* option) {
  double v = 0.0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (text.empty() || ec != std::errc() || ptr != text.data() + text.size() || !std::isfinite(v)) {
    throw core::InputError(option, fmt::format("expected a finite number, got '{}'", text));
  }
  return v;
}

std::optional<std::size_t> parse_step(const std::string& text) {
  if (text.empty()) return std::nullopt;
  return static_cast<std::size_t>(parse_int(text, "--step", 0));
}

std::string term_line(const char* label, const solver::NoiseTerm& t, const std::string& unit) {
  if (!t.resolved) return fmt::format("  {:<26} not resolved\n", label);
  return fmt::format("  {:<26} {:.4g} +- {:.2g} {}\n", label, t.value, t.sigma, unit);
}

// One datasheet figure as `calstand noise` shows it: value +- sigma, the value alone for a
// figure read off the curve, "-" when not resolved.
std::string figure_cell(const solver::DatasheetFigure& f) {
  if (!f.resolved) return "-";
  return std::isfinite(f.sigma) ? fmt::format("{:.4g} +- {:.2g}", f.value, f.sigma)
                                : fmt::format("{:.4g}", f.value);
}

// The total and Theo kinds (solver/total_deviation.hpp): the same JSON as the Allan kinds,
// plus whether the bias corrections were applied; no noise-term fit (that is on the Allan
// variance, or `calstand noise-id`).
void print_total(const solver::TotalResult& t, const std::string& source, std::string unit,
                 double rate_hz, bool json) {
  const std::string key(solver::to_string(t.kind));
  if (t.kind == solver::TotalKind::kTimeTotal) unit += "*s";  // tau / sqrt(3) MTOTDEV
  solver::AllanResult r;
  r.sample_rate_hz = t.sample_rate_hz;
  r.samples = t.samples;
  r.confidence = t.confidence;
  r.points = t.points;
  if (json) {
    auto out = analysis::allan_json(r, source, key, unit, rate_hz, std::nullopt, std::nullopt);
    out["bias_corrected"] = t.bias_corrected;
    std::cout << out.dump(2) << "\n";
    return;
  }
  std::cout << fmt::format("{} of {}: {} samples at {:.6g} Hz, {:.1f} % intervals, {} [{}]\n", key,
                           source, r.samples, rate_hz, 100.0 * r.confidence,
                           t.bias_corrected ? "bias-corrected as Stable32" : "no bias correction",
                           unit);
  std::cout << fmt::format("{:>12} {:>8} {:>13} {:>13} {:>13} {:>10} {:>6}\n", "tau [s]", "m", key,
                           "lo", "hi", "edf", "alpha");
  for (const auto& p : r.points) {
    std::cout << fmt::format("{:>12.6g} {:>8} {:>13.6e} {:>13.6e} {:>13.6e} {:>10.4g} {:>6}\n",
                             p.tau_s, p.m, p.deviation, p.lo, p.hi, p.edf, p.alpha);
  }
}

// The record of `calstand allan` and `calstand noise-id`: a CSV column, or one channel of a
// stored run's static step.
struct Series {
  std::vector<double> data;
  double rate_hz = 0.0;
  std::string unit = "unit";
  std::string source;
  std::optional<solver::ImuChannel> channel;
};

// With `stream`, the record is fed to it (constant memory) and out.data stays empty.
Series load_series(const AllanArgs& a, solver::DeviationStream* stream = nullptr) {
  Series out;
  std::vector<double>& data = out.data;
  double& rate_hz = out.rate_hz;
  std::string& unit = out.unit;
  std::string& source = out.source;
  std::optional<solver::ImuChannel>& channel = out.channel;
  if (!a.csv.empty()) {
    if (!a.db.empty() || !a.run.empty()) {
      throw core::InputError("--csv", "give either --csv or --db/--run, not both");
    }
    if (a.column.empty() || a.rate.empty()) {
      throw core::InputError("--csv", "needs --column NAME and --rate HZ");
    }
    rate_hz = parse_double(a.rate, "--rate");
    if (rate_hz <= 0.0)
      throw core::InputError("--rate", fmt::format("must be positive, got {}", rate_hz));
    if (stream) {
      solver::stream_csv_column(a.csv, a.column, *stream);
    } else {
      data = solver::read_csv_column(a.csv, a.column);
    }
    source = fmt::format("{} column {}", a.csv, a.column);
    if (!a.units.empty()) unit = a.units;
  } else {
    if (!a.units.empty()) {
      throw core::InputError("--units", "only with --csv (a run's channels have their units)");
    }
    if (a.db.empty() || a.run.empty() || a.channel.empty()) {
      throw core::InputError("allan",
                             "give --db FILE --run ID --channel gx|gy|gz|ax|ay|az "
                             "(and --step N), or --csv FILE --column NAME --rate HZ");
    }
    channel = solver::parse_channel(a.channel);
    const std::int64_t run = parse_int(a.run, "--run", 1);
    store::Database db = open_existing_database(a.db);
    const std::size_t step = solver::choose_noise_step(db, run, parse_step(a.step));
    std::string device = a.device;
    if (device.empty()) {
      const auto devices = store::sample_devices(db, run);
      if (devices.empty())
        throw core::InputError("--run", fmt::format("run {} holds no samples", run));
      device = devices.front();
    }
    if (stream) {
      rate_hz =
          solver::stream_stored_channel(db, run, step, device, *channel, *stream).sample_rate_hz;
    } else {
      const auto samples = store::read_samples(db, run, step, device);
      if (samples.empty()) {
        throw core::InputError(
            "--step", fmt::format("step {} of run {} holds no samples of '{}'", step, run, device));
      }
      rate_hz = solver::sample_rate_of(samples);
      data = solver::channel_series(samples, *channel);
    }
    unit = std::string(solver::channel_unit(*channel));
    source = fmt::format("run {} step {} {} {}", run, step, device, a.channel);
  }
  return out;
}

void run_allan(const AllanArgs& a) {
  const std::optional<solver::TotalKind> total_kind = solver::parse_total_kind(a.kind);
  solver::AllanOptions options;
  if (!total_kind) {
    try {
      options.kind = solver::parse_allan_kind(a.kind);
    } catch (const core::InputError&) {
      throw core::InputError("--kind", fmt::format("'{}' is none of adev, mdev, ohdev, hdev, "
                                                   "totdev, mtotdev, ttotdev, htotdev, theo1, "
                                                   "theobr, theoh",
                                                   a.kind));
    }
    if (a.no_bias_correction) {
      throw core::InputError("--no-bias-correction",
                             "only for the total and Theo kinds (the Allan kinds are unbiased)");
    }
  }
  options.taus = solver::TauSet::parse(a.taus);
  options.confidence = parse_double(a.confidence, "--confidence");
  if (!a.alpha.empty()) options.alpha = static_cast<int>(parse_int(a.alpha, "--alpha", -4));
  solver::TotalOptions total;
  if (total_kind) {
    total.kind = *total_kind;
    total.taus = options.taus;
    total.confidence = options.confidence;
    total.alpha = options.alpha;
    total.bias_correction = !a.no_bias_correction;
    total.validate();
  } else {
    options.validate();
  }

  // The octave curves of adev, ohdev and mdev are streamed (constant memory: a day at 1 kHz
  // fits); hdev, the other tau sets and the total and Theo kinds, which reflect or resample the
  // whole record, hold it in memory.
  const bool streamed = !total_kind && options.kind != solver::AllanKind::kHadamardNonOverlapping &&
                        options.taus.spacing == solver::TauSpacing::kOctave;
  std::optional<solver::DeviationStream> stream;
  if (streamed) stream.emplace(std::vector<solver::AllanKind>{options.kind});
  const auto too_long = [&] {
    return core::InputError(
        total_kind ? "--kind" : "--taus",
        "the record does not fit in memory; only the octave taus of adev, ohdev and mdev are "
        "streamed in constant memory (hdev, decade, dense and listed taus, and the total and "
        "Theo kinds hold the whole record)");
  };
  Series series;
  try {
    series = load_series(a, stream ? &*stream : nullptr);
  } catch (const std::bad_alloc&) {
    throw too_long();
  }
  std::vector<double>& data = series.data;
  const double rate_hz = series.rate_hz;
  const std::string& unit = series.unit;
  const std::string& source = series.source;
  const std::optional<solver::ImuChannel>& channel = series.channel;
  if (total_kind) {
    std::optional<solver::TotalResult> t;
    try {
      t = solver::total_deviation(data, rate_hz, total);
    } catch (const std::bad_alloc&) {
      throw too_long();
    }
    print_total(*t, source, unit, rate_hz, a.json);
    return;
  }
  std::optional<solver::AllanResult> computed;
  try {
    computed = stream ? stream->result(rate_hz, options) : solver::allan(data, rate_hz, options);
  } catch (const std::bad_alloc&) {
    throw too_long();
  }
  const solver::AllanResult& r = *computed;
  std::optional<solver::NoiseTerms> terms;
  if (options.kind == solver::AllanKind::kAllan) {
    // As `calstand noise`: an IMU's anti-aliasing filter shapes the first samples of tau.
    solver::NoiseFitOptions fit;
    if (channel) fit.min_tau_s = solver::RunNoiseOptions{}.min_tau_samples / rate_hz;
    try {
      terms = solver::fit_noise_terms(r, fit);
    } catch (const core::InputError&) {
      // Too few averaging times for a fit: the curve alone is still the answer.
    }
  }
  const std::string key(solver::to_string(options.kind));
  // A gyro or accelerometer unit (a run's channel, or --units) also gives datasheet figures.
  const std::optional<analysis::DatasheetUnit> datasheet =
      channel ? std::optional(analysis::DatasheetUnit{solver::is_gyro(*channel), 1.0})
              : analysis::datasheet_unit(unit);
  if (a.json) {
    std::cout << analysis::allan_json(r, source, key, unit, rate_hz, terms, datasheet).dump(2)
              << "\n";
    return;
  }
  std::cout << fmt::format("{} of {}: {} samples at {:.6g} Hz, {:.1f} % intervals [{}]\n", key,
                           source, r.samples, rate_hz, 100.0 * r.confidence, unit);
  std::cout << fmt::format("{:>12} {:>13} {:>13} {:>13} {:>10} {:>6}\n", "tau [s]", key, "lo", "hi",
                           "edf", "alpha");
  for (const auto& p : r.points) {
    std::cout << fmt::format("{:>12.6g} {:>13.6e} {:>13.6e} {:>13.6e} {:>10.4g} {:>6}\n", p.tau_s,
                             p.deviation, p.lo, p.hi, p.edf, p.alpha);
  }
  if (terms) {
    const auto& t = *terms;
    // Without a unit (a CSV without --units) the terms are in "u", the data's unit.
    const std::string u = unit == "unit" ? "u" : unit;
    std::cout << fmt::format("\nnoise terms (Allan variance fit, chi2/dof {:.3g}; unit {})\n",
                             t.chi2_dof, u == "u" ? "u = unit of the data" : u);
    std::cout << term_line("quantization Q", t.quantization, u + "*s");
    std::cout << term_line("random walk N", t.random_walk, u + "/sqrt(Hz)");
    std::cout << term_line("bias instability B (fit)", t.bias_instability, u);
    std::cout << term_line("rate random walk K", t.rate_random_walk, u + "/sqrt(s)");
    std::cout << term_line("rate ramp R", t.rate_ramp, u + "/s");
    std::cout << fmt::format(
        "  {:<26} {:.4g} {} at tau {:.4g} s (B = minimum / 0.664 = {:.4g} {})\n", "Allan minimum",
        t.min_deviation, u, t.min_tau_s, t.bias_instability_from_min, u);
    if (datasheet) {
      std::cout << fmt::format("\ndatasheet figures ({}, as calstand noise gives them)\n",
                               datasheet->gyro ? "gyro" : "accelerometer");
      for (const auto& f : solver::datasheet_figures(
               analysis::scale_noise_terms(t, datasheet->to_base), datasheet->gyro)) {
        std::cout << fmt::format("  {:<40} {:>22} {}\n", f.label, figure_cell(f), f.unit);
      }
    } else if (!a.units.empty()) {
      std::cout << fmt::format("(no datasheet figures: '{}' is none of deg/s, rad/s, m/s^2, g)\n",
                               unit);
    }
  }
}

struct NoiseIdArgs : AllanArgs {
  std::string bootstrap = "0";
  std::string min_tau = "0";
};

// A datasheet figure of one parameter (the human output): ARW deg/sqrt(h) or VRW m/s/sqrt(h)
// from a white density, deg/h/sqrt(h) or m/s/h/sqrt(h) from a random-walk density, deg/h or ug
// for the rest; empty for a unit that is neither a gyro's nor an accelerometer's.
std::string datasheet_cell(solver::NoiseKind kind, double v, const analysis::DatasheetUnit& d) {
  constexpr double kUg = 9.80665e-6;  // m/s^2 per micro-g
  const double b = v * d.to_base;     // deg/s or m/s^2 based
  switch (kind) {
    case solver::NoiseKind::kWhite:
      return fmt::format("{:.4g} {}", b * 60.0, d.gyro ? "deg/sqrt(h)" : "m/s/sqrt(h)");
    case solver::NoiseKind::kRandomWalk:
      return fmt::format("{:.4g} {}", b * 3600.0 * 60.0,
                         d.gyro ? "deg/h/sqrt(h)" : "m/s/h/sqrt(h)");
    case solver::NoiseKind::kFlicker:
    case solver::NoiseKind::kGaussMarkov:
      return d.gyro ? fmt::format("{:.4g} deg/h", b * 3600.0) : fmt::format("{:.4g} ug", b / kUg);
    case solver::NoiseKind::kDrift:
      return d.gyro ? fmt::format("{:.4g} deg/h/s", b * 3600.0)
                    : fmt::format("{:.4g} ug/s", b / kUg);
    case solver::NoiseKind::kQuantization:
      return d.gyro ? fmt::format("{:.4g} deg", b) : fmt::format("{:.4g} m/s", b);
  }
  return {};
}

void run_noise_id(const NoiseIdArgs& a) {
  solver::NoiseIdOptions options;
  options.bootstrap = static_cast<std::size_t>(parse_int(a.bootstrap, "--bootstrap", 0));
  options.min_tau_s = parse_double(a.min_tau, "--min-tau");
  // The GMWM needs only the wavelet variances, streamed in constant memory; the bootstrap's
  // replicates are whole simulated records, so with it the record is held in memory too.
  std::optional<solver::DeviationStream> stream;
  if (options.bootstrap == 0)
    stream.emplace(std::vector<solver::AllanKind>{solver::AllanKind::kAllan});
  const Series series = load_series(a, stream ? &*stream : nullptr);
  const solver::NoiseModel model =
      stream ? solver::identify_noise_model(stream->moments(series.rate_hz), options)
             : solver::identify_noise_model(series.data, series.rate_hz, options);
  if (a.json) {
    std::cout << analysis::noise_model_json(model, series.source, series.unit).dump(2) << "\n";
    return;
  }
  const std::optional<analysis::DatasheetUnit> datasheet =
      series.channel ? std::optional(analysis::DatasheetUnit{solver::is_gyro(*series.channel), 1.0})
                     : analysis::datasheet_unit(series.unit);
  std::cout << fmt::format(
      "noise model of {}: {} samples at {:.6g} Hz [{}]\n{}\nselected by {}\n\n", series.source,
      model.samples, model.sample_rate_hz, series.unit, model.estimator, model.selected_by);
  std::cout << fmt::format("{:<14} {:<18} {:>12} {:>27} {:<18} {}\n", "term", "parameter", "value",
                           "95 % interval", "unit", datasheet ? "datasheet" : "");
  for (const auto& t : model.terms) {
    const std::string kind(solver::to_string(t.kind));
    const auto row = [&](const std::string& name, double v, double lo, double hi,
                         const std::string& u, const std::string& sheet) {
      std::cout << fmt::format("{:<14} {:<18} {:>12.4g} {:>27} {:<18} {}\n", kind, name, v,
                               fmt::format("[{:.4g}, {:.4g}]", lo, hi), u, sheet);
    };
    row(analysis::noise_parameter_name(t.kind), t.value, t.value_lo, t.value_hi,
        analysis::noise_parameter_unit(t.kind, series.unit),
        datasheet ? datasheet_cell(t.kind, t.value, *datasheet) : "");
    if (t.kind == solver::NoiseKind::kGaussMarkov)
      row("tau_s", t.tau_s, t.tau_lo_s, t.tau_hi_s, "s", "");
  }
  std::cout << "\ncandidates (criterion = efficient GMWM objective J + 2 p ln ln n; '-': a term "
               "not resolved)\n";
  for (const auto& c : model.candidates) {
    std::string names;
    for (auto k : c.kinds)
      names += (names.empty() ? "" : " + ") + std::string(solver::to_string(k));
    std::cout << fmt::format("  {:<62} {:>10} {}\n", names,
                             c.admissible ? fmt::format("{:.2f}", c.criterion) : "-",
                             c.selected ? "selected" : "");
  }
}

void print_noise_table(const solver::RunNoise& r, bool gyro) {
  std::vector<const solver::ChannelNoise*> chans;
  for (const auto& c : r.channels) {
    if (solver::is_gyro(c.channel) == gyro) chans.push_back(&c);
  }
  if (chans.empty()) return;
  std::cout << fmt::format("\n{:<40} {:<14}", gyro ? "gyro" : "accelerometer", "unit");
  for (const auto* c : chans) std::cout << fmt::format(" {:>22}", solver::to_string(c->channel));
  std::cout << "\n";
  for (std::size_t i = 0; i < chans.front()->figures.size(); ++i) {
    const auto& f0 = chans.front()->figures[i];
    std::cout << fmt::format("{:<40} {:<14}", f0.label, f0.unit);
    for (const auto* c : chans) {
      std::cout << fmt::format(" {:>22}", figure_cell(c->figures[i]));
    }
    std::cout << "\n";
  }
}

// What the record gives against what each figure needs (solver/record_length.hpp).
void print_record_length(const solver::RunNoise& r) {
  const solver::RecordLengthRule rule;
  std::cout << fmt::format(
      "\nrecord length: this record has {}; what each figure needs for its {:.0f} % interval "
      "within +-{:.0f} % (the Allan variance's edf >= {:.0f} at the figure's tau):\n",
      solver::format_record_length(r.duration_s), 100.0 * rule.confidence, 100.0 * rule.half_width,
      solver::required_edf(rule));
  for (const solver::FigureRecordNeed& n : solver::record_length_needs(r, rule)) {
    const char* label = n.figure == "random_walk"
                            ? (n.gyro ? "angle random walk" : "velocity random walk")
                        : n.figure == "bias_instability"
                            ? "bias instability"
                            : (n.gyro ? "rate random walk" : "acceleration random walk");
    const std::string verdict = n.enough
                                    ? "enough"
                                    : fmt::format("not enough: this record has {}",
                                                  solver::format_record_length(n.record_length_s));
    std::cout << fmt::format(
        "  {:<13} {:<25} needs {}{} (tau {:.3g} s{}): {}\n", n.gyro ? "gyro" : "accelerometer",
        label, n.located ? "about " : "more than ", solver::format_record_length(n.needed_s),
        n.tau_s, n.located ? "" : ", the minimum not reached yet", verdict);
  }
}

// A model figure in its datasheet unit (ARW, bias instability, RRW; deg/h or ug for a
// Gauss-Markov sigma), for the human output; the correlation time as it is.
std::string model_figure_sheet(const solver::ModelFigure& f, bool gyro) {
  const analysis::DatasheetUnit d{gyro, 1.0};
  if (f.name == "white_density") return datasheet_cell(solver::NoiseKind::kWhite, f.value, d);
  if (f.name == "random_walk") return datasheet_cell(solver::NoiseKind::kRandomWalk, f.value, d);
  if (f.name == "bias_instability") return datasheet_cell(solver::NoiseKind::kFlicker, f.value, d);
  if (f.name == "gauss_markov_sigma")
    return datasheet_cell(solver::NoiseKind::kGaussMarkov, f.value, d);
  return "";
}

// Per channel the figures of its identified model, or the Allan line's where the record does
// not support the model, each with its estimator.
void print_model_figures(const std::vector<solver::ChannelModelFigures>& models) {
  std::cout << "\nnoise model figures (95 % intervals; estimator gmwm: the identified composite "
               "model, as calstand noise-id gives it; allan-line: the fit above, +- 1.96 sigma)\n";
  std::cout << fmt::format("{:<8} {:<20} {:>11} {:>25} {:<22} {:<22} {}\n", "channel", "figure",
                           "value", "95 % interval", "unit", "datasheet", "estimator");
  for (const solver::ChannelModelFigures& m : models) {
    const std::string channel(solver::to_string(m.channel));
    if (!m.model) std::cout << fmt::format("{:<8} (no model: {})\n", channel, m.note);
    for (const solver::ModelFigure& f : m.figures) {
      const std::string value = f.resolved ? fmt::format("{:.4g}", f.value) : "-";
      const std::string interval =
          f.resolved ? fmt::format("[{:.4g}, {:.4g}]", f.lo, f.hi) : "not resolved";
      const std::string sheet = f.resolved ? model_figure_sheet(f, solver::is_gyro(m.channel)) : "";
      const std::string why = f.note.empty() || !m.model ? "" : fmt::format(" ({})", f.note);
      std::cout << fmt::format("{:<8} {:<20} {:>11} {:>25} {:<22} {:<22} {}{}\n", channel, f.name,
                               value, interval, f.unit, sheet, f.estimator, why);
    }
  }
}

void run_noise(const NoiseArgs& a) {
  if (a.db.empty() || a.run.empty()) throw core::InputError("noise", "needs --db FILE --run ID");
  solver::RunNoiseOptions options;
  options.device = a.device;
  options.step = parse_step(a.step);
  options.allan.taus = solver::TauSet::parse(a.taus);
  const std::int64_t run = parse_int(a.run, "--run", 1);
  store::Database db = open_existing_database(a.db);
  const solver::RunNoise r = solver::analyse_run_noise(db, run, options);
  std::vector<solver::ChannelModelFigures> models;
  if (!a.no_noise_model) models = solver::channel_noise_models(db, r);

  std::optional<solver::KalibrImu> kalibr;
  if (!a.kalibr.empty()) {
    std::vector<std::string> unresolved;
    kalibr = a.no_noise_model
                 ? solver::kalibr_from_run_noise(r, a.rostopic, &unresolved)
                 : solver::kalibr_from_noise_models(r, models, a.rostopic, &unresolved);
    const std::string yaml = solver::kalibr_yaml(*kalibr);
    std::ofstream out(a.kalibr);
    if (!out || !(out << yaml) || !out.flush()) {
      throw std::runtime_error(fmt::format("{}: cannot write the Kalibr file", a.kalibr));
    }
    for (const auto& field : unresolved) {
      std::cerr << fmt::format(
          "calstand: warning: {}: not resolved on every axis (record longer); the file has the "
          "largest resolved axis or 0\n",
          field);
    }
  }
  if (a.json) {
    Json out = analysis::run_noise_json(r);
    for (std::size_t i = 0; i < models.size() && i < out["channels"].size(); ++i) {
      out["channels"][i].update(analysis::channel_model_figures_json(models[i]));
    }
    if (a.no_noise_model) out["noise_model_note"] = "not asked for (--no-noise-model)";
    out["record_length"] = analysis::record_length_json(r);
    if (!a.kalibr.empty()) out["kalibr"] = a.kalibr;
    if (kalibr) {
      out["kalibr_estimators"] = {
          {"gyroscope_noise_density", kalibr->gyroscope_noise_density_estimator},
          {"gyroscope_random_walk", kalibr->gyroscope_random_walk_estimator},
          {"accelerometer_noise_density", kalibr->accelerometer_noise_density_estimator},
          {"accelerometer_random_walk", kalibr->accelerometer_random_walk_estimator}};
    }
    std::cout << out.dump(2) << "\n";
    return;
  }
  std::cout << fmt::format(
      "noise of run {} step {} ({}), {}: {} samples at {:.6g} Hz over {:.1f} s{}\n", r.run, r.step,
      r.step_label, r.device, r.samples, r.sample_rate_hz, r.duration_s,
      r.gaps ? fmt::format(", {} gaps in the device clock", r.gaps) : "");
  std::cout << "IEEE Std 952 terms fitted to the Allan variance (+- one sigma); '-': not resolved "
               "by the record.\nBias instability: the Allan minimum is what datasheets quote; "
               "B = minimum / 0.664 is the IEEE coefficient.\n";
  print_noise_table(r, true);
  print_noise_table(r, false);
  if (!models.empty()) print_model_figures(models);
  print_record_length(r);
  if (kalibr) {
    std::cout << fmt::format(
        "\nKalibr imu.yaml written to {} (estimators: gyroscope_noise_density {}, "
        "gyroscope_random_walk {}, accelerometer_noise_density {}, accelerometer_random_walk {})\n",
        a.kalibr, kalibr->gyroscope_noise_density_estimator,
        kalibr->gyroscope_random_walk_estimator, kalibr->accelerometer_noise_density_estimator,
        kalibr->accelerometer_random_walk_estimator);
  }
}

}  // namespace

void register_allan(CLI::App& app) {
  auto a = std::make_shared<AllanArgs>();
  CLI::App* cmd = app.add_subcommand(
      "allan",
      "Allan (or modified Allan, Hadamard) deviation of one channel with confidence intervals, "
      "and the noise terms fitted to it");
  cmd->add_option("--db", a->db, "SQLite database file")->type_name("FILE");
  cmd->add_option("--run", a->run, "run id")->type_name("ID");
  cmd->add_option("--step", a->step, "step index (default: the longest static capture)")
      ->type_name("N");
  cmd->add_option("--channel", a->channel, "gx gy gz [deg/s] or ax ay az [m/s^2]")
      ->type_name("NAME");
  cmd->add_option("--device", a->device, "IMU name (default: the first with samples)")
      ->type_name("NAME");
  cmd->add_option("--csv", a->csv, "CSV file with a header line, instead of --db")
      ->type_name("FILE");
  cmd->add_option("--column", a->column, "CSV column")->type_name("NAME");
  cmd->add_option("--rate", a->rate, "CSV sample rate [Hz]")->type_name("HZ");
  cmd->add_option("--units", a->units,
                  "unit of the CSV column, labelling the output; deg/s, rad/s (gyro), m/s^2 "
                  "or g (accelerometer) also give the datasheet figures (ARW, bias instability, "
                  "...)")
      ->type_name("UNIT");
  cmd->add_option("--taus", a->taus,
                  "octave, decade, dense or a list of seconds (1,10,100); octave adev, ohdev "
                  "and mdev are streamed in constant memory (a day at 1 kHz), the rest hold "
                  "the record in memory")
      ->capture_default_str();
  cmd->add_option("--kind", a->kind,
                  "adev (overlapping), mdev, ohdev (overlapping Hadamard), hdev (Hadamard); "
                  "totdev, mtotdev, ttotdev, htotdev (total); theo1, theobr, theoh (Theo taus "
                  "are 0.75 m tau0); the total and Theo kinds reflect the whole record, so "
                  "they hold it in memory")
      ->capture_default_str();
  cmd->add_option("--alpha", a->alpha,
                  "power-law noise exponent for the intervals and bias corrections (2 white PM "
                  "... -2 random-walk FM, -4 for htotdev); default: identified at each tau")
      ->type_name("A");
  cmd->add_flag("--no-bias-correction", a->no_bias_correction,
                "total and Theo kinds: the raw estimator, without Stable32's bias corrections");
  cmd->add_option("--confidence", a->confidence, "two-sided probability of the intervals")
      ->capture_default_str();
  cmd->add_flag("--json", a->json, "print the result as JSON");
  cmd->callback([a] { run_allan(*a); });

  auto id = std::make_shared<NoiseIdArgs>();
  CLI::App* noise_id = app.add_subcommand(
      "noise-id",
      "Composite noise model of a static record (white, quantization, flicker, one or two "
      "Gauss-Markov, random walk, ramp) by the GMWM, with model selection and 95 % intervals "
      "(docs/noise-id.md)");
  noise_id->add_option("--db", id->db, "SQLite database file")->type_name("FILE");
  noise_id->add_option("--run", id->run, "run id")->type_name("ID");
  noise_id->add_option("--step", id->step, "step index (default: the longest static capture)")
      ->type_name("N");
  noise_id->add_option("--channel", id->channel, "gx gy gz [deg/s] or ax ay az [m/s^2]")
      ->type_name("NAME");
  noise_id->add_option("--device", id->device, "IMU name (default: the first with samples)")
      ->type_name("NAME");
  noise_id->add_option("--csv", id->csv, "CSV file with a header line, instead of --db")
      ->type_name("FILE");
  noise_id->add_option("--column", id->column, "CSV column")->type_name("NAME");
  noise_id->add_option("--rate", id->rate, "CSV sample rate [Hz]")->type_name("HZ");
  noise_id
      ->add_option("--units", id->units,
                   "unit of the CSV column: deg/s, rad/s, m/s^2 or g also give datasheet "
                   "figures")
      ->type_name("UNIT");
  noise_id
      ->add_option("--bootstrap", id->bootstrap,
                   "parametric-bootstrap records for the intervals (0: the asymptotic "
                   "intervals, the record streamed in constant memory; else at least 20, "
                   "simulated whole, the record held in memory)")
      ->capture_default_str();
  noise_id
      ->add_option("--min-tau", id->min_tau,
                   "leave out the scales whose averaging time is below this [s] (a sensor's "
                   "output low-pass)")
      ->type_name("S")
      ->capture_default_str();
  noise_id->add_flag("--json", id->json, "print the result as JSON");
  noise_id->callback([id] { run_noise_id(*id); });

  auto n = std::make_shared<NoiseArgs>();
  CLI::App* noise = app.add_subcommand(
      "noise",
      "Noise terms of a run's static step for all six channels, in datasheet units (ARW "
      "deg/sqrt(h), bias instability deg/h and ug, RRW deg/h/sqrt(h), VRW m/s/sqrt(h))");
  noise->add_option("--db", n->db, "SQLite database file")->type_name("FILE");
  noise->add_option("--run", n->run, "run id")->type_name("ID");
  noise->add_option("--device", n->device, "IMU name (default: the first with samples)")
      ->type_name("NAME");
  noise->add_option("--step", n->step, "step index (default: the longest static capture)")
      ->type_name("N");
  noise
      ->add_option("--taus", n->taus, "averaging times of the fit: octave, decade, dense or a list")
      ->capture_default_str();
  noise->add_option("--kalibr", n->kalibr, "also write the figures as a Kalibr imu.yaml")
      ->type_name("FILE");
  noise->add_option("--rostopic", n->rostopic, "rostopic of the Kalibr file")
      ->capture_default_str();
  noise->add_flag("--no-noise-model", n->no_noise_model,
                  "skip the composite noise model (GMWM, about 1 s per channel and 2^19 "
                  "samples): Allan-line figures only");
  noise->add_flag("--json", n->json, "print the result as JSON");
  noise->callback([n] { run_noise(*n); });
}

}  // namespace calstand::cli
