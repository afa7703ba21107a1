// An identified composite noise model as JSON (calstand noise-id --json).
#include "analysis/noise_model_json.hpp"

#include <cmath>
#include <limits>

#include "core/error.hpp"

namespace calstand::analysis {
namespace {

using Json = nlohmann::ordered_json;

// NaN (an interval the bootstrap could not give) as JSON null.
Json number(double v) { return std::isfinite(v) ? Json(v) : Json(nullptr); }

Json parameter(double value, double lo, double hi, const std::string& unit) {
  Json p;
  p["value"] = number(value);
  p["ci95"] = Json::array({number(lo), number(hi)});
  p["unit"] = unit;
  return p;
}

}  // namespace

std::string noise_parameter_name(solver::NoiseKind kind) {
  switch (kind) {
    case solver::NoiseKind::kWhite:
    case solver::NoiseKind::kRandomWalk:
      return "density";
    case solver::NoiseKind::kQuantization:
      return "q";
    case solver::NoiseKind::kFlicker:
      return "bias_instability";
    case solver::NoiseKind::kGaussMarkov:
      return "sigma";
    case solver::NoiseKind::kDrift:
      return "ramp";
  }
  return "value";
}

std::string noise_parameter_unit(solver::NoiseKind kind, const std::string& unit) {
  switch (kind) {
    case solver::NoiseKind::kWhite:
      return unit + "/sqrt(Hz)";
    case solver::NoiseKind::kQuantization:
      return unit + "*s";
    case solver::NoiseKind::kRandomWalk:
      return unit + "/sqrt(s)";
    case solver::NoiseKind::kDrift:
      return unit + "/s";
    default:
      return unit;
  }
}

Json noise_model_json(const solver::NoiseModel& model, const std::string& source,
                      const std::string& unit) {
  Json out;
  out["source"] = source;
  out["unit"] = unit;
  out["sample_rate_hz"] = model.sample_rate_hz;
  out["samples"] = model.samples;
  out["estimator"] = model.estimator;
  Json terms = Json::array();
  for (const auto& t : model.terms) {
    Json term;
    term["kind"] = std::string(solver::to_string(t.kind));
    Json params;
    params[noise_parameter_name(t.kind)] =
        parameter(t.value, t.value_lo, t.value_hi, noise_parameter_unit(t.kind, unit));
    if (t.kind == solver::NoiseKind::kGaussMarkov) {
      params["tau_s"] = parameter(t.tau_s, t.tau_lo_s, t.tau_hi_s, "s");
    }
    term["parameters"] = params;
    terms.push_back(term);
  }
  out["terms"] = terms;
  out["selected_by"] = model.selected_by;
  Json candidates = Json::array();
  for (const auto& c : model.candidates) {
    Json j;
    Json names = Json::array();
    for (auto k : c.kinds) names.push_back(std::string(solver::to_string(k)));
    j["terms"] = names;
    j["parameters"] = c.parameters;
    j["objective"] = number(c.objective);
    j["criterion"] = number(c.criterion);
    j["admissible"] = c.admissible;
    j["selected"] = c.selected;
    candidates.push_back(j);
  }
  out["candidates"] = candidates;
  Json wv;
  Json tau = Json::array(), measured = Json::array(), fitted = Json::array();
  for (std::size_t j = 0; j < model.moments.m.size(); ++j) {
    tau.push_back(2.0 * static_cast<double>(model.moments.m[j]) / model.sample_rate_hz);
    measured.push_back(model.moments.variance[j]);
    fitted.push_back(model.fitted[j]);
  }
  wv["tau_s"] = tau;  // the Haar scale 2 m tau0
  wv["measured"] = measured;
  wv["fitted"] = fitted;
  wv["unit"] = "(" + unit + ")^2";
  out["wavelet_variance"] = wv;
  return out;
}

Json channel_model_figures_json(const solver::ChannelModelFigures& m) {
  Json out;
  if (m.model) {
    Json kinds = Json::array();
    for (const auto& t : m.model->terms) kinds.push_back(std::string(solver::to_string(t.kind)));
    out["noise_model"] = {{"estimator", m.model->estimator},
                          {"min_tau_s", m.min_tau_s},
                          {"selected_by", m.model->selected_by},
                          {"terms", kinds}};
  } else {
    out["noise_model"] = nullptr;
    out["noise_model_note"] = m.note;
  }
  Json figures = Json::array();
  for (const solver::ModelFigure& f : m.figures) {
    Json j;
    j["name"] = f.name;
    j["value"] = number(f.value);
    j["ci95"] = Json::array({number(f.lo), number(f.hi)});
    j["unit"] = f.unit;
    j["estimator"] = f.estimator;
    j["resolved"] = f.resolved;
    if (!f.note.empty()) j["note"] = f.note;
    figures.push_back(j);
  }
  out["model_figures"] = figures;
  return out;
}

std::vector<solver::ModelFigure> model_figures_from_json(const nlohmann::json& figures,
                                                         const std::string& where) {
  if (!figures.is_array()) throw core::InputError(where, "must be an array of figures");
  constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
  // A number, or null for one the model could not give (NaN as the writer's number() makes).
  const auto number_or_null = [](const nlohmann::json& j, const std::string& at) {
    if (j.is_null()) return kNaN;
    if (!j.is_number()) throw core::InputError(at, "must be a number or null");
    return j.get<double>();
  };
  std::vector<solver::ModelFigure> out;
  for (std::size_t i = 0; i < figures.size(); ++i) {
    const nlohmann::json& f = figures[i];
    const std::string at = where + "[" + std::to_string(i) + "]";
    if (!f.is_object()) throw core::InputError(at, "must be an object");
    for (const char* key : {"name", "unit", "estimator"}) {
      if (!f.contains(key) || !f[key].is_string()) {
        throw core::InputError(at + "." + key, "missing or not a string");
      }
    }
    if (!f.contains("value")) throw core::InputError(at + ".value", "missing");
    solver::ModelFigure m;
    m.name = f["name"].get<std::string>();
    m.unit = f["unit"].get<std::string>();
    m.estimator = f["estimator"].get<std::string>();
    m.value = number_or_null(f["value"], at + ".value");
    m.lo = m.hi = kNaN;
    if (f.contains("ci95")) {
      const nlohmann::json& ci = f["ci95"];
      if (!ci.is_array() || ci.size() != 2) {
        throw core::InputError(at + ".ci95", "must be [lo, hi]");
      }
      m.lo = number_or_null(ci[0], at + ".ci95[0]");
      m.hi = number_or_null(ci[1], at + ".ci95[1]");
    }
    if (f.contains("resolved") && !f["resolved"].is_boolean()) {
      throw core::InputError(at + ".resolved", "must be true or false");
    }
    m.resolved = f.value("resolved", true);
    m.note = f.value("note", std::string());
    out.push_back(std::move(m));
  }
  return out;
}

}  // namespace calstand::analysis
