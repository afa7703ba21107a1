#include "solver/noise_estimate.hpp"

#include <fmt/format.h>

#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.hpp"
#include "solver/noise_rows.hpp"
#include "wander_kernels.hpp"

namespace calstand::solver {
namespace {

// An independent extra variance per step must beat the best wander by this much penalised log
// likelihood (a BIC difference of 10: "very strong" on the Kass-Raftery scale) before the
// excess is called an effect rather than noise. Real wanders (flicker above all, whose fast
// components look nearly independent from step to step) come within a few units of it.
constexpr double kNotWanderMargin = 5.0;
// Penalised log likelihood within which flicker is preferred to another wander (see there).
constexpr double kCautiousFlickerMargin = 3.0;

using detail::ChannelProblem;
using detail::Kernel;
using detail::Likelihood;

/// The columns of `superset`'s parameters that `fit` determined.
std::vector<Eigen::Index> determined_columns(const Model& superset, const FitResult& fit) {
  std::vector<Eigen::Index> columns;
  const auto& all = superset.parameters();
  for (const FittedParameter& fp : fit.parameters) {
    const auto it = std::find_if(all.begin(), all.end(),
                                 [&](const ParameterInfo& q) { return q.name == fp.name; });
    if (it != all.end()) columns.push_back(it - all.begin());
  }
  return columns;
}

std::string describe(const WanderModel& w, int channel) {
  const bool gyro = channel < kAx;
  // Datasheet units: deg/h for a gyro bias, ug for an accelerometer's.
  const double to_sheet = gyro ? 3600.0 : 1e6 / 9.80665;
  const char* unit = gyro ? "deg/h" : "ug";
  switch (w.kind) {
    case WanderKind::kGaussMarkov:
      return fmt::format("Gauss-Markov bias {:.3g} {} with {:.3g} s correlation time",
                         w.sigma * to_sheet, unit, w.tau_s);
    case WanderKind::kFlicker:
      return fmt::format("bias instability (flicker) B {:.3g} {} (Allan floor {:.3g} {})",
                         w.flicker_b * to_sheet, unit, 0.664 * w.flicker_b * to_sheet, unit);
    case WanderKind::kRandomWalk:
      return fmt::format("{} random walk {:.3g} {}/sqrt(h)", gyro ? "rate" : "acceleration",
                         w.random_walk_k * to_sheet * 60.0, unit);
    case WanderKind::kSum: {
      std::string out;
      for (const WanderModel& p : w.parts) out += (out.empty() ? "" : " + ") + describe(p, channel);
      return out.empty() ? "no wandering bias" : out;
    }
    case WanderKind::kNone:
      return "no wandering bias";
  }
  return "";
}

// Order of the temperature polynomials in the noise superset.
constexpr int kNoiseSupersetTemperatureOrder = 3;

/// Why channel `c` gets no noise model in a fit of `rows` over `steps` ("" when it gets one).
std::string why_no_noise_model(const std::vector<StepSummary>& steps, SensorRows rows, int c) {
  if (rows != SensorRows::kBoth && (rows == SensorRows::kGyro) != (c < kAx)) {
    return "its sensor's rows are not part of this fit";
  }
  if (std::all_of(steps.begin(), steps.end(),
                  [&](const StepSummary& s) { return std::isnan(s.measured[c]); })) {
    return "the unit does not measure it (no step has a mean): its terms are not determined";
  }
  return "";
}

/// The white part from inside the steps and each channel's wander as measured elsewhere: the
/// white part alone beside a wander (it holds the rest of a block's scatter).
StepNoise with_known_wander(const std::vector<StepSummary>& steps, const NoiseFloor& white,
                            SensorRows rows, const KnownWander& known) {
  StepNoise noise = StepNoise::white_only(white, "");
  noise.method = fmt::format(
      "white noise from the scatter inside {} {}; wandering bias per channel from {} (not "
      "estimated from this run)",
      white.steps_used, white.from_static_steps ? "static steps" : "steps", known.source);
  const FlickerBand band = flicker_band(steps);
  for (int c = 0; c < kChannels; ++c) {
    ChannelStepNoise& ch = noise.channels[static_cast<std::size_t>(c)];
    ch.note = why_no_noise_model(steps, rows, c);
    if (!ch.note.empty()) continue;
    ch.determined = true;
    ch.wander = spread_over(known.wander[static_cast<std::size_t>(c)], band);
    ch.source = known.source;
    // No wander beside it: the steps' own scatter at a tenth of a step, as where a run shows none.
    if (ch.wander.kind == WanderKind::kNone) noise.white.density[c] = white.batch_density[c];
    ch.note = describe(ch.wander, c);
  }
  return noise;
}

}  // namespace

Model noise_superset(const Model& model) {
  Model m = model;
  for (const auto& info : core::error_term_catalogue()) {
    const ModelTerm* present = model.find(info.name);
    if (present && !info.polynomial_order) continue;
    // Temperature polynomials to a fixed order beyond the model's (the fit drops the orders
    // the run's plateaus cannot determine), so that every model of the same run, and every
    // candidate diagnose tries, is weighed with one noise model.
    const int order = info.polynomial_order ? std::max(kNoiseSupersetTemperatureOrder,
                                                       present ? present->order + 1 : 1)
                                            : 1;
    m = m.with_term(info, order);
  }
  return m;
}

StepNoise estimate_step_noise(const std::vector<StepSummary>& steps, const Model& superset,
                              SensorRows rows, const NoiseEstimateOptions& options) {
  const NoiseFloor white = measure_noise_floor(steps);
  // Without a wander model the weights are the steps' own scatter at a tenth of a step (the
  // batch means), wander included at that block length: the white part alone would make a
  // step mean far surer than it is wherever the bias wanders (a flicker floor 15 times the
  // white noise at 6 s, an ADIS16488-class accelerometer's).
  NoiseFloor batch = white;
  batch.density = white.batch_density;
  if (!options.estimate_wander) {
    return StepNoise::white_only(
        batch, "white noise inside the steps only (wander not estimated, as asked)");
  }
  if (options.known_wander) return with_known_wander(steps, white, rows, *options.known_wander);
  FitOptions fo;
  fo.rows = rows;
  FitResult fit;
  bool fitted = true;
  try {
    fit = fit_model(steps, superset, white, fo);
  } catch (const core::InputError&) {
    fitted = false;  // more catalogue parameters than step means: no room to see a wander
  }
  StepNoise noise = StepNoise::white_only(white, "");
  // A channel keeps the white part of the floor only where a wander is estimated beside it.
  const auto without_wander = [&](int c) { noise.white.density[c] = white.batch_density[c]; };
  if (!fitted) {
    noise.method = fmt::format(
        "white noise from the scatter inside {} {} only: the run's {} step means are too few "
        "for every catalogue term, so a wandering bias cannot be told from a missing effect",
        white.steps_used, white.from_static_steps ? "static steps" : "steps", steps.size());
  } else {
    noise.method = fmt::format(
        "white noise from the scatter inside {} {}; wandering bias per channel by restricted "
        "likelihood of the {} step means' residuals after every catalogue term",
        white.steps_used, white.from_static_steps ? "static steps" : "steps", steps.size());
  }

  const detail::WanderKernels kernels = detail::make_wander_kernels(steps);
  const std::vector<Eigen::Index> columns = determined_columns(superset, fit);

  for (int c = 0; c < kChannels; ++c) {
    ChannelStepNoise& ch = noise.channels[static_cast<std::size_t>(c)];
    ch.note = why_no_noise_model(steps, rows, c);
    if (!ch.note.empty()) continue;
    if (!fitted) {
      ch.note =
          "the run has fewer step means than the catalogue has parameters: the wander "
          "cannot be told from a missing effect; weights from the scatter inside the steps";
      ch.too_few_steps = true;
      without_wander(c);
      continue;
    }
    const ChannelProblem p = detail::channel_problem(steps, columns, c, white.density[c]);
    const int dof = static_cast<int>(steps.size()) - p.parameters;
    if (dof < options.min_dof) {
      ch.note = fmt::format(
          "{} step means leave {} degrees of freedom beyond the {} parameters "
          "acting on {} (at least {} needed to see a wandering bias); weights "
          "from the scatter inside the steps",
          steps.size(), dof, p.parameters, channel_name(c), options.min_dof);
      ch.too_few_steps = true;
      without_wander(c);
      continue;
    }
    const double white_ll = detail::white_log_likelihood(p, Likelihood::kRestricted);
    const double penalty_per_parameter = 0.5 * std::log(static_cast<double>(dof));
    double best_score = white_ll;
    WanderModel best;
    WanderModel flicker_fit;
    double flicker_score = -std::numeric_limits<double>::infinity();
    for (const Kernel& k : kernels.wanders) {
      const detail::Trial t =
          detail::best_amplitude(k, p, kernels.typical_count, Likelihood::kRestricted);
      const double score = t.log_likelihood - penalty_per_parameter * k.parameters;
      const WanderModel w = detail::with_amplitude(k, t.amplitude);
      if (w.kind == WanderKind::kFlicker && score > flicker_score) {
        flicker_score = score;
        flicker_fit = w;
      }
      if (score > best_score) {
        best_score = score;
        best = w;
      }
    }
    // A run of tens of steps tells the fast part of a wander far better than its slow part,
    // which only a few plateaus hours apart carry. Where flicker explains the data nearly as
    // well as the best wander, take it: it keeps the slow wander that a fast Gauss-Markov fit
    // would deny, so that a slowly varying effect (a temperature polynomial's next order) is
    // not claimed from bias wander between plateaus.
    if (options.prefer_flicker && best.kind != WanderKind::kNone &&
        best.kind != WanderKind::kFlicker && flicker_score >= best_score - kCautiousFlickerMargin) {
      best = flicker_fit;
      best_score = flicker_score;
    }
    const detail::Trial excess = detail::best_amplitude(
        kernels.independent, p, kernels.typical_count, Likelihood::kRestricted);
    const double excess_score = excess.log_likelihood - penalty_per_parameter;
    ch.source = fmt::format("restricted likelihood of {} step means ({} parameters act on {})",
                            steps.size(), p.parameters, channel_name(c));
    if (best.kind != WanderKind::kNone && excess_score - best_score > kNotWanderMargin) {
      ch.determined = false;
      ch.note = fmt::format(
          "the step means scatter {:.2g} times more than the white noise inside the steps, but "
          "neighbouring steps do not share the excess as a wandering bias would: an effect the "
          "model lacks, not noise; weights from the scatter inside the steps",
          std::sqrt(1.0 + excess.amplitude / (p.white / kernels.typical_count)));
      without_wander(c);
      continue;
    }
    if (best.kind == WanderKind::kNone) without_wander(c);
    ch.determined = true;
    ch.wander = best;
    ch.log_likelihood_gain = best_score - white_ll;
    ch.note = describe(best, c);
  }
  return noise;
}

StepNoise estimate_run_noise(const RunData& data, const Model& model, SensorRows rows,
                             const NoiseEstimateOptions& options) {
  const Model superset = noise_superset(model);
  const std::vector<StepSummary> steps = summarize_steps(data, superset);
  return estimate_step_noise(summarize_noise_rows(data, superset, steps), superset, rows, options);
}

FitResult fit_run(const RunData& data, const Model& model, const FitOptions& options,
                  const NoiseEstimateOptions& noise_options,
                  std::vector<StepSummary>* model_steps) {
  const Model superset = noise_superset(model);
  const std::vector<StepSummary> all = summarize_steps(data, superset);
  const StepNoise noise = estimate_step_noise(summarize_noise_rows(data, superset, all), superset,
                                              options.rows, noise_options);
  const std::vector<StepSummary> steps =
      model.earth_rate() ? select_parameters(all, superset, model) : summarize_steps(data, model);
  FitResult fit = fit_model(steps, model, noise, options);
  if (model_steps) *model_steps = steps;
  return fit;
}

}  // namespace calstand::solver
