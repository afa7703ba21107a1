#include "solver/diagnose.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <boost/math/distributions/fisher_f.hpp>
#include <cmath>
#include <limits>
#include <map>

#include "core/error.hpp"
#include "solver/effect_or_wander.hpp"
#include "solver/noise_estimate.hpp"
#include "solver/noise_rows.hpp"

namespace calstand::solver {
namespace {

constexpr std::size_t kSignalsReported = 20;
// A candidate that removes more than this share of the chi2/dof excess over 1 is a real effect
// even when others remain.
constexpr double kDominantShareOfExcess = 0.5;
// An F-test p-value below this is strong evidence for a term.
constexpr double kStrongP = 1e-6;
// "Very strong" evidence on the Kass-Raftery scale of BIC differences.
constexpr double kStrongDeltaBic = -10.0;

struct CandidateModel {
  std::string term;
  const core::ErrorTermInfo* info = nullptr;
  Model model;
};

/// Each catalogue term the model lacks, and the next order of its temperature polynomials.
std::vector<CandidateModel> candidate_models(const Model& model, SensorRows rows) {
  std::vector<CandidateModel> out;
  for (const auto& info : core::error_term_catalogue()) {
    // Terms of a sensor whose rows are not fitted, and the Earth rate without gyro rows, cannot
    // change the fit.
    if (rows == SensorRows::kAccel &&
        (info.sensor == core::TermSensor::kGyro || info.name == "earth_rate"))
      continue;
    if (rows == SensorRows::kGyro && info.sensor == core::TermSensor::kAccel) continue;
    const ModelTerm* present = model.find(info.name);
    if (present && !info.polynomial_order) continue;
    const int order = present ? present->order + 1 : 1;
    Model m = model.with_term(info, order);
    out.push_back({m.terms()[present ? static_cast<std::size_t>(present - model.terms().data())
                                     : m.terms().size() - 1]
                       .name,
                   &info, std::move(m)});
  }
  return out;
}

double squared_z(const FitResult& fit, const StepResidual& s) {
  const Vector6d z = s.z();
  double sum = 0.0;
  for (int c : fit_channels(fit.rows)) sum += z[c] * z[c];
  return sum;
}

/// "the steps at T 70 degC, +z up" for the groups whose chi-square the candidate lowers most.
std::string what_it_fixes(const FitResult& before, const std::vector<GroupQuality>& g_before,
                          const FitResult& after, const std::vector<StepSummary>& steps) {
  const auto g_after = group_quality(after, steps);
  std::map<std::string, double> after_chi2;
  for (const auto& g : g_after) after_chi2[g.group] = g.chi2_dof;
  std::vector<std::pair<double, std::string>> gains;
  for (const auto& g : g_before) {
    const double gain = (g.chi2_dof - after_chi2[g.group]) * static_cast<double>(g.steps.size());
    if (gain > 0.0) gains.emplace_back(gain, g.group);
  }
  std::sort(gains.begin(), gains.end(), std::greater<>());
  // Steps it fixes: those whose squared z-score falls the most.
  std::vector<std::pair<double, std::string>> step_gains;
  for (std::size_t k = 0; k < before.steps.size() && k < after.steps.size(); ++k) {
    step_gains.emplace_back(squared_z(before, before.steps[k]) - squared_z(after, after.steps[k]),
                            before.steps[k].label.empty()
                                ? fmt::format("step {}", before.steps[k].index)
                                : before.steps[k].label);
  }
  std::sort(step_gains.begin(), step_gains.end(), std::greater<>());
  std::vector<std::string> words;
  for (std::size_t i = 0; i < gains.size() && i < 2; ++i) words.push_back(gains[i].second);
  std::vector<std::string> named;
  for (std::size_t i = 0; i < step_gains.size() && i < 3 && step_gains[i].first > 0.0; ++i) {
    named.push_back(step_gains[i].second);
  }
  if (words.empty() && named.empty()) return "it fixes no step noticeably";
  if (words.empty()) return fmt::format("fixes most at {}", fmt::join(named, ", "));
  return fmt::format("fixes most where {}{}", fmt::join(words, " and "),
                     named.empty() ? "" : fmt::format(" (e.g. {})", fmt::join(named, ", ")));
}

double pearson(const std::vector<double>& a, const std::vector<double>& b) {
  const double n = static_cast<double>(a.size());
  double ma = 0.0, mb = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    ma += a[i];
    mb += b[i];
  }
  ma /= n;
  mb /= n;
  double sab = 0.0, saa = 0.0, sbb = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    sab += (a[i] - ma) * (b[i] - mb);
    saa += (a[i] - ma) * (a[i] - ma);
    sbb += (b[i] - mb) * (b[i] - mb);
  }
  // A signal constant over the run (to rounding) correlates with nothing.
  if (saa <= 1e-20 * (ma * ma + 1.0) * n || sbb <= 0.0) return 0.0;
  return sab / std::sqrt(saa * sbb);
}

std::vector<SignalCorrelation> correlate_signals(const FitResult& fit,
                                                 const std::vector<StepSummary>& steps) {
  std::vector<SignalCorrelation> out;
  for (int c : fit_channels(fit.rows)) {
    std::vector<double> z;
    for (const auto& s : fit.steps) z.push_back(s.z()[c]);
    for (std::size_t k = 0; k < kSignalCount; ++k) {
      const std::string name(signal_names()[k]);
      const std::pair<std::string, std::array<double, kSignalCount> StepSummary::*> forms[] = {
          {name, &StepSummary::signals},
          {name + "^2", &StepSummary::signals_sq},
          {"abs(" + name + ")", &StepSummary::signals_abs}};
      for (const auto& [label, member] : forms) {
        std::vector<double> x;
        for (const auto& s : steps) x.push_back((s.*member)[k]);
        const double r = pearson(x, z);
        if (r != 0.0) out.push_back({label, std::string(channel_name(c)), r});
      }
    }
  }
  std::stable_sort(out.begin(), out.end(), [](const auto& a, const auto& b) {
    return std::abs(a.correlation) > std::abs(b.correlation);
  });
  if (out.size() > kSignalsReported) out.resize(kSignalsReported);
  return out;
}

/// The fitted channels whose noise model has a wandering bias weighing at least as much as the
/// white noise in a typical step mean. The noise model removes only catalogue effects before it
/// looks for a wander, so an effect the catalogue lacks, shared by neighbouring steps, can pose
/// as one; there the model "fits the noise floor" without explaining anything.
std::vector<std::string> wander_outweighing_white(const FitResult& fit,
                                                  const std::vector<StepSummary>& steps) {
  std::vector<std::string> out;
  for (int c : fit_channels(fit.rows)) {
    const ChannelStepNoise& ch = fit.noise.channels[static_cast<std::size_t>(c)];
    if (!ch.determined || ch.wander.kind == WanderKind::kNone) continue;
    double wander = 0.0, white = 0.0;
    for (const StepSummary& s : steps) {
      wander += ch.wander.interval_mean_covariance(s.start_s, s.end_s, s.start_s, s.end_s);
      white += fit.noise.white.density[c] / static_cast<double>(s.count);
    }
    if (wander >= white) out.emplace_back(channel_name(c));
  }
  return out;
}

}  // namespace

bool best_candidate_dominates(const FitResult& fit, const Candidate& best) {
  if (best.p_value >= kStrongP) return false;
  const auto removes_most = [](double before, double after) {
    return before > 1.0 && std::isfinite(after) &&
           before - after > kDominantShareOfExcess * (before - 1.0);
  };
  if (removes_most(fit.chi2_dof, best.chi2_dof_after)) return true;
  if (!std::isfinite(fit.chi2_dof_gyro) || !std::isfinite(fit.chi2_dof_accel)) return false;
  return fit.chi2_dof_gyro >= fit.chi2_dof_accel
             ? removes_most(fit.chi2_dof_gyro, best.chi2_dof_after_gyro)
             : removes_most(fit.chi2_dof_accel, best.chi2_dof_after_accel);
}

Diagnosis diagnose(const RunData& data, const Model& model, const FitOptions& options,
                   const DiagnoseOptions& diagnose_options) {
  std::vector<CandidateModel> candidates = candidate_models(model, options.rows);
  // One pass over the samples for the model and every candidate that keeps its reference: the
  // noise model's superset (every catalogue term, see noise_superset()) when the model has the
  // Earth rate, so that the same pass serves the noise model; the Earth rate changes the
  // reference, so without it the noise model and that candidate get their own passes.
  Model superset = model;
  if (model.earth_rate()) {
    superset = noise_superset(model);
  } else {
    for (const auto& c : candidates) {
      if (c.info->name == "earth_rate") continue;
      const ModelTerm* t = c.model.find(c.info->name);
      superset = superset.with_term(*c.info, t ? t->order : 1);
    }
  }
  const std::vector<StepSummary> all = summarize_steps(data, superset);
  // The noise rows: the steps, with a long static capture by its segments (noise_rows.hpp),
  // summarised for the noise superset (which `superset` is when the model has the Earth rate).
  const Model noise_model_terms = model.earth_rate() ? superset : noise_superset(model);
  const std::vector<StepSummary> noise_steps =
      model.earth_rate() ? all : summarize_steps(data, noise_model_terms);
  const CaptureSegments segments = segment_long_captures(data, noise_steps);
  std::vector<NoiseRowSource> sources;
  std::vector<StepSummary> rows =
      noise_rows(noise_steps, segments,
                 segments.empty() ? std::vector<StepSummary>{}
                                  : summarize_steps(segments.segments, noise_model_terms),
                 &sources);
  const NoiseEstimateOptions& noise_options = diagnose_options.noise;
  const StepNoise noise = estimate_step_noise(rows, noise_model_terms, options.rows, noise_options);
  const EffectOrWander evidence(
      std::move(rows), noise_model_terms, options.rows,
      noise_options.known_wander ? &*noise_options.known_wander : nullptr);
  const std::vector<StepSummary> steps = select_parameters(all, superset, model);

  Diagnosis d;
  d.fit = fit_model(steps, model, noise, options);
  d.groups = group_quality(d.fit, steps);
  d.signals = correlate_signals(d.fit, steps);
  const double n_rows = static_cast<double>(d.fit.dof + static_cast<int>(d.fit.parameters.size()));
  // The parameters of each catalogue term that lowers BIC against the wander.
  std::vector<std::vector<std::string>> catalogue_terms;
  for (const auto& c : candidates) {
    const std::vector<StepSummary> cs = c.info->name == "earth_rate"
                                            ? summarize_steps(data, c.model)
                                            : select_parameters(all, superset, c.model);
    FitResult after;
    try {
      after = fit_model(cs, c.model, noise, options);
    } catch (const core::InputError&) {
      d.untestable.push_back(c.term);  // more parameters than the run has rows
      continue;
    }
    const int added =
        static_cast<int>(after.parameters.size()) - static_cast<int>(d.fit.parameters.size());
    if (added <= 0 && c.info->name != "earth_rate") {
      d.untestable.push_back(c.term);
      continue;
    }
    Candidate k;
    k.term = c.term;
    k.added_parameters = added;
    k.chi2_dof_after = after.chi2_dof;
    k.chi2_dof_after_gyro = after.chi2_dof_gyro;
    k.chi2_dof_after_accel = after.chi2_dof_accel;
    k.delta_bic = after.chi2 - d.fit.chi2 + static_cast<double>(added) * std::log(n_rows);
    // Against the wander only where the term helps with the noise model's weights: against a
    // wander re-estimated without it, it helps less (the wander takes what it can).
    if (c.info->name != "earth_rate" && k.delta_bic < 0.0) {
      std::vector<std::string> added_names;
      for (const ParameterInfo& p : c.model.parameters()) {
        const auto& had = model.parameters();
        if (std::none_of(had.begin(), had.end(),
                         [&](const ParameterInfo& q) { return q.name == p.name; })) {
          added_names.push_back(p.name);
        }
      }
      // A temperature order k: without it means without every order from k up, which the noise
      // superset also holds (with three plateaus, orders 2 and 3 would fit the offsets of order
      // 1 as well).
      if (c.info->polynomial_order) {
        const int order = c.model.find(c.info->name)->order;
        const std::string prefix = std::string(c.info->name) + ".";
        for (const ParameterInfo& p : evidence.superset().parameters()) {
          if (p.name.rfind(prefix, 0) == 0 && p.name.back() - '0' > order) {
            added_names.push_back(p.name);
          }
        }
      }
      const std::array<bool, kChannels> acting = evidence.channels_of(added_names);
      if (std::find(acting.begin(), acting.end(), true) != acting.end()) {
        k.delta_bic_against_wander =
            delta_bic(evidence.base(acting), evidence.without(added_names));
        if (k.delta_bic_against_wander < 0.0) catalogue_terms.push_back(added_names);
      }
    }
    if (added > 0 && after.dof > 0 && after.chi2 > 0.0) {
      const double F = ((d.fit.chi2 - after.chi2) / added) / (after.chi2 / after.dof);
      const boost::math::fisher_f_distribution<double> dist(added, after.dof);
      k.p_value = F > 0.0 ? boost::math::cdf(boost::math::complement(dist, F)) : 1.0;
    }
    k.explanation =
        fmt::format("{}: {}", c.info->effect, what_it_fixes(d.fit, d.groups, after, steps));
    d.candidates.push_back(std::move(k));
  }
  std::stable_sort(
      d.candidates.begin(), d.candidates.end(),
      [](const Candidate& a, const Candidate& b) { return a.delta_bic < b.delta_bic; });

  const bool model_fits = d.fit.chi2_dof <= kExplainedChi2Dof;
  const bool best_fits =
      !d.candidates.empty() && d.candidates.front().chi2_dof_after <= kExplainedChi2Dof;
  // Several effects missing at once: the best candidate removes most of the excess over the
  // noise but not all. It explains what it removes; the user adds it and diagnoses again. Most
  // of the whole excess, or most of the worst sensor's: a gyro term cannot touch the
  // accelerometers' misfit, and where both sensors miss an effect (the demo's temperature drift
  // of both biases: gyro 3.2, accel 2.3) the gyro term that takes the gyros to their floor is
  // the first of two, not "nothing explains it".
  const bool best_dominates =
      !d.candidates.empty() && best_candidate_dominates(d.fit, d.candidates.front());
  d.explained = model_fits || best_fits || best_dominates;
  // Strong evidence (BIC lower by more than 10, F-test p under 1e-6) recommends a term even when
  // the model is already near the floor: with hundreds of rows, chi2/dof 1.2 is still a signal.
  // A catalogue term is judged against the noise model of the richest catalogue model, not
  // against a wander re-estimated without it: with a few plateaus hours apart, a slow wander
  // re-estimated freely explains plateau offsets nearly as well as a temperature term (MEMS
  // class: +3 to +16 against the wander for a 1 deg/h/degC bias the fixed weights find at -150),
  // and the catalogue's physics is the prior a lab holds. delta_bic_against_wander says how far
  // the run alone tells the two apart.
  const bool strong = !d.candidates.empty() && d.candidates.front().delta_bic < kStrongDeltaBic &&
                      d.candidates.front().p_value < kStrongP;
  if (strong && (!model_fits || d.candidates.front().chi2_dof_after < d.fit.chi2_dof)) {
    d.recommended = d.candidates.front().term;
  }
  std::vector<std::string> wandering = wander_outweighing_white(d.fit, steps);
  if (wandering.empty()) {
    for (int c : fit_channels(d.fit.rows)) {
      if (noise.channels[static_cast<std::size_t>(c)].wander.kind != WanderKind::kNone) {
        wandering.emplace_back(channel_name(c));
      }
    }
  }
  // A wander may hold an effect the catalogue lacks (effect_or_wander.hpp): wherever the noise
  // model has one, the search runs and judges its forms against it. With the wander known (a
  // static run's), the search always runs: a chi2/dof near 1 is no screen for a warm-up of a few
  // step means' noise over the first ten steps of hundreds, which the likelihood ratio sees (on
  // white-noise units none of 24 such warm-ups was searched for when the static run showed no
  // wander).
  const bool search =
      diagnose_options.custom_search == CustomSearch::kAlways ||
      (diagnose_options.custom_search == CustomSearch::kWhenUnexplained &&
       (!d.explained || noise.correlated() || noise_options.known_wander.has_value()));
  if (search) {
    SuggestInput in;
    in.data = &data;
    in.model = &model;
    in.steps = &steps;
    in.fit = &d.fit;
    in.catalogue = &superset;
    in.catalogue_steps = &all;
    // The catalogue's best on the same footing as the suggestions: against the wander.
    in.best_catalogue_delta_bic = std::numeric_limits<double>::infinity();
    for (const Candidate& c : d.candidates) {
      if (std::isfinite(c.delta_bic_against_wander)) {
        in.best_catalogue_delta_bic =
            std::min(in.best_catalogue_delta_bic, c.delta_bic_against_wander);
      }
    }
    if (evidence.wander_known()) in.catalogue_terms = catalogue_terms;
    in.evidence = &evidence;
    in.evidence_sources = &sources;
    in.segments = &segments;
    in.noise_options = &noise_options;
    SuggestionSearch found = suggest_custom_terms(in, options, diagnose_options.suggest);
    d.custom_searched = found.ran;
    d.custom_forms_tried = found.forms_tried;
    d.custom_summary = found.summary;
    d.warm_ups = std::move(found.warm_ups);
    d.suggestions = std::move(found.suggestions);
    for (Suggestion& s : d.suggestions) {
      s.explanation = fmt::format("{}; {}", s.effect, what_it_fixes(d.fit, d.groups, s.fit, steps));
    }
  }
  // A suggestion beat every catalogue term and held out of sample: the catalogue does not
  // explain the residual, even where it reached the noise floor with a wander (which the custom
  // term then explains better: not noise, an effect). A catalogue term it beats by very strong
  // evidence is not worth adding first.
  const bool noise_posed = !d.suggestions.empty() && d.explained;
  if (!d.suggestions.empty()) {
    d.explained = false;
    const double catalogue_best = d.candidates.empty() ? std::numeric_limits<double>::infinity()
                                  : std::isfinite(d.candidates.front().delta_bic_against_wander)
                                      ? d.candidates.front().delta_bic_against_wander
                                      : d.candidates.front().delta_bic;
    // With the wander known, the catalogue's best is what it adds once the suggestion is there.
    const double given = d.suggestions.front().catalogue_delta_bic_given;
    if (!d.recommended.empty() &&
        d.suggestions.front().delta_bic <
            (std::isnan(given) ? catalogue_best : given) + kStrongDeltaBic) {
      d.recommended.clear();
    }
  }
  if (noise_posed) {
    const Suggestion& top = d.suggestions.front();
    d.advice = fmt::format(
        "the model reaches chi2/dof {:.2f} only with the wandering bias the noise model gives {}; "
        "a custom term built from the signals explains that residual better than any catalogue "
        "term{}: --custom '{}' (chi2/dof {:.2f} with its own noise model, BIC {:+.0f}; held out, "
        "chi2/dof {:.2f} to {:.2f} with {}).{}",
        d.fit.chi2_dof, fmt::join(wandering, ", "),
        d.candidates.empty()
            ? std::string()
            : fmt::format(" (the best, {}, BIC {:+.0f})", d.candidates.front().term,
                          d.candidates.front().delta_bic),
        top.custom, top.chi2_dof_after, top.delta_bic, top.held_out_chi2_dof_before,
        top.held_out_chi2_dof_after, top.held_out,
        d.recommended.empty() ? "" : fmt::format(" {} does nearly as well.", d.recommended));
  } else if (model_fits && strong) {
    d.advice = fmt::format(
        "the model is near the noise floor (chi2/dof {:.2f}), but adding {} is "
        "strongly supported (BIC {:+.0f}, chi2/dof to {:.2f})",
        d.fit.chi2_dof, d.candidates.front().term, d.candidates.front().delta_bic,
        d.candidates.front().chi2_dof_after);
  } else if (model_fits) {
    d.advice = fmt::format(
        "the model fits to the noise floor (chi2/dof {:.2f}); nothing is missing", d.fit.chi2_dof);
  } else if (best_fits) {
    d.advice =
        fmt::format("add {}: chi2/dof falls from {:.2f} to {:.2f}", d.candidates.front().term,
                    d.fit.chi2_dof, d.candidates.front().chi2_dof_after);
  } else if (best_dominates) {
    d.advice = fmt::format(
        "add {}: chi2/dof falls from {:.2f} to {:.2f}; more than one effect is "
        "missing, so diagnose again with it in the model",
        d.candidates.front().term, d.fit.chi2_dof, d.candidates.front().chi2_dof_after);
  } else {
    std::string follows;
    for (std::size_t i = 0; i < d.signals.size() && i < 3; ++i) {
      follows += fmt::format("{}{} ({}, r = {:.2f})", i ? ", " : "", d.signals[i].signal,
                             d.signals[i].channel, d.signals[i].correlation);
    }
    const std::string best =
        d.candidates.empty()
            ? std::string("no candidate could be tested")
            : fmt::format("even the best candidate, {}, leaves chi2/dof {:.2f}",
                          d.candidates.front().term, d.candidates.front().chi2_dof_after);
    d.advice = fmt::format("no catalogue term explains the residual: {}. The residual follows {}.",
                           best, follows.empty() ? "no signal" : follows);
    if (!d.suggestions.empty()) {
      const Suggestion& top = d.suggestions.front();
      const bool all_of_it = top.chi2_dof_after <= kExplainedChi2Dof;
      d.advice += fmt::format(
          " A custom term built from the signals {}: --custom '{}' (chi2/dof {:.2f} to {:.2f}, "
          "BIC {:+.0f}; held out, chi2/dof {:.2f} to {:.2f} with {}).{}",
          all_of_it ? "explains it" : "explains part of it", top.custom, d.fit.chi2_dof,
          top.chi2_dof_after, top.delta_bic, top.held_out_chi2_dof_before,
          top.held_out_chi2_dof_after, top.held_out,
          all_of_it ? "" : " Add it and diagnose again: more than one effect is missing.");
    } else if (d.custom_searched) {
      d.advice += " Nothing simple explains it: " + d.custom_summary + ".";
    } else if (!d.signals.empty()) {
      const auto& top = d.signals.front();
      const char* sensor = top.channel[0] == 'g' ? "gyro" : "accel";
      d.advice +=
          fmt::format(" Try a custom term built on it, e.g. --custom k1={}:{}", sensor, top.signal);
    }
    // A short run (a six-position test's six step means) cannot measure the unit's wandering
    // bias: its misfit is then judged against the white noise alone, and a flicker floor reads
    // as a missing effect. Said, with the way to tell them apart.
    std::vector<std::string> unmeasured;
    for (int c : fit_channels(d.fit.rows)) {
      if (noise.channels[static_cast<std::size_t>(c)].too_few_steps) {
        unmeasured.emplace_back(channel_name(c));
      }
    }
    if (!unmeasured.empty()) {
      d.advice += fmt::format(
          " This run could not measure the unit's wandering bias on {} (see the noise model): "
          "the residual may be that wander, not an effect. A static run of the unit (hours at "
          "rest) given as --noise-run tells the two apart.",
          fmt::join(unmeasured, ", "));
    }
  }
  return d;
}

nlohmann::json diagnosis_to_json(const Diagnosis& d) {
  nlohmann::json j;
  j["model"] = d.fit.terms;
  j["chi2_dof"] = d.fit.chi2_dof;
  j["residual_rms"] = {{"gyro", d.fit.residual_rms_gyro_dps},
                       {"accel", d.fit.residual_rms_accel_mps2}};
  j["candidates"] = nlohmann::json::array();
  for (const auto& c : d.candidates) {
    j["candidates"].push_back(
        {{"term", c.term},
         {"delta_bic", c.delta_bic},
         {"delta_bic_against_wander", std::isfinite(c.delta_bic_against_wander)
                                          ? nlohmann::json(c.delta_bic_against_wander)
                                          : nlohmann::json(nullptr)},
         {"p_value", c.p_value},
         {"chi2_dof_after", c.chi2_dof_after},
         {"added_parameters", c.added_parameters},
         {"explanation", c.explanation}});
  }
  j["untestable"] = d.untestable;
  j["signals"] = nlohmann::json::array();
  for (const auto& s : d.signals) {
    j["signals"].push_back(
        {{"signal", s.signal}, {"channel", s.channel}, {"correlation", s.correlation}});
  }
  j["suggestions"] = nlohmann::json::array();
  for (const auto& s : d.suggestions) {
    j["suggestions"].push_back({{"custom", s.custom},
                                {"chi2_dof_after", s.chi2_dof_after},
                                {"delta_bic", s.delta_bic},
                                {"p_value", s.p_value},
                                {"added_parameters", s.added_parameters},
                                {"held_out",
                                 {{"method", s.held_out},
                                  {"chi2_dof_before", s.held_out_chi2_dof_before},
                                  {"chi2_dof_after", s.held_out_chi2_dof_after}}},
                                {"explanation", s.explanation}});
  }
  nlohmann::json warm_ups = nlohmann::json::array();
  const auto number = [](double v) {
    return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
  };
  for (const WarmUpCheck& w : d.warm_ups) {
    warm_ups.push_back({{"custom", w.custom},
                        {"tau_s", w.tau_s},
                        {"two_log_likelihood_ratio", number(w.two_log_likelihood_ratio)},
                        {"noise_penalty_change", w.noise_penalty_change},
                        {"delta_bic", number(w.delta_bic)},
                        {"bar", w.bar},
                        {"beats_wander", w.beats_wander()},
                        {"held_out_better", w.held_out_better},
                        {"kept", w.kept},
                        {"verdict", w.verdict}});
  }
  j["custom_search"] = {{"ran", d.custom_searched},
                        {"forms_tried", d.custom_forms_tried},
                        {"summary", d.custom_summary},
                        {"warm_ups", warm_ups}};
  j["explained"] = d.explained;
  j["advice"] = d.advice;
  j["recommended"] = d.recommended;
  nlohmann::json groups = nlohmann::json::object();
  add_groups_json(groups, d.groups, worst_steps(d.fit));
  j["groups"] = groups["groups"];
  j["worst_steps"] = groups["worst_steps"];
  return j;
}

}  // namespace calstand::solver
