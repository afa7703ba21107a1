#include "analysis/noise_json.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <span>

#include "analysis/noise_model_json.hpp"
#include "core/error.hpp"
#include "core/units.hpp"

namespace calstand::analysis {
namespace {

using Json = nlohmann::ordered_json;

// How much shorter than kMinNoiseRecordS a record may span (see long_enough_for_noise()).
constexpr double kRecordSlack = 0.01;

Json noise_term_json(const solver::NoiseTerm& t, const std::string& unit) {
  return {{"value", t.value}, {"sigma", t.sigma}, {"resolved", t.resolved}, {"unit", unit}};
}

}  // namespace

bool long_enough_for_noise(double duration_s) {
  return duration_s >= kMinNoiseRecordS * (1.0 - kRecordSlack);
}

Json noise_terms_json(const solver::NoiseTerms& t, const std::string& u) {
  Json j;
  j["quantization"] = noise_term_json(t.quantization, u + "*s");
  j["random_walk"] = noise_term_json(t.random_walk, u + "/sqrt(Hz)");
  j["bias_instability"] = noise_term_json(t.bias_instability, u);
  j["rate_random_walk"] = noise_term_json(t.rate_random_walk, u + "/sqrt(s)");
  j["rate_ramp"] = noise_term_json(t.rate_ramp, u + "/s");
  j["min_deviation"] = t.min_deviation;
  j["min_tau_s"] = t.min_tau_s;
  j["bias_instability_from_min"] = t.bias_instability_from_min;
  j["chi2_dof"] = t.chi2_dof;
  j["unit"] = u;
  return j;
}

Json datasheet_figures_json(const std::vector<solver::DatasheetFigure>& figures) {
  Json a = Json::array();
  for (const auto& f : figures) {
    a.push_back({{"name", f.name},
                 {"label", f.label},
                 {"value", f.value},
                 {"sigma", std::isfinite(f.sigma) ? Json(f.sigma) : Json()},
                 {"unit", f.unit},
                 {"resolved", f.resolved}});
  }
  return a;
}

Json run_noise_json(const solver::RunNoise& r) {
  Json out;
  out["run"] = r.run;
  out["device"] = r.device;
  out["step"] = r.step;
  out["step_label"] = r.step_label;
  out["samples"] = r.samples;
  out["sample_rate_hz"] = r.sample_rate_hz;
  out["duration_s"] = r.duration_s;
  out["gaps"] = r.gaps;
  Json chans = Json::array();
  for (const auto& c : r.channels) {
    const std::string unit(solver::channel_unit(c.channel));
    // Every figure here is the Allan curve's: fitted lines, or read off its minimum.
    Json figures = datasheet_figures_json(c.figures);
    for (std::size_t i = 0; i < figures.size() && i < c.figures.size(); ++i) {
      figures[i]["estimator"] = std::isfinite(c.figures[i].sigma) ? "allan-line" : "allan-minimum";
    }
    chans.push_back({{"channel", std::string(solver::to_string(c.channel))},
                     {"unit", unit},
                     {"figures", figures},
                     {"terms", noise_terms_json(c.terms, unit)}});
  }
  out["channels"] = chans;
  return out;
}

std::optional<DatasheetUnit> datasheet_unit(const std::string& unit) {
  constexpr double kDegPerRad = 57.29577951308232;
  constexpr double kG0 = 9.80665;
  if (unit == "deg/s") return DatasheetUnit{true, 1.0};
  if (unit == "rad/s") return DatasheetUnit{true, kDegPerRad};
  if (unit == "m/s^2") return DatasheetUnit{false, 1.0};
  if (unit == "g") return DatasheetUnit{false, kG0};
  return std::nullopt;
}

solver::NoiseTerms scale_noise_terms(const solver::NoiseTerms& terms, double k) {
  solver::NoiseTerms t = terms;
  for (solver::NoiseTerm* term :
       {&t.quantization, &t.random_walk, &t.bias_instability, &t.rate_random_walk, &t.rate_ramp}) {
    term->value *= k;
    term->sigma *= k;
  }
  t.min_deviation *= k;
  t.bias_instability_from_min *= k;
  return t;
}

Json allan_json(const solver::AllanResult& r, const std::string& source, const std::string& key,
                const std::string& unit, double rate_hz,
                const std::optional<solver::NoiseTerms>& terms,
                std::optional<DatasheetUnit> datasheet) {
  Json out;
  out["source"] = source;
  out["kind"] = key;
  out["unit"] = unit;
  out["sample_rate_hz"] = rate_hz;
  out["samples"] = r.samples;
  out["confidence"] = r.confidence;
  Json tau = Json::array(), dev = Json::array(), lo = Json::array(), hi = Json::array(),
       edf = Json::array(), alpha = Json::array();
  for (const auto& p : r.points) {
    tau.push_back(p.tau_s);
    dev.push_back(p.deviation);
    lo.push_back(p.lo);
    hi.push_back(p.hi);
    edf.push_back(p.edf);
    alpha.push_back(p.alpha);
  }
  out["tau"] = tau;
  out[key] = dev;
  out[key + "_lo"] = lo;
  out[key + "_hi"] = hi;
  out["edf"] = edf;
  out["alpha"] = alpha;
  if (terms) {
    Json noise = noise_terms_json(*terms, unit);
    if (datasheet) {
      noise["datasheet"] = datasheet_figures_json(solver::datasheet_figures(
          scale_noise_terms(*terms, datasheet->to_base), datasheet->gyro));
    }
    out["noise"] = noise;
  } else {
    out["noise"] = nullptr;
  }
  return out;
}

nlohmann::json calibration_noise_figures(store::Database& db, std::int64_t run,
                                         const std::string& device) {
  solver::RunNoiseOptions options;
  options.device = device;
  solver::RunNoise noise;
  try {
    noise = solver::analyse_run_noise(db, run, options);
  } catch (const core::InputError&) {
    return nullptr;  // no static capture
  }
  if (!long_enough_for_noise(noise.duration_s)) return nullptr;
  nlohmann::json j = {{"step", noise.step},
                      {"duration_s", noise.duration_s},
                      {"sample_rate_hz", noise.sample_rate_hz},
                      {"channels", nlohmann::json::object()}};
  for (const auto& c : noise.channels) {
    nlohmann::json figures = nlohmann::json::array();
    for (const auto& f : c.figures) {
      figures.push_back(
          {{"name", f.name},
           {"value", f.value},
           {"sigma", std::isfinite(f.sigma) ? nlohmann::json(f.sigma) : nlohmann::json()},
           {"unit", f.unit},
           {"resolved", f.resolved}});
    }
    j["channels"][std::string(solver::to_string(c.channel))] = figures;
  }
  // The identified models' figures beside the Allan line's: the Kalibr and OpenVINS exports
  // prefer them (issue 33), acceptance keeps reading "channels".
  nlohmann::json models = nlohmann::json::object();
  for (const solver::ChannelModelFigures& m : solver::channel_noise_models(db, noise)) {
    models[std::string(solver::to_string(m.channel))] =
        nlohmann::json(channel_model_figures_json(m).at("model_figures"));
  }
  j["model_figures"] = models;
  return j;
}

std::optional<solver::RunNoise> calibration_noise_terms(const nlohmann::json& noise) {
  if (!noise.is_object()) return std::nullopt;
  // The figures' units say how to go back: N in the data's unit times sqrt(s), K in the data's
  // unit per sqrt(s) (solver::NoiseTerms), whatever datasheet unit the record used.
  struct Wanted {
    const char* figure;
    const char* unit;
    solver::NoiseTerm solver::NoiseTerms::*term;
  };
  constexpr Wanted kGyro[] = {
      {"angle_random_walk", "deg/sqrt(s)", &solver::NoiseTerms::random_walk},
      {"rate_random_walk", "deg/s/sqrt(s)", &solver::NoiseTerms::rate_random_walk}};
  constexpr Wanted kAccel[] = {
      {"velocity_random_walk", "m/s/sqrt(s)", &solver::NoiseTerms::random_walk},
      {"acceleration_random_walk", "m/s^2/sqrt(s)", &solver::NoiseTerms::rate_random_walk}};
  solver::RunNoise out;
  out.sample_rate_hz = noise.value("sample_rate_hz", 0.0);
  const nlohmann::json channels = noise.value("channels", nlohmann::json::object());
  for (const solver::ImuChannel c : solver::kAllChannels) {
    const std::string name(solver::to_string(c));
    solver::ChannelNoise ch;
    ch.channel = c;
    for (const Wanted& w :
         solver::is_gyro(c) ? std::span<const Wanted>(kGyro) : std::span<const Wanted>(kAccel)) {
      const std::string where = "noise.channels." + name + ": " + w.figure;
      const nlohmann::json figures = channels.value(name, nlohmann::json::array());
      const auto f = std::find_if(figures.begin(), figures.end(), [&](const nlohmann::json& j) {
        return j.is_object() && j.value("name", "") == w.figure;
      });
      if (f == figures.end() || !f->contains("value") || !(*f)["value"].is_number()) {
        throw core::InputError(where, "missing from the record's noise figures");
      }
      double value = 0.0;
      try {
        value = core::convert((*f)["value"].get<double>(), f->value("unit", std::string()), w.unit);
      } catch (const core::InputError& e) {
        throw core::InputError(where, e.what());
      }
      ch.terms.*w.term = {value, 0.0, f->value("resolved", true)};
    }
    out.channels.push_back(std::move(ch));
  }
  return out;
}

std::optional<std::vector<solver::ChannelModelFigures>> calibration_noise_models(
    const nlohmann::json& noise) {
  if (!noise.is_object() || !noise.contains("model_figures")) return std::nullopt;
  const nlohmann::json& channels = noise["model_figures"];
  if (!channels.is_object()) throw core::InputError("noise.model_figures", "must be an object");
  std::vector<solver::ChannelModelFigures> out;
  for (const solver::ImuChannel c : solver::kAllChannels) {
    const std::string name(solver::to_string(c));
    const std::string where = "noise.model_figures." + name;
    if (!channels.contains(name)) throw core::InputError(where, "missing");
    solver::ChannelModelFigures m;
    m.channel = c;
    m.figures = model_figures_from_json(channels[name], where);
    // The export takes N and K in the data's unit; a record states each figure's unit.
    const std::string u(solver::channel_unit(c));
    for (solver::ModelFigure& f : m.figures) {
      std::string unit;
      if (f.name == "white_density") unit = u + "/sqrt(Hz)";
      if (f.name == "random_walk") unit = u + "/sqrt(s)";
      if (unit.empty() || f.unit == unit) continue;
      try {
        for (double* v : {&f.value, &f.lo, &f.hi}) {
          if (std::isfinite(*v)) *v = core::convert(*v, f.unit, unit);
        }
      } catch (const core::InputError& e) {
        throw core::InputError(where + ": " + f.name, e.what());
      }
      f.unit = unit;
    }
    out.push_back(std::move(m));
  }
  return out;
}

nlohmann::ordered_json record_length_json(const solver::RunNoise& noise,
                                          const solver::RecordLengthRule& rule) {
  nlohmann::ordered_json j;
  j["record_length_s"] = noise.duration_s;
  j["rule"] = {
      {"confidence", rule.confidence},
      {"half_width", rule.half_width},
      {"required_edf", solver::required_edf(rule)},
      {"text", fmt::format("the {:.0f} % confidence interval of the Allan deviation at the "
                           "figure's tau within +-{:.0f} %",
                           100.0 * rule.confidence, 100.0 * rule.half_width)}};
  for (const solver::FigureRecordNeed& n : solver::record_length_needs(noise, rule)) {
    j[n.gyro ? "gyro" : "accel"][n.figure] = {{"tau_s", n.tau_s},
                                              {"alpha", n.alpha},
                                              {"channel", n.channel},
                                              {"needed_s", n.needed_s},
                                              {"record_length_s", n.record_length_s},
                                              {"enough", n.enough},
                                              {"located", n.located}};
  }
  return j;
}

}  // namespace calstand::analysis
