#pragma once
// `calstand noise-id --json`: an identified composite noise model (solver/composite_noise.hpp)
// as the JSON issue 33 specifies, every parameter with its 95 % interval and its unit written out.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "noise/composite_noise.hpp"
#include "noise/model_figures.hpp"

namespace calstand::analysis {

/// The unit of each parameter of `kind` for data in `unit` (e.g. "deg/s"): white "density"
/// [unit/sqrt(Hz)], quantization "q" [unit*s], flicker "bias_instability" [unit], gauss_markov
/// "sigma" [unit] and "tau_s" [s], random_walk "density" [unit/sqrt(s)], drift "ramp" [unit/s].
std::string noise_parameter_name(solver::NoiseKind kind);
std::string noise_parameter_unit(solver::NoiseKind kind, const std::string& unit);

/// {"source", "unit", "sample_rate_hz", "samples", "estimator", "terms": [{"kind",
/// "parameters": {NAME: {"value", "ci95": [lo, hi], "unit"}}}], "selected_by", "candidates":
/// [{"terms", "parameters", "objective", "criterion", "admissible", "selected"}],
/// "wavelet_variance": {"tau_s", "measured", "fitted", "unit"}}.
nlohmann::ordered_json noise_model_json(const solver::NoiseModel& model, const std::string& source,
                                        const std::string& unit);

/// One channel's figures from its identified model or the Allan line (solver::model_figures()):
/// {"noise_model": {"estimator", "min_tau_s", "selected_by", "terms": [kind...]} or null,
/// "noise_model_note": why there is none (absent when there is one), "model_figures": [{"name",
/// "value", "ci95": [lo, hi], "unit", "estimator": "gmwm"|"allan-line", "resolved", "note"
/// (allan-line only)}]}.
nlohmann::ordered_json channel_model_figures_json(const solver::ChannelModelFigures& m);

/// The "model_figures" array of channel_model_figures_json() read back (a calibration record
/// keeps it, analysis::calibration_noise_figures()): null values and interval ends as NaN.
/// Throws core::InputError naming `where`[i] and the field when an entry is not an object, or
/// its name, value, unit or estimator is missing or of the wrong type.
std::vector<solver::ModelFigure> model_figures_from_json(const nlohmann::json& figures,
                                                         const std::string& where);

}  // namespace calstand::analysis
