#pragma once
// Custom terms for a residual the catalogue does not explain: built from the signals of
// error-model.md, tried, and kept only when they help.
//
// The forms. For each sensor, every signal s, its square, its absolute value and the product of
// every pair of signals on one parameter per axis (`gyro:force_z^2`); the same with each axis on
// its own axis's signal (`gyro:force_{axis}^2`, `gyro:rate_{axis}*force_{axis}`,
// `gyro:temperature*force_{axis}`); and a warm-up transient `exp(-elapsed/tau)` with tau searched
// on a log grid, then refined. Each form acts on the subset of the sensor's axes that earns its
// parameters (`gyro.z:force_z^2` when only gz follows force_z^2).
//
// Screening. Hundreds of forms through muParser over every sample would take seconds, so the
// step means of every building block are computed natively in one pass over the samples, and
// each form is judged by the chi-square it would remove from the model's fit, with the fit's own
// whitening (the noise model of the diagnosis): its whitened step-mean column projected out of
// the model's columns, against the whitened residual. A form whose column lies in the span of
// the catalogue terms is that catalogue effect in disguise and is left out.
//
// Screening ranks the forms twice, with the diagnosis's noise model and with white noise alone:
// the wander fitted without the term may have swallowed the effect (effect_or_wander.hpp), and
// a form screened only against those weights would look weak.
//
// The guards. The best few of both rankings are judged against the wander on the same footing
// (effect_or_wander.hpp: BIC on the profile likelihood, the wander re-estimated with the term
// and without it, on the noise rows where a long static capture enters by its segments) and
// must lower BIC by "very strong" evidence (10) more than the best catalogue candidate does,
// judged the same way (a tie goes to the catalogue: in a thermal campaign `elapsed` follows the
// plateaus as a temperature term does), and by more than very strong evidence plus the
// look-elsewhere cost of the search (2 ln of the forms tried); a warm-up exp(-elapsed/tau) that
// settles within the run (tau up to a third of its span), the one form stated before the search,
// does not (suggest.cpp says why its bar is not lower still, and why a slower decay is not one).
// Each sensor's warm-up is reported with its figures whether kept or not (WarmUpCheck). Then
// they must hold on data they
// were not fitted on, judged against the noise that remains with the term: leave one
// temperature plateau out when the run has three or more (a transient in elapsed time
// extrapolates in time, not temperature: five folds of interleaved steps for it, as for a run
// with fewer plateaus); the held-out chi-square must fall by more than the parameters the term
// adds. The survivors' figures are those of fit_run with the term, the path `calstand fit
// --custom` takes (its noise model re-estimated with the term).

#include <array>
#include <limits>
#include <string>
#include <vector>

#include "solver/effect_or_wander.hpp"
#include "solver/fit.hpp"
#include "solver/model.hpp"
#include "solver/noise_estimate.hpp"
#include "solver/noise_rows.hpp"
#include "solver/step_summary.hpp"

namespace calstand::solver {

/// A custom term that explains (part of) the residual.
struct Suggestion {
  std::string custom;  ///< NAME=SENSOR[.AXES]:EXPRESSION, as `calstand fit --custom` takes it
  /// chi2/dof of fit_run with the term: what `calstand fit --custom` reports.
  double chi2_dof_after = 0.0;
  /// BIC with the term - without (effect_or_wander.hpp: profile likelihood, the wander
  /// re-estimated under each); negative is better.
  double delta_bic = 0.0;
  double p_value = 1.0;  ///< F-test of the added parameters, with the diagnosis's noise model
  int added_parameters = 0;
  std::string held_out;                   ///< how: "3 temperature plateaus", "5 folds of steps"
  double held_out_chi2_dof_before = 0.0;  ///< of the model, predicting each held-out part
  double held_out_chi2_dof_after = 0.0;   ///< ... with the term
  std::string effect;                     ///< in words, with the fitted coefficients
  std::string explanation;  ///< the effect and which steps it fixes (filled by diagnose)
  FitResult fit;            ///< fit_run with the term
  /// With the wander known: the best catalogue term's delta_bic against it with this term
  /// present (+infinity when none lowers BIC then); otherwise NaN (the catalogue's own figure
  /// stands).
  double catalogue_delta_bic_given = std::numeric_limits<double>::quiet_NaN();
};

/// The warm-up transient of one sensor as the search judged it, kept or not: a lab asking "is
/// there a warm-up?" gets the figures either way.
struct WarmUpCheck {
  std::string custom;  ///< the term, NAME=SENSOR[.AXES]:exp(-elapsed/TAU)
  double tau_s = 0.0;
  /// 2 ln of the likelihood ratio, term against the wander, each wander re-estimated under its
  /// design (profile likelihood); NaN when the screening already rejected the form.
  double two_log_likelihood_ratio = 0.0;
  /// The wanders' parameters' cost with the term less without (usually 0 or negative: the term
  /// may leave a simpler wander).
  double noise_penalty_change = 0.0;
  double delta_bic = 0.0;  ///< against the wander (NaN when not reached)
  double bar = 0.0;        ///< the delta_bic asked of a warm-up
  bool held_out_better = false;
  bool kept = false;    ///< among the suggestions
  std::string verdict;  ///< in words: why it was kept or not
  /// Passed the bar against the wander (false when the screening rejected it: delta_bic NaN).
  bool beats_wander() const { return delta_bic < bar; }
};

/// The outcome of the search.
struct SuggestionSearch {
  bool ran = false;
  int forms_tried = 0;                  ///< candidate forms screened (sensor x expression)
  std::vector<Suggestion> suggestions;  ///< best (most negative delta_bic) first
  std::vector<WarmUpCheck> warm_ups;    ///< the best warm-up checked per sensor
  std::string summary;                  ///< one sentence: what was tried and what held
};

struct SuggestOptions {
  /// Confirmed through fit_run and reported: each costs a pass over the samples with the noise
  /// superset, as much as the diagnosis itself, so the best and the runner-up.
  std::size_t max_suggestions = 2;
  std::size_t max_checked = 8;  ///< refitted exactly and cross-validated
};

/// What the search needs from the diagnosis: the model's step summaries and fit (whose noise
/// model weights everything), and the catalogue's span.
struct SuggestInput {
  const RunData* data = nullptr;
  const Model* model = nullptr;
  const std::vector<StepSummary>* steps = nullptr;  ///< summaries for `model`
  const FitResult* fit = nullptr;                   ///< of `model` on `steps`
  /// `model` with every catalogue term that could be added (same earth_rate as `model`), and
  /// summaries for it: a form inside its span is a catalogue effect.
  const Model* catalogue = nullptr;
  const std::vector<StepSummary>* catalogue_steps = nullptr;
  /// delta_bic of the best catalogue candidate (+infinity when there is none), on the same
  /// footing as the suggestions' (effect_or_wander.hpp).
  double best_catalogue_delta_bic = 0.0;
  /// With the wander known (evidence->wander_known()): the parameters of each catalogue term
  /// that lowered BIC against it, so that a warm-up is weighed against what each adds once the
  /// warm-up is there, not against what it adds alone (a temperature order takes a warm-up's
  /// plateau offset when nothing else can).
  std::vector<std::vector<std::string>> catalogue_terms;
  /// The term against the wander on the noise rows (summaries for `catalogue`), where each row
  /// came from, and the long captures' segments (the rows that are not whole steps).
  const EffectOrWander* evidence = nullptr;
  const std::vector<NoiseRowSource>* evidence_sources = nullptr;
  const CaptureSegments* segments = nullptr;
  /// How each suggestion's own fit (fit_run) has its noise model: the diagnosis's way.
  const NoiseEstimateOptions* noise_options = nullptr;
};

/// Searches the custom terms that explain the residual of `in.fit`. Nothing is suggested when no
/// form passes the guards (see above). `options.rows` limits the sensors tried.
SuggestionSearch suggest_custom_terms(const SuggestInput& in, const FitOptions& options = {},
                                      const SuggestOptions& suggest = {});

}  // namespace calstand::solver
