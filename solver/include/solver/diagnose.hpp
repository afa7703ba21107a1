#pragma once

#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "solver/fit.hpp"
#include "solver/groups.hpp"
#include "solver/suggest.hpp"

namespace calstand::solver {

/// One catalogue term tried on top of the model.
struct Candidate {
  std::string term;        ///< e.g. "gyro_g_sensitivity", "gyro_temp_bias:2"
  double delta_bic = 0.0;  ///< BIC after - before (chi2 + k ln n); negative is better
  /// BIC with the term - without, the wander re-estimated under each (effect_or_wander.hpp);
  /// NaN for the Earth rate (it changes the reference, not the design) and for a term that
  /// does not lower BIC with the noise model's weights (not computed: it cannot do better
  /// against a wander that may take what it explains).
  double delta_bic_against_wander = std::numeric_limits<double>::quiet_NaN();
  double p_value = 1.0;  ///< F-test of the added parameters
  double chi2_dof_after = 0.0;
  /// Per sensor after the term (FitResult's: NaN where the sensor is not fitted).
  double chi2_dof_after_gyro = std::numeric_limits<double>::quiet_NaN();
  double chi2_dof_after_accel = std::numeric_limits<double>::quiet_NaN();
  int added_parameters = 0;  ///< identified parameters the term adds
  std::string explanation;   ///< the physical effect and which steps it fixes, in words
};

/// How strongly a channel's step residuals (z-scores) follow a signal.
struct SignalCorrelation {
  std::string signal;        ///< "temperature_rate", "rate_x^2", "abs(force_z)"
  std::string channel;       ///< gx .. az
  double correlation = 0.0;  ///< Pearson, over steps
};

struct Diagnosis {
  FitResult fit;                           ///< the model as given
  std::vector<GroupQuality> groups;        ///< of `fit`, worst first
  std::vector<Candidate> candidates;       ///< best (most negative delta_bic) first
  std::vector<std::string> untestable;     ///< candidate terms the run cannot determine at all
  std::vector<SignalCorrelation> signals;  ///< strongest first
  bool explained = false;  ///< the model, or the model with the best candidate, fits the noise
  std::string advice;      ///< one paragraph for the user
  /// The term to add: the best candidate when the model is above the noise floor and that
  /// candidate explains (all or most of) the excess; empty otherwise.
  std::string recommended;
  /// Custom terms built from the signals that explain the residual, best first (see
  /// suggest.hpp); `explained` stays false with them: the catalogue does not have the effect.
  std::vector<Suggestion> suggestions;
  bool custom_searched = false;  ///< the search for custom terms ran
  int custom_forms_tried = 0;
  std::string custom_summary;         ///< one sentence: what was tried and what held
  std::vector<WarmUpCheck> warm_ups;  ///< the warm-up judged per sensor, kept or not
};

/// When diagnose searches custom terms built from the signals.
enum class CustomSearch {
  /// When no catalogue term explains the residual (`explained` false): a catalogue term, with
  /// its physical meaning and contract units, is always preferred, and when one explains (most
  /// of) the excess the user adds it and diagnoses again before anything custom is worth trying.
  kWhenUnexplained,
  kAlways,  ///< whatever the catalogue does (the guards still apply)
  kNever,
};

struct DiagnoseOptions {
  CustomSearch custom_search = CustomSearch::kWhenUnexplained;
  SuggestOptions suggest;
  /// How the noise model is had: estimated from the run, or its wander given (known_wander,
  /// a static run of the same unit), for the diagnosis, its candidates and its suggestions.
  NoiseEstimateOptions noise;
};

/// A fit with chi2/dof at or below this is at the noise floor (the residuals are explained).
inline constexpr double kExplainedChi2Dof = 1.5;

/// Whether the best candidate explains what it removes though other effects remain: an F-test
/// p under 1e-6, and more than half of the chi2/dof excess over 1 removed, of the whole fit or
/// of the sensor that misfits most (a gyro term cannot touch the accelerometers' misfit).
bool best_candidate_dominates(const FitResult& fit, const Candidate& best);

/// Fits `model`, then each catalogue term it lacks (and the next order of each temperature
/// polynomial it has) added in turn, ranked by the change in BIC; correlates the residuals with
/// every signal of error-model.md, their squares and absolute values. One pass over the samples
/// serves every candidate. Then, as `diagnose_options` asks, searches custom terms
/// (suggest_custom_terms()).
Diagnosis diagnose(const RunData& data, const Model& model, const FitOptions& options = {},
                   const DiagnoseOptions& diagnose_options = {});

/// The `calstand diagnose --json` document.
nlohmann::json diagnosis_to_json(const Diagnosis& d);

}  // namespace calstand::solver
