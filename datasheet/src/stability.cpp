#include "datasheet/stability.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "analysis/noise_json.hpp"
#include "analysis/noise_model_json.hpp"
#include "core/error.hpp"
#include "datasheet_units.hpp"
#include "noise/run_noise.hpp"

namespace calstand::analysis {
namespace {

/// IEEE 952: the flicker floor of the Allan deviation is 0.664 B.
constexpr double kFlickerFloor = 0.664;
/// Degrees of freedom a point needs to count for the minimum: about +-22 % on the deviation at
/// one sigma (solver::NoiseTerms reads its minimum so too).
constexpr double kMinFloorEdf = 10.0;

}  // namespace

StabilityAnalysis analyse_stability(store::Database& db, std::int64_t run,
                                    const std::string& device, std::optional<std::size_t> step,
                                    bool noise_model) {
  solver::RunNoiseOptions options;
  options.device = device;
  options.step = step;
  const solver::RunNoise noise = solver::analyse_run_noise(db, run, options);
  StabilityAnalysis out = stability_of(noise, options.min_tau_samples);
  if (noise_model) out.models = solver::channel_noise_models(db, noise);
  return out;
}

StabilityAnalysis stability_of(const solver::RunNoise& noise, double min_tau_samples) {
  if (!long_enough_for_noise(noise.duration_s)) {
    throw core::InputError(
        fmt::format("run {} step {}", noise.run, noise.step),
        fmt::format("the capture lasts {:.0f} s; a bias floor and a correlation time need a "
                    "static record of at least {:.0f} s",
                    noise.duration_s, kMinNoiseRecordS));
  }
  StabilityAnalysis out;
  out.run = noise.run;
  out.device = noise.device;
  out.step = noise.step;
  out.step_label = noise.step_label;
  out.duration_s = noise.duration_s;
  for (std::size_t c = 0; c < noise.channels.size() && c < out.channels.size(); ++c) {
    const solver::ChannelNoise& ch = noise.channels[c];
    const double k = c < 3 ? kDegPerSToDegPerH : kMps2ToUg;
    ChannelStability& s = out.channels[c];
    s.channel = std::string(solver::to_string(ch.channel));
    const auto& points = ch.allan.points;
    out.confidence = ch.allan.confidence;
    // The minimum among the points with at least kMinFloorEdf degrees of freedom (their own,
    // from the curve's local noise type), or of all when none has: the last few points scatter
    // by a factor of two and more, and their lowest would be a minimum of the noise, biased
    // low, whose interval need not hold the floor (a 700 s record's last point, 1.1 EDF, read
    // a gyro's curve 6 times below the line of the points before it). Which point that is may
    // change with one point's EDF crossing 10; whether a floor was seen does not (below).
    const bool any_firm =
        std::any_of(points.begin(), points.end(),
                    [](const solver::AllanPoint& p) { return p.edf >= kMinFloorEdf; });
    auto floor = points.end();
    for (auto it = points.begin(); it != points.end(); ++it) {
      if (any_firm && !(it->edf >= kMinFloorEdf)) continue;
      if (floor == points.end() || it->deviation < floor->deviation) floor = it;
    }
    if (floor != points.end()) {
      s.bias_instability = k * floor->deviation / kFlickerFloor;
      s.bias_instability_lo = k * floor->lo / kFlickerFloor;
      s.bias_instability_hi = k * floor->hi / kFlickerFloor;
      s.min_tau_s = floor->tau_s;
      // A floor is where the curve turns up again and stays up: a later point whose interval
      // lies wholly above the minimum's, and after it no point reading lower than the minimum,
      // whatever its degrees of freedom. A minimum at (or near) the last averaging times that
      // noise alone put there is not one, nor is the dip before a Gauss-Markov bias's Allan
      // bump when the curve comes down below it again after the bump: the figure is then only
      // a bound. So the verdict does not turn on whether a late point has 7.9 or 10.2 EDF (the
      // noise type lag-1 carries there, or the one its slope shows): below 10 it is left out of
      // the minimum, and the minimum before the bump that it undercuts is no floor; above, it is
      // the minimum, and nothing after it lies wholly above. Points between the minimum and the
      // rise (a flat flicker floor's scatter) do not count against it.
      const auto rise = std::find_if(floor + 1, points.end(),
                                     [&](const solver::AllanPoint& p) { return p.lo > floor->hi; });
      s.floor_resolved = rise != points.end() &&
                         std::none_of(rise + 1, points.end(), [&](const solver::AllanPoint& p) {
                           return p.deviation < floor->deviation;
                         });
    }
    // As the noise-term fit: without the shortest averaging times, where the IMU's
    // anti-aliasing filter lowers the curve and a vanishing correlation time would fit it.
    solver::BiasModelOptions model_options;
    model_options.min_tau_s = min_tau_samples / noise.sample_rate_hz;
    const solver::BiasModelChoice choice = solver::choose_bias_model(ch.allan, model_options);
    s.bias_model = choice.model;
    s.bias_model_reason = choice.reason;
    s.bias_model_aic_difference = choice.aic_difference;
    if (choice.model == solver::BiasModel::kGaussMarkov) {
      const solver::GaussMarkovFit& gm = choice.gauss_markov;
      s.variation_sigma = k * gm.sigma;
      s.correlation_time_s = gm.tau_c_s;
      s.correlation_resolved = gm.peak_in_range && 1.89 * gm.tau_c_s >= model_options.min_tau_s;
    }
    if (choice.model == solver::BiasModel::kFlicker) {
      s.flicker_b = k * choice.flicker.bias_instability.value;
      s.flicker_b_sigma = k * choice.flicker.bias_instability.sigma;
    }
  }
  return out;
}

nlohmann::json to_json(const StabilityAnalysis& s) {
  // The model's figures of channels first .. first + 2 in datasheet units: a flicker term's B,
  // the Gauss-Markov term of longest correlation time; null where the model has none.
  const auto model_keys = [&](nlohmann::json& out, std::size_t first, const char* unit) {
    nlohmann::json b = nlohmann::json::array(), b_ci = nlohmann::json::array();
    nlohmann::json gm = nlohmann::json::array(), gm_ci = nlohmann::json::array();
    nlohmann::json tau = nlohmann::json::array(), tau_ci = nlohmann::json::array();
    nlohmann::json note = nlohmann::json::array();
    for (std::size_t c = first; c < first + 3; ++c) {
      const solver::ChannelModelFigures& m = s.models[c];
      const double k = c < 3 ? kDegPerSToDegPerH : kMps2ToUg;
      const solver::ModelFigure* flicker = nullptr;
      const solver::ModelFigure* sigma = nullptr;
      const solver::ModelFigure* tau_c = nullptr;
      for (const solver::ModelFigure& f : m.figures) {
        if (f.estimator != solver::kGmwmEstimator) continue;
        if (f.name == "bias_instability") flicker = &f;
        if (f.name == "gauss_markov_sigma") sigma = &f;  // sorted by tau: the last is the longest
        if (f.name == "gauss_markov_tau") tau_c = &f;
      }
      const auto put = [&](nlohmann::json& v, nlohmann::json& ci, const solver::ModelFigure* f,
                           double scale) {
        v.push_back(f ? nlohmann::json(scale * f->value) : nlohmann::json(nullptr));
        ci.push_back(f ? nlohmann::json::array({scale * f->lo, scale * f->hi})
                       : nlohmann::json(nullptr));
      };
      put(b, b_ci, flicker, k);
      put(gm, gm_ci, sigma, k);
      put(tau, tau_ci, tau_c, 1.0);
      note.push_back(m.model ? nlohmann::json(nullptr) : nlohmann::json(m.note));
    }
    out[fmt::format("bias_instability_model_{}", unit)] = b;
    out[fmt::format("bias_instability_model_interval_{}", unit)] = b_ci;
    out[fmt::format("bias_variation_model_{}", unit)] = gm;
    out[fmt::format("bias_variation_model_interval_{}", unit)] = gm_ci;
    out["correlation_time_model_s"] = tau;
    out["correlation_time_model_interval_s"] = tau_ci;
    out["model_note"] = note;
  };
  const auto optional = [](const std::optional<double>& v) {
    return v ? nlohmann::json(*v) : nlohmann::json(nullptr);
  };
  const auto sensor = [&](std::size_t first, const char* unit) {
    nlohmann::json bi = nlohmann::json::array();
    nlohmann::json interval = nlohmann::json::array();
    nlohmann::json tau = nlohmann::json::array();
    nlohmann::json sigma = nlohmann::json::array();
    nlohmann::json tau_c = nlohmann::json::array();
    nlohmann::json resolved = nlohmann::json::array();
    nlohmann::json floor_resolved = nlohmann::json::array();
    nlohmann::json model = nlohmann::json::array();
    nlohmann::json reason = nlohmann::json::array();
    nlohmann::json aic = nlohmann::json::array();
    nlohmann::json flicker_b = nlohmann::json::array();
    nlohmann::json flicker_b_sigma = nlohmann::json::array();
    for (std::size_t c = first; c < first + 3; ++c) {
      const ChannelStability& ch = s.channels[c];
      bi.push_back(ch.bias_instability);
      interval.push_back({ch.bias_instability_lo, ch.bias_instability_hi});
      tau.push_back(ch.min_tau_s);
      sigma.push_back(optional(ch.variation_sigma));
      tau_c.push_back(optional(ch.correlation_time_s));
      resolved.push_back(ch.correlation_resolved);
      floor_resolved.push_back(ch.floor_resolved);
      model.push_back(std::string(solver::to_string(ch.bias_model)));
      reason.push_back(ch.bias_model_reason);
      aic.push_back(ch.bias_model_aic_difference);
      flicker_b.push_back(optional(ch.flicker_b));
      flicker_b_sigma.push_back(ch.flicker_b ? nlohmann::json(ch.flicker_b_sigma)
                                             : nlohmann::json(nullptr));
    }
    nlohmann::json out{{fmt::format("bias_instability_{}", unit), bi},
                       {fmt::format("bias_instability_interval_{}", unit), interval},
                       {"floor_tau_s", tau},
                       {fmt::format("bias_variation_{}", unit), sigma},
                       {"correlation_time_s", tau_c},
                       {"correlation_resolved", resolved},
                       {"floor_resolved", floor_resolved},
                       {"bias_model", model},
                       {"bias_model_reason", reason},
                       {"bias_model_aic_difference", aic},
                       {fmt::format("bias_instability_fit_{}", unit), flicker_b},
                       {fmt::format("bias_instability_fit_sigma_{}", unit), flicker_b_sigma}};
    if (s.models.size() == s.channels.size()) model_keys(out, first, unit);
    return out;
  };
  nlohmann::json out{{"run", s.run},
                     {"device", s.device},
                     {"step", s.step},
                     {"step_label", s.step_label},
                     {"duration_s", s.duration_s},
                     {"confidence", s.confidence},
                     {"gyro", sensor(0, "deg_per_h")},
                     {"accel", sensor(3, "ug")}};
  if (s.models.empty()) {
    out["noise_models"] = nullptr;
    return out;
  }
  nlohmann::json estimators;
  for (const char* unit : {"deg_per_h", "ug"}) {
    estimators[fmt::format("bias_instability_{}", unit)] = "allan-floor";
    estimators[fmt::format("bias_variation_{}", unit)] = "allan-line";
    estimators[fmt::format("bias_instability_fit_{}", unit)] = "allan-line";
    estimators[fmt::format("bias_instability_model_{}", unit)] = "gmwm";
    estimators[fmt::format("bias_variation_model_{}", unit)] = "gmwm";
  }
  estimators["correlation_time_s"] = "allan-line";
  estimators["correlation_time_model_s"] = "gmwm";
  out["estimators"] = estimators;
  nlohmann::json models = nlohmann::json::array();
  for (const auto& m : s.models) {
    nlohmann::json j = nlohmann::json(channel_model_figures_json(m));
    j["channel"] = std::string(solver::to_string(m.channel));
    models.push_back(j);
  }
  out["noise_models"] = models;
  return out;
}

}  // namespace calstand::analysis
